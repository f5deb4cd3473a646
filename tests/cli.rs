//! The `inlay` program end to end: headless demo output files and the clear,
//! non-panicking errors it gives for bad input.

mod common;

use std::path::PathBuf;
use std::process::{Command, Output};

use inlay_engine::HdrImage;

fn inlay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inlay"))
        .args(args)
        .output()
        .expect("the inlay binary runs")
}

fn text(o: &Output) -> String {
    common::output_text(o)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("inlay-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn headless_demo_writes_exr_and_png_and_prints_per_pass_timings() {
    let dir = scratch("demo");
    let exr = dir.join("d.exr");
    let png = dir.join("d.png");
    let o = inlay(&[
        "--validate",
        "demo",
        "--headless",
        "--width",
        "48",
        "--height",
        "32",
        "--frames",
        "3",
        "--out",
        exr.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    for pass in ["sky", "quads", "scene", "readback", "frame (gpu)"] {
        assert!(t.contains(pass), "timing table lacks {pass}: {t}");
    }
    assert!(t.contains("culled (nothing consumes them): heatmap"), "{t}");
    let img = HdrImage::load_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (48, 32));
    assert_eq!(img.non_finite_count(), 0);
    assert!(
        img.pixels.iter().any(|p| p[0] > 2.0),
        "the EXR keeps HDR values"
    );
    let png_bytes = std::fs::read(&png).unwrap();
    assert_eq!(&png_bytes[1..4], b"PNG");
}

#[test]
fn bad_arguments_fail_cleanly_with_named_causes() {
    let dir = scratch("bad");
    let bmp = dir.join("x.bmp");
    let o = inlay(&[
        "demo",
        "--headless",
        "--width",
        "8",
        "--height",
        "8",
        "--frames",
        "1",
        "--out",
        bmp.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("x.bmp") && text(&o).contains(".exr or .png"),
        "{}",
        text(&o)
    );

    let o = inlay(&["demo", "--headless", "--width", "0", "--height", "8"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("out of range"), "{}", text(&o));

    let missing = dir.join("no/such/dir/out.png");
    let o = inlay(&[
        "demo",
        "--headless",
        "--width",
        "8",
        "--height",
        "8",
        "--frames",
        "1",
        "--out",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("no/such/dir/out.png"), "{}", text(&o));

    let o = inlay(&["demo", "--headless", "--exposure", "NaN"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

#[test]
fn an_unknown_device_name_lists_the_devices() {
    let o = inlay(&[
        "--device",
        "no-such-gpu-xyz",
        "demo",
        "--headless",
        "--frames",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("no usable Vulkan device matches `no-such-gpu-xyz`"),
        "{t}"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_inlay"))
        .env("INLAY_DEVICE", "also-missing")
        .args(["demo", "--headless", "--frames", "1"])
        .output()
        .unwrap();
    assert!(text(&o).contains("`also-missing`"), "{}", text(&o));
}

#[test]
fn a_broken_shader_directory_is_reported_with_file_and_line() {
    let dir = scratch("shaders");
    let lib = inlay_passes::shaders::embedded_library();
    for path in lib.paths() {
        let source = lib.get(path).unwrap().to_string();
        let dest = dir.join(path);
        std::fs::create_dir_all(dest.parent().unwrap()).unwrap();
        let source = if path == "demo/quads.wgsl" {
            source.replace("let c = corners[v % 6u];", "let c = corners[v % 6u]\n")
        } else {
            source
        };
        std::fs::write(dest, source).unwrap();
    }
    let out = dir.join("o.png");
    let o = Command::new(env!("CARGO_BIN_EXE_inlay"))
        .env("INLAY_SHADER_DIR", &dir)
        .args([
            "demo",
            "--headless",
            "--frames",
            "1",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("demo/quads.wgsl:"), "{}", text(&o));
}

/// `inlay render-views` writes a training set that `inlay dataset` reads
/// back (EXR frames with depth maps, and bracketed PNGs); a broken dataset
/// is refused with every bad frame named.
/// `from` (a `transforms.json`) written to `to` with the first `count`
/// frames' poses in OpenCV's camera convention: each matrix's second and
/// third columns negated.
fn write_opencv_poses(from: &std::path::Path, to: &std::path::Path, count: usize) {
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(from).unwrap()).unwrap();
    for f in json["frames"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .take(count)
    {
        for row in f["transform_matrix"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .take(3)
        {
            for c in [1, 2] {
                row[c] = (-row[c].as_f64().unwrap()).into();
            }
        }
    }
    std::fs::write(to, json.to_string()).unwrap();
}

#[test]
fn render_views_writes_a_dataset_that_dataset_reads() {
    let dir = scratch("render-views");
    let out = dir.join("dog-views");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/dog.toml");
    let o = inlay(&[
        "render-views",
        scene,
        "--views",
        "3",
        "--size",
        "16x12",
        "--samples",
        "2",
        "--brackets=-1,1",
        "--depth",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains("saturate even"), "{}", text(&o));
    let o = inlay(&["dataset", out.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("depth maps: 3 of 3 frames"), "{t}");
    assert!(
        t.contains("instant-ngp dialect") && t.contains("frames: 3 usable"),
        "{t}"
    );
    assert!(t.contains("from the file's `aabb`"), "{t}");
    // The pixels past the field's bounds are transparent: their alpha is
    // the share of the pixel the field covers.
    assert!(
        t.contains("with alpha below 1") && !t.contains("; 0 with alpha below 1"),
        "{t}"
    );
    let o = inlay(&["dataset", out.join("brackets").to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success() && t.contains("frames: 6 usable"), "{t}");
    assert!(t.contains("exposure_time given for 6 frames"), "{t}");
    assert!(!t.contains("white in every bracket"), "{t}");
    // Brackets that do not hold the brightest pixels are called out where
    // they are written and where they are read.
    let short = dir.join("dog-ev1");
    let o = inlay(&[
        "render-views",
        scene,
        "--views",
        "1",
        "--size",
        "16x12",
        "--samples",
        "2",
        "--brackets=1",
        "--out",
        short.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("saturate even the shortest bracket (EV +1)")
            && t.contains("or below would record them"),
        "{t}"
    );
    let o = inlay(&["dataset", short.join("brackets").to_str().unwrap()]);
    let t = text(&o);
    assert!(
        o.status.success()
            && t.contains("of 1 of its 1 bracketed poses are white in every bracket"),
        "{t}"
    );
    // The same poses written in OpenCV's camera convention look away from
    // the field: training is refused before any work, naming the file, the
    // key and the convention, and no field is written.
    let opencv = out.join("opencv.json");
    write_opencv_poses(&out.join("transforms.json"), &opencv, 3);
    let refused = dir.join("opencv.inlayfield");
    let o = inlay(&[
        "train",
        opencv.to_str().unwrap(),
        "--out",
        refused.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success() && !refused.exists(), "{t}");
    assert!(
        t.contains(
            "opencv.json: frames: 3 of the 3 frames' cameras see none of the field's bounds"
        ) && t.contains("OpenCV's camera convention"),
        "{t}"
    );
    // Two of the three written so: refused, unless they may be left out,
    // and then training names them.
    let two = out.join("two-opencv.json");
    write_opencv_poses(&out.join("transforms.json"), &two, 2);
    let kept = dir.join("two.inlayfield");
    let args = [
        "train",
        two.to_str().unwrap(),
        "--out",
        kept.to_str().unwrap(),
        "--resolution",
        "8",
        "--stages",
        "1",
        "--iterations",
        "2",
        "--hold-out",
        "0",
    ];
    let o = inlay(&args);
    let t = text(&o);
    assert!(
        !o.status.success() && t.contains("--skip-bad-frames trains on those that see them"),
        "{t}"
    );
    let o = inlay(&[&args[..], &["--skip-bad-frames"]].concat());
    let t = text(&o);
    assert!(o.status.success() && kept.exists(), "{t}");
    assert!(
        t.contains("2 frames left out (--skip-bad-frames):")
            && t.contains("frames[1]: its camera sees none of the field's bounds"),
        "{t}"
    );

    // A prior that pulls every density down leaves nothing: an error, and
    // no empty field written as if trained.
    let empty = dir.join("empty.inlayfield");
    let o = inlay(&[
        "train",
        out.to_str().unwrap(),
        "--out",
        empty.to_str().unwrap(),
        "--resolution",
        "8",
        "--stages",
        "1",
        "--iterations",
        "20",
        "--sparsity",
        "1e3",
    ]);
    let t = text(&o);
    assert!(!o.status.success() && !empty.exists(), "{t}");
    assert!(
        t.contains("training left the field empty") && t.contains("--sparsity 1000"),
        "{t}"
    );

    // `inlay train` takes it: a tiny grid, a few steps, the field written
    // and readable by `render`.
    let field = dir.join("views.inlayfield");
    let depth_picture = dir.join("depth.exr");
    let spread_picture = dir.join("spread.exr");
    // A picture of held-out views with none held out is refused before
    // any work, naming the flag.
    let o = inlay(&[
        "train",
        out.to_str().unwrap(),
        "--out",
        field.to_str().unwrap(),
        "--hold-out",
        "0",
        "--scene",
        scene,
        "--depth-picture",
        depth_picture.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && text(&o).contains("--depth-picture: draws the held-out views"),
        "{}",
        text(&o)
    );
    assert!(!field.exists() && !depth_picture.exists());
    let o = inlay(&[
        "train",
        out.to_str().unwrap(),
        "--out",
        field.to_str().unwrap(),
        "--resolution",
        "8",
        "--stages",
        "2",
        "--iterations",
        "20",
        "--batch",
        "256",
        "--hold-out",
        "1",
        "--scene",
        scene,
        "--sky",
        "4",
        "--depth-picture",
        depth_picture.to_str().unwrap(),
        "--spread-picture",
        spread_picture.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("held-out frame 1: PSNR") && field.is_file(),
        "{t}"
    );
    // The held-out view's depth error drawn pixel by pixel, at its size,
    // something of the recipe in it (no pixel is black everywhere).
    let drawn = inlay_engine::HdrImage::load_exr(&depth_picture).unwrap();
    let view = inlay_engine::HdrImage::load_exr(&out.join("view-001.exr")).unwrap();
    assert_eq!((drawn.width, drawn.height), (view.width, view.height));
    assert!(drawn.pixels.iter().any(|p| p[0] + p[1] + p[2] > 0.0));
    // How far its surfaces spread, printed and drawn at the view's size.
    assert!(
        t.contains("held-out frame 1: the field's surfaces spread over 4 node spacings"),
        "{t}"
    );
    let spread = inlay_engine::HdrImage::load_exr(&spread_picture).unwrap();
    assert_eq!((spread.width, spread.height), (view.width, view.height));
    assert!(spread.pixels.iter().any(|p| p[0] + p[1] + p[2] > 0.0));
    // Where a step's time went, the training rays' pass among the rest.
    assert!(t.contains("a step took") && t.contains("train-rays"), "{t}");
    // And the radiance the knobs were fractions of.
    assert!(t.contains("knobs' scale: radiance"), "{t}");
    // Its depth maps held each ray's weight.
    assert!(
        t.contains("depth maps: 3 of 3 frames") && t.contains("each of their rays held to it"),
        "{t}"
    );
    // Its first stage's view-dependent start, said (2 of 20 steps).
    assert!(
        t.contains("the first 2 steps at degree 1, then degree 0"),
        "{t}"
    );
    // The sky learnt behind it, beside it.
    let sky = dir.join("views.sky.exr");
    assert!(t.contains("learnt a sky of 8x4 texels"), "{t}");
    let image = inlay_engine::HdrImage::load_exr(&sky).unwrap();
    inlay_passes::train::Sky::from_image(&image).unwrap();
    // Its geometry scored against the recipe the views show.
    assert!(
        t.contains("held-out frame 1: geometry against")
            && t.contains("node spacings")
            && t.contains("of the surfaces' light"),
        "{t}"
    );
    let trained = inlay_passes::field::load_field(&field).unwrap();
    // A run stopped at once (time budget) still writes a valid field, and
    // `--resume` continues from a field at its resolution.
    let stopped = dir.join("stopped.inlayfield");
    let o = inlay(&[
        "train",
        out.to_str().unwrap(),
        "--out",
        stopped.to_str().unwrap(),
        "--resolution",
        "8",
        "--time-budget",
        "1e-6",
        "--hold-out",
        "0",
    ]);
    let t = text(&o);
    assert!(
        o.status.success() && t.contains("stopped at step 0 (time budget)"),
        "{t}"
    );
    // Stopped in the first stage's view-dependent start (degree 1), it
    // still writes the degree asked for (0); and its grey start, which no
    // training ray yet weighs as much as pruning's threshold, is kept
    // unpruned (pruning it wrote a field with no density).
    let grey = inlay_passes::field::load_field(&stopped).unwrap();
    assert_eq!(grey.sh_degree, 0);
    assert!(grey.nodes.iter().any(|n| n[3] > 0.0));
    // A run whose arithmetic leaves f32's range stops with an error at
    // the step it did, and the field it would replace is left as it was.
    let before = std::fs::read(&stopped).unwrap();
    let o = inlay(&[
        "train",
        out.to_str().unwrap(),
        "--out",
        stopped.to_str().unwrap(),
        "--resolution",
        "8",
        "--iterations",
        "20",
        "--batch",
        "256",
        "--hold-out",
        "0",
        "--scale",
        "1e-30",
    ]);
    let t = text(&o);
    assert!(
        !o.status.success() && t.contains("training diverged: the batch's loss is NaN at step"),
        "{t}"
    );
    assert_eq!(std::fs::read(&stopped).unwrap(), before);
    let o = inlay(&[
        "train",
        out.to_str().unwrap(),
        "--out",
        stopped.to_str().unwrap(),
        "--resume",
        field.to_str().unwrap(),
        "--iterations",
        "5",
        "--batch",
        "128",
        "--hold-out",
        "0",
        "--sh-degree",
        "1",
        "--learn-exposure",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    // Its sky went on from the resumed field's (beside it), which
    // `--sky auto`, the default, chose.
    assert!(
        text(&o).contains("learning a sky of 8x4 texels behind the field: the --resume field's"),
        "{}",
        text(&o)
    );
    assert!(dir.join("stopped.sky.exr").is_file());
    assert!(text(&o).contains("learnt exposure gains"), "{}", text(&o));
    // Resumed with view-dependent colour: the file carries it, trained.
    let resumed = inlay_passes::field::load_field(&stopped).unwrap();
    assert_eq!(resumed.resolution, trained.resolution);
    assert_ne!(resumed.nodes, trained.nodes);
    assert_eq!(resumed.sh_degree, 1);
    assert!(resumed.sh.iter().flatten().any(|c| *c != 0.0));
    // Resumed again without the flag, it keeps its degree, and its only
    // stage trains the bricks it makes visible (the default, as a resumed
    // field too large for one binding always does); `--sparse=false`
    // trains it dense.
    let again = dir.join("again.inlayfield");
    for (flags, sparse) in [(&[][..], true), (&["--sparse=false"][..], false)] {
        let mut args = vec![
            "train",
            out.to_str().unwrap(),
            "--out",
            again.to_str().unwrap(),
            "--resume",
            stopped.to_str().unwrap(),
            "--iterations",
            "1",
            "--batch",
            "16",
            "--hold-out",
            "0",
        ];
        args.extend_from_slice(flags);
        let o = inlay(&args);
        assert!(o.status.success(), "{}", text(&o));
        assert_eq!(
            text(&o).contains("bricks of 8³ nodes (sparse)"),
            sparse,
            "{}",
            text(&o)
        );
        assert_eq!(
            inlay_passes::field::load_field(&again).unwrap().sh_degree,
            1
        );
    }
    for (flag, value, says) in [
        ("--time-budget", "0", "--time-budget"),
        ("--stages", "9", "--stages"),
        (
            "--first-stage-share",
            "1.5",
            "--first-stage-share: 1.5 must lie between 0 and 1",
        ),
        (
            "--refine-density-exponent",
            "2",
            "--refine-density-exponent: 2 must lie between 0 and 1",
        ),
        ("--sh-degree", "3", "--sh-degree: 3 must be in 0..=2"),
        ("--sky", "2000", "--sky: 2000 must be in 0..=1024"),
        ("--prune", "nan", "--prune: NaN must be non-negative"),
        ("--sparsity", "nan", "--sparsity: NaN must be non-negative"),
        (
            "--sparsity-edge",
            "inf",
            "--sparsity-edge: inf must be non-negative",
        ),
        ("--scale", "0", "--scale: 0 must be a positive radiance"),
        ("--out", "x.exr", ".inlayfield"),
        (
            "--scene",
            concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cups.toml"),
            "are not within the dataset's",
        ),
        (
            "--held-out-samples",
            "0",
            "--held-out-samples: 0 must be in 1..=16",
        ),
    ] {
        let mut args = vec![
            "train",
            out.to_str().unwrap(),
            "--out",
            field.to_str().unwrap(),
        ];
        if flag == "--out" {
            args.truncate(2);
        }
        args.extend([flag, value]);
        let o = inlay(&args);
        assert_eq!(o.status.code(), Some(1), "{flag}: {}", text(&o));
        assert!(text(&o).contains(says), "{flag}: {}", text(&o));
    }

    // A scene file names the trained field and the dataset's cameras:
    // they are the cameras render-views placed, and `render` takes one.
    let scene_file = dir.join("trained.toml");
    std::fs::write(
        &scene_file,
        "name = \"trained\"\nfield = \"views.inlayfield\"\ncameras_from = \"dog-views\"\n",
    )
    .unwrap();
    let trained_scene = inlay_passes::scene::load_scene(&scene_file).unwrap();
    let dog = inlay_passes::scene::load_scene(std::path::Path::new(scene)).unwrap();
    let placed = inlay_passes::dataset::capture::cap_cameras(
        &dog.recipe().unwrap().bounds,
        3,
        40.0,
        16.0 / 12.0,
        &dog.capture,
    );
    assert_eq!(trained_scene.cameras.len(), 3);
    for (a, b) in trained_scene.cameras.iter().zip(&placed) {
        let (da, db) = (
            (a.look_at - a.position).normalize(),
            (b.look_at - b.position).normalize(),
        );
        assert!((a.position - b.position).length() < 1e-5 && (da - db).length() < 1e-5);
        assert!(
            (a.fov_y - b.fov_y).abs() < 1e-6,
            "{} vs {}",
            a.fov_y,
            b.fov_y
        );
    }
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "field = \"views.inlayfield\"\ncameras_from = \"nowhere\"\n",
    )
    .unwrap();
    let err = inlay_passes::scene::load_scene(&bad)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("cameras_from") && err.contains("nowhere"),
        "{err}"
    );
    let render_to = |out: &std::path::Path| {
        inlay(&[
            "render",
            scene_file.to_str().unwrap(),
            "--camera",
            "view-001",
            "--width",
            "16",
            "--height",
            "12",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let picture = dir.join("trained.png");
    let o = render_to(&picture);
    assert!(o.status.success() && picture.is_file(), "{}", text(&o));
    // The sky learnt with the field (FIELD.sky.exr beside it) is drawn
    // behind it, and said so; without the file the same render says
    // nothing of a sky; a sky file that is not an EXR is an error naming
    // it.
    let (with_sky, over_black) = (dir.join("with-sky.exr"), dir.join("over-black.exr"));
    let o = render_to(&with_sky);
    assert!(
        o.status.success() && text(&o).contains("is drawn behind it"),
        "{}",
        text(&o)
    );
    let aside = dir.join("aside.exr");
    std::fs::rename(&sky, &aside).unwrap();
    let o = render_to(&over_black);
    assert!(
        o.status.success() && !text(&o).contains("drawn behind"),
        "{}",
        text(&o)
    );
    // A sky of 2 everywhere: each pixel gains (1 − coverage)·2.
    inlay_passes::field::Sky::uniform(4, glam::DVec3::splat(2.0))
        .to_image()
        .save(&sky, 1.0)
        .unwrap();
    let o = render_to(&with_sky);
    assert!(o.status.success(), "{}", text(&o));
    let (a, b) = (
        inlay_engine::HdrImage::load_exr(&with_sky).unwrap(),
        inlay_engine::HdrImage::load_exr(&over_black).unwrap(),
    );
    let mut uncovered = 0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let left = (1.0 - q[3]).max(0.0);
        for k in 0..3 {
            assert!((p[k] - q[k] - 2.0 * left).abs() < 1e-4, "{p:?} over {q:?}");
        }
        assert_eq!(p[3], 1.0);
        uncovered += (left > 0.01) as usize;
    }
    assert!(uncovered > 0, "no pixel shows the sky");
    std::fs::write(&sky, b"not an exr").unwrap();
    let o = render_to(&with_sky);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("views.sky.exr"), "{}", text(&o));
    std::fs::rename(&aside, &sky).unwrap();

    // Two frames lose their images: both are named, and nothing panics.
    std::fs::remove_file(out.join("view-000.exr")).unwrap();
    std::fs::write(out.join("view-002.exr"), b"not an exr").unwrap();
    let o = inlay(&["dataset", out.to_str().unwrap()]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("transforms.json: frames: 2 of 3 frames cannot be used"),
        "{t}"
    );
    assert!(
        t.contains("frames[0]") && t.contains("frames[2]") && !t.contains("frames[1]:"),
        "{t}"
    );
    let o = inlay(&["dataset", out.to_str().unwrap(), "--skip-bad-frames"]);
    let t = text(&o);
    assert!(
        o.status.success() && t.contains("1 usable, 2 left out"),
        "{t}"
    );

    let o = inlay(&[
        "render-views",
        scene,
        "--size",
        "16by12",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("WxH"), "{}", text(&o));
    // An arc of azimuths: backwards or of one angle is refused by name;
    // a negative start is an angle, not a flag.
    for bad in ["90,0", "10"] {
        let o = inlay(&[
            "render-views",
            scene,
            &format!("--azimuth={bad}"),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "{bad}: {}", text(&o));
        assert!(text(&o).contains("--azimuth"), "{bad}: {}", text(&o));
    }
    let arc = out.join("arc");
    let o = inlay(&[
        "render-views",
        scene,
        "--azimuth",
        "-30,60",
        "--views",
        "2",
        "--size",
        "8x8",
        "--samples",
        "1",
        "--out",
        arc.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("from azimuths -30° to 60°"),
        "{}",
        text(&o)
    );
}

/// Six views of a grey world with a bulb hanging above the box: `inlay
/// train` finds the bulb from the five it trains on, writes it beside the
/// field, and draws it in the held-out view; trained again with
/// `--seen-lights off` to the same file, the stale lights are emptied.
#[test]
fn train_finds_a_bulb_past_the_bounds_and_keeps_it_beside_the_field() {
    use inlay_passes::dataset::{Intrinsics, Pose};
    let dir = scratch("seen-lights");
    let data = dir.join("bulb");
    std::fs::create_dir_all(&data).unwrap();
    let (w, h) = (40u32, 30u32);
    let (bulb, radius) = (glam::DVec3::new(0.2, 2.4, -0.1), 0.05);
    let intrinsics = Intrinsics::centred(w, h, 50.0);
    let mut frames = Vec::new();
    for k in 0..6 {
        let a = k as f64 * std::f64::consts::TAU / 6.0;
        let eye = glam::DVec3::new(4.0 * a.cos(), 1.5, 4.0 * a.sin());
        let pose = Pose::looking_at(eye, glam::DVec3::new(0.0, 0.9, 0.0), glam::DVec3::Y);
        // Each pixel the share of an 8 × 8 grid of its rays the bulb meets.
        let pixels = (0..w * h)
            .map(|p| {
                let hits = (0..64)
                    .filter(|i| {
                        let (u, v) = (
                            (p % w) as f64 + (i % 8) as f64 / 8.0 + 1.0 / 16.0,
                            (p / w) as f64 + (i / 8) as f64 / 8.0 + 1.0 / 16.0,
                        );
                        let d = pose
                            .to_world(intrinsics.direction(u, v).unwrap())
                            .normalize();
                        let oc = eye - bulb;
                        let b = oc.dot(d);
                        b * b - (oc.length_squared() - radius * radius) > 0.0 && b < 0.0
                    })
                    .count();
                let c = (0.2 + hits as f64 / 64.0 * 5000.0) as f32;
                [c, c, c, 1.0]
            })
            .collect();
        let name = format!("view-{k}.exr");
        HdrImage {
            width: w,
            height: h,
            pixels,
        }
        .save(&data.join(&name), 1.0)
        .unwrap();
        let m = pose.matrix.transpose().to_cols_array_2d();
        frames.push(serde_json::json!({ "file_path": name, "transform_matrix": m }));
    }
    let transforms = serde_json::json!({
        "aabb": [[-1.0, -0.1, -1.0], [1.0, 1.4, 1.0]],
        "fl_x": intrinsics.fx, "fl_y": intrinsics.fy,
        "cx": intrinsics.cx, "cy": intrinsics.cy,
        "w": w, "h": h,
        "frames": frames,
    });
    std::fs::write(data.join("transforms.json"), transforms.to_string()).unwrap();
    // `inlay dataset` says what training will find, from all six views.
    let o = inlay(&["dataset", data.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("light past the bounds: a sphere at") && t.contains("seen in 6 views"),
        "{t}"
    );
    // Its share of the light past the bounds leaves the bulb's pixels out,
    // as training does.
    assert!(
        t.contains("pixels left out, as training leaves them"),
        "{t}"
    );
    let field = dir.join("bulb.inlayfield");
    let lights = dir.join("bulb.lights.toml");
    let train = |extra: &[&str]| {
        let mut args = vec![
            "train",
            data.to_str().unwrap(),
            "--out",
            field.to_str().unwrap(),
            "--resolution",
            "8",
            "--stages",
            "1",
            "--iterations",
            "5",
            "--hold-out",
            "1",
        ];
        args.extend_from_slice(extra);
        inlay(&args)
    };
    let o = train(&[]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    // Its frames record no depth: two runs, what the first run's field
    // places and leaves open said between them.
    assert!(
        t.contains("two runs: the first on the photographs alone")
            && t.contains("training pixels whose weight spreads over 3 spacings or more"),
        "{t}"
    );
    assert!(
        t.contains("light past the bounds: a sphere at") && t.contains("seen in 5 training views"),
        "{t}"
    );
    assert!(
        t.contains("1 light seen past the bounds, drawn wherever the field is"),
        "{t}"
    );
    let found = inlay_passes::field::seen_lights::load_seen_lights(&lights).unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    assert!((found[0].centre - bulb).length() < 0.02, "{found:?}");
    // The held-out view holds the bulb's light: the field alone, dark and
    // grey, would read a twentieth of it.
    let held = t
        .lines()
        .find(|l| l.starts_with("held-out frame 3:"))
        .unwrap_or_else(|| panic!("{t}"));
    let brightness: f64 = held
        .rsplit(' ')
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{held}"));
    assert!((0.7..1.3).contains(&brightness), "{held}");
    let o = train(&["--seen-lights", "off"]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("no light seen past the bounds"), "{t}");
    assert!(inlay_passes::field::seen_lights::load_seen_lights(&lights)
        .unwrap()
        .is_empty());
}
