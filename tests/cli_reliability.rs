//! The command line never leaves a result that looks right and is not:
//! outputs and limits are checked before any work, a run killed while it
//! writes leaves the previous output whole, and an SSDF is used only for
//! the object it was baked from.

mod common;

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::time::Instant;

use inlay_engine::HdrImage;

use common::{inlay_cached as inlay, s, scene_path};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("inlay-cli-rel-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Fails unless the run failed with a message containing every one of
/// `needles`, having done no work (with an empty cache, any work on a
/// recipe scene starts with a bake, which says so).
fn refused_before_work(o: &Output, needles: &[&str]) {
    let t = common::output_text(o);
    assert!(!o.status.success(), "{t}");
    for n in needles {
        assert!(t.contains(n), "`{n}` missing: {t}");
    }
    assert!(
        !t.contains("baked"),
        "work was done before the refusal: {t}"
    );
}

/// Renders one 16 × 9 frame of `scene` over the field file `field` into
/// `out`, with its cache in `dir`.
fn render_small(
    scene: &std::path::Path,
    field: &std::path::Path,
    out: &std::path::Path,
    dir: &std::path::Path,
) -> Output {
    inlay(
        &[
            "render",
            s(scene),
            "--field",
            s(field),
            "--width",
            "16",
            "--height",
            "9",
            "--frames",
            "1",
            "--out",
            s(out),
        ],
        dir,
    )
}

#[test]
fn outputs_and_device_limits_are_checked_before_any_work() {
    let dir = scratch("before-work");
    let dog = scene_path("dog.toml");
    let missing = dir.join("no-such-dir/out.png");
    let a_directory = dir.join("d.png");
    std::fs::create_dir_all(&a_directory).unwrap();
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (
            vec![
                "render".into(),
                dog.clone(),
                "--out".into(),
                s(&missing).into(),
            ],
            vec!["--out", "no-such-dir", "does not exist"],
        ),
        (
            vec![
                "render".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("x.jpg")).into(),
            ],
            vec!["--out", "x.jpg", ".exr or .png"],
        ),
        (
            vec![
                "render".into(),
                dog.clone(),
                "--out".into(),
                s(&a_directory).into(),
            ],
            vec!["--out", "d.png", "directory"],
        ),
        (
            vec![
                "render".into(),
                dog.clone(),
                "--width".into(),
                "100000".into(),
                "--out".into(),
                s(&dir.join("ok.png")).into(),
            ],
            vec!["100000x360", "--width"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.txt")).into(),
            ],
            vec!["--out", ".toml"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.toml")).into(),
                "--min-loss-gain".into(),
                "nan".into(),
            ],
            vec!["--min-loss-gain", "must be in [0, 1e6]"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.toml")).into(),
                "--views-from".into(),
                s(&missing.with_file_name("transforms.json")).into(),
            ],
            vec!["--views-from", "transforms.json", "no such file"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.toml")).into(),
                "--radiance-from-photos".into(),
            ],
            vec!["--radiance-from-photos", "--seen-from"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.toml")).into(),
                "--seen-from".into(),
                "scene".into(),
                "--radiance-from-photos".into(),
            ],
            vec!["--radiance-from-photos", "not `scene`"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.toml")).into(),
                "--downscale".into(),
                "2".into(),
            ],
            vec!["--downscale 2", "--seen-from DATASET", "none are read"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("env.toml")).into(),
                "--seen-from".into(),
                concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cycles/dog/training").into(),
                "--downscale".into(),
                "65".into(),
            ],
            vec!["--seen-from", "--downscale", "65: must be 1 to 64"],
        ),
        (
            vec![
                "estimate-env".into(),
                dog.clone(),
                "--picture".into(),
                s(&missing).into(),
            ],
            vec!["--picture", "does not exist"],
        ),
        (
            vec![
                "profile".into(),
                dog.clone(),
                "--json".into(),
                s(&missing.with_extension("json")).into(),
            ],
            vec!["--json", "does not exist"],
        ),
        (
            vec![
                "probe".into(),
                dog.clone(),
                "--at".into(),
                "0,0,0".into(),
                "--out".into(),
                s(&dir.join("p.bmp")).into(),
            ],
            vec!["--out", "p.bmp"],
        ),
        (
            vec![
                "bake-scene".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("f.bin")).into(),
            ],
            vec!["--out", ".inlayfield"],
        ),
        (
            vec![
                "bake-ssdf".into(),
                s(&common::objects_dir().join("toy.glb")).into(),
                "--out".into(),
                s(&missing.with_extension("inlayssdf")).into(),
            ],
            vec!["--out", "does not exist"],
        ),
        (
            vec![
                "reference".into(),
                dog.clone(),
                "--out".into(),
                s(&dir.join("r.tiff")).into(),
            ],
            vec!["--out", "r.tiff"],
        ),
    ];
    for (args, needles) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = inlay(&args, &dir.join("cache"));
        refused_before_work(&o, &needles);
    }
    assert!(!dir.join("ok.png").exists());
    // Every refusal left the directory as it was: no output, no temporary.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "cache" && n != "d.png")
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// Writes a field file of format `version` for 1024³ nodes over [−1, 1]³,
/// `tail` after the bounds (the flags and what follows), `len` bytes long,
/// its data zero (sparse on disk); returns its header.
fn huge_field_file(path: &std::path::Path, version: u32, tail: &[[u8; 4]], len: u64) -> Vec<u8> {
    let mut header = Vec::new();
    header.extend_from_slice(b"INLAYFLD");
    for v in [version, 0, 1024, 1024, 1024] {
        header.extend_from_slice(&v.to_le_bytes());
    }
    for v in [-1f32, -1.0, -1.0, 1.0, 1.0, 1.0] {
        header.extend_from_slice(&v.to_le_bytes());
    }
    tail.iter().for_each(|w| header.extend_from_slice(w));
    std::fs::write(path, &header).unwrap();
    let file = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    file.set_len(len).unwrap();
    header
}

/// A field file whose header asks for more nodes than the device can hold
/// is refused from its header: a sparse 16 GiB file (1024³ nodes, more than
/// the device's largest heap; a smaller one may fit the storage binding
/// once stored sparsely, which only its nodes tell) is never read.
#[test]
fn a_field_too_large_for_the_device_is_refused_from_its_header() {
    let dir = scratch("huge-field");
    let path = dir.join("huge.inlayfield");
    let header = huge_field_file(&path, 1, &[0u32.to_le_bytes()], 56 + 16 * 1024u64.pow(3));
    assert_eq!(header.len(), 56);
    let o = inlay(
        &[
            "render",
            &scene_path("dog.toml"),
            "--field",
            s(&path),
            "--out",
            s(&dir.join("x.png")),
        ],
        &dir,
    );
    refused_before_work(
        &o,
        &[
            "huge.inlayfield",
            "resolution",
            "1024x1024x1024",
            "largest memory heap",
        ],
    );
    // A file shorter than its header says is refused before it is read.
    let short = dir.join("short.inlayfield");
    std::fs::write(&short, &header).unwrap();
    let e = inlay_passes::field::load_field(&short).unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
    // A sparse file (version 2) whose kept bricks hold more than one
    // storage binding, though the heap would take them, is refused from
    // its header too: its header says how many bricks it keeps.
    let binding = common::gpu().info().max_storage_buffer_range as u64;
    let bricks = binding / (512 * 16) + 1;
    let path = dir.join("sparse.inlayfield");
    let tail = [
        1u32.to_le_bytes(),
        (bricks as u32).to_le_bytes(),
        1f32.to_le_bytes(),
    ];
    let len = 64 + 4 * 128u64.pow(3) + 16 * 512 * bricks;
    assert_eq!(huge_field_file(&path, 2, &tail, len).len(), 64);
    let o = inlay(
        &[
            "render",
            &scene_path("dog.toml"),
            "--field",
            s(&path),
            "--out",
            s(&dir.join("x.png")),
        ],
        &dir,
    );
    refused_before_work(
        &o,
        &[
            "sparse.inlayfield",
            "resolution",
            "stored sparsely",
            "largest storage binding",
        ],
    );
}

/// `inlay reference` killed at many points of its run (tracing, or writing
/// its EXR) never leaves a broken image under the output's name: only the
/// previous one or the new one, whole.
#[test]
fn a_run_killed_while_writing_leaves_the_previous_output_whole() {
    let dir = scratch("killed");
    let out = dir.join("image.exr");
    let args = |samples: &str| {
        vec![
            "reference".to_string(),
            scene_path("plants.toml"),
            "--width".into(),
            "960".into(),
            "--height".into(),
            "540".into(),
            "--samples".into(),
            samples.into(),
            "--out".into(),
            s(&out).into(),
        ]
    };
    let started = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_inlay"))
        .args(args("1"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", common::output_text(&o));
    let whole_run = started.elapsed();
    let check = |when: &str| {
        let img = HdrImage::load_exr(&out)
            .unwrap_or_else(|e| panic!("after a kill {when}, the output is broken: {e}"));
        assert_eq!((img.width, img.height), (960, 540));
    };
    check("(first run)");
    // Kills spread over the second half of the run (the write is at its
    // end), and past its end too.
    for i in 0..30u32 {
        let delay = whole_run.mul_f64(0.5 + 0.025 * i as f64);
        let mut child = Command::new(env!("CARGO_BIN_EXE_inlay"))
            .args(args("1"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(delay);
        let _ = child.kill();
        let _ = child.wait();
        check(&format!("after {:.0} ms", delay.as_secs_f64() * 1e3));
    }
    // Whatever a kill left is a hidden temporary, never the output's name.
    for e in std::fs::read_dir(&dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            name == "image.exr" || name.starts_with(inlay_engine::output::PARTIAL_PREFIX),
            "{name}"
        );
    }
}

/// An SSDF baked from one object and named for another is refused, naming
/// the file and what to do; before, the other object's shadows were used.
#[test]
fn an_ssdf_is_used_only_for_the_object_it_was_baked_from() {
    let dir = scratch("ssdf-object");
    let objects = common::objects_dir();
    let ssdf = dir.join("sphere.inlayssdf");
    let o = inlay(
        &[
            "bake-ssdf",
            s(&objects.join("metal-sphere.gltf")),
            "--out",
            s(&ssdf),
            "--grid",
            "4",
            "--directions",
            "8",
            "--components",
            "4",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    let text = std::fs::read_to_string(scene_path("books.toml")).unwrap();
    assert!(text.contains("objects/metal-sphere.gltf") && text.contains("scale = 0.1"));
    let scene = |object: &str| {
        text.replace("objects/metal-sphere.gltf", s(&objects.join(object)))
            .replace(
                "scale = 0.1",
                &format!("scale = 0.1\nssdf = \"{}\"", s(&ssdf)),
            )
    };
    let wrong = dir.join("wrong.toml");
    std::fs::write(&wrong, scene("toy.glb")).unwrap();
    let field = dir.join("books.inlayfield");
    let o = inlay(
        &[
            "bake-scene",
            s(&wrong),
            "--out",
            s(&field),
            "--resolution",
            "8",
            "--samples",
            "1",
            "--bounces",
            "0",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    let o = render_small(&wrong, &field, &dir.join("wrong.png"), &dir);
    let t = common::output_text(&o);
    assert!(!o.status.success(), "{t}");
    for needle in ["sphere.inlayssdf", "object", "another mesh", "bake-ssdf"] {
        assert!(t.contains(needle), "`{needle}` missing: {t}");
    }
    assert!(!dir.join("wrong.png").exists());
}

/// On llvmpipe, which ends an invocation's loops after 65535 iterations
/// in all, an object whose shading would march 8 × 8 rays of up to 1025
/// samples to PLANTS' lamp at each pixel is refused before any frame,
/// naming the knobs, rather than shaded with its rays cut short; a
/// device without that limit renders it.
#[test]
fn shading_rays_past_the_devices_loop_limit_are_refused() {
    let dir = scratch("pixel-loops");
    let limited = common::gpu().info().loop_iteration_limit.is_some();
    let text = std::fs::read_to_string(scene_path("plants.toml")).unwrap();
    let toy = common::objects_dir().join("toy.glb");
    assert!(text.contains("file = \"objects/toy.glb\"") && !text.contains("[march]"));
    let scene = dir.join("plants-rays.toml");
    let text = text.replace("objects/toy.glb", s(&toy))
        + "\n[march]\nsamples_per_ray = 1024\n\n[lighting]\nlocal_light_rays = 8\n";
    std::fs::write(&scene, text).unwrap();
    let field = dir.join("plants.inlayfield");
    let o = inlay(
        &[
            "bake-scene",
            s(&scene),
            "--out",
            s(&field),
            "--resolution",
            "40",
            "--samples",
            "4",
            "--bounces",
            "1",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    let out = dir.join("rays.png");
    let o = render_small(&scene, &field, &out, &dir);
    let t = common::output_text(&o);
    if !limited {
        assert!(o.status.success(), "{t}");
        return;
    }
    assert!(!o.status.success(), "{t}");
    for needle in [
        "toy",
        "object-shade",
        "local_light_rays` 8",
        "samples_per_ray` 1024",
        "65535",
    ] {
        assert!(t.contains(needle), "`{needle}` missing: {t}");
    }
    assert!(!out.exists());
}

/// DOG over a field with view-dependent colour renders at the scene's own
/// knobs: its shading's rays, counted against llvmpipe's loop limit, stay
/// under it (counted at nine iterations a sample, as the march's own loop
/// over the corners costs, they had passed it and the frame was refused).
#[test]
fn a_view_dependent_field_renders_at_the_scenes_knobs() {
    use inlay_passes::field::{save_field, sh_extra_coefficients};
    let dir = scratch("sh-dog");
    let scene = common::bundled_scene("dog.toml");
    let plain = common::bake_small(&scene, 48, 1, 0);
    // The lamp is shaded as a local light: its rays are what the check
    // counts most.
    let emitters = inlay_passes::field::find_emitters(&plain);
    assert_eq!(
        scene.lighting.local.choose(&emitters, &plain.bounds).len(),
        1
    );
    let k = sh_extra_coefficients(1);
    let sh: Vec<[f32; 3]> = (0..plain.nodes.len() * k)
        .map(|i| {
            let c = plain.nodes[i / k];
            std::array::from_fn(|ch| 0.2 * c[ch] * if (i + ch) % 2 == 0 { 1.0 } else { -1.0 })
        })
        .collect();
    let field = dir.join("dog-sh1.inlayfield");
    save_field(&field, &plain.with_sh(1, sh)).unwrap();
    let out = dir.join("dog.png");
    let o = render_small(
        std::path::Path::new(&scene_path("dog.toml")),
        &field,
        &out,
        &dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    assert!(out.exists());
}

/// The text of a scene of `count` small cubes on a floor, at test knobs.
fn many_cubes(count: usize) -> String {
    let cube = common::objects_dir().join("checker-cube.gltf");
    let mut text = String::from(
        r#"name = "many"
[recipe]
bounds = { min = [-1.0, -0.1, -1.0], max = [1.0, 1.0, 1.0] }
[[recipe.primitives]]
name = "floor"
type = "box"
center = [0.0, -0.05, 0.0]
size = [2.0, 0.1, 2.0]
albedo = [0.5, 0.5, 0.5]
[environment]
lobes = [{ direction = [0.0, 1.0, 0.0], sharpness = 2.0, amplitude = [1.0, 1.0, 1.0] }]
[[cameras]]
position = [0.0, 1.5, 2.0]
look_at = [0.0, 0.0, 0.0]
[bake]
resolution = 16
samples = 1
bounces = 0
[lighting]
probe_resolution = 4
lobes = 2
cold_iterations = 2
warm_iterations = 1
[shadows]
grid = 4
directions = 8
components = 4
"#,
    );
    for i in 0..count {
        let (x, z) = (-0.8 + (i % 8) as f64 * 0.22, -0.8 + (i / 8) as f64 * 0.22);
        text.push_str(&format!(
            "[[objects]]\nname = \"cube{i}\"\nfile = \"{}\"\nposition = [{x:.3}, 0.05, {z:.3}]\nscale = 0.05\n",
            s(&cube)
        ));
    }
    text
}

/// As many objects as a scene may hold are inserted, shadowed and timed
/// (before, from 31 objects on, the frame's passes outgrew the timer's 128
/// and the render failed after its bakes); one more is refused when the
/// scene is read.
#[test]
fn the_most_objects_a_scene_may_hold_render() {
    let dir = scratch("many");
    let most = inlay_passes::scene::MAX_OBJECTS;
    let scene = dir.join("most.toml");
    std::fs::write(&scene, many_cubes(most)).unwrap();
    let out = dir.join("most.exr");
    let o = inlay(
        &[
            "--validate",
            "render",
            s(&scene),
            "--width",
            "48",
            "--height",
            "27",
            "--frames",
            "1",
            "--out",
            s(&out),
        ],
        &dir,
    );
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("cast-shadow"), "{t}");
    assert_eq!(HdrImage::load_exr(&out).unwrap().non_finite_count(), 0);
    let over = dir.join("over.toml");
    std::fs::write(&over, many_cubes(most + 1)).unwrap();
    let o = inlay(
        &["render", s(&over), "--out", s(&dir.join("over.png"))],
        &dir,
    );
    refused_before_work(&o, &["over.toml", "objects", "at most 64"]);
}

/// `bake-scene` refuses, before baking, a resolution whose field the device
/// could not render even sparsely (before, it baked for minutes and
/// `render` refused the file afterwards). Lavapipe's 2 GiB heap holds
/// every bundled scene's 512-node field (sparse, it also fits its 128 MiB
/// binding): there the check is `reliability.rs`'s on a small device.
#[test]
fn bake_scene_refuses_a_field_the_device_cannot_render() {
    let dir = scratch("bake-limit");
    let info = common::gpu().info().clone();
    let scene =
        inlay_passes::scene::load_scene(std::path::Path::new(&scene_path("dog.toml"))).unwrap();
    let res = inlay_passes::bake::grid_resolution(scene.recipe().unwrap(), 512);
    if inlay_passes::field::check_field_may_fit(
        &info,
        res,
        0,
        inlay_passes::field::NodeStorage::Render,
    )
    .is_ok()
    {
        eprintln!(
            "{} may render a 512-node field: nothing to refuse here",
            info.name
        );
        return;
    }
    let out = dir.join("big.inlayfield");
    let o = inlay(
        &[
            "bake-scene",
            &scene_path("dog.toml"),
            "--resolution",
            "512",
            "--out",
            s(&out),
        ],
        &dir,
    );
    refused_before_work(&o, &["--resolution 512", "more than", &info.name]);
    assert!(!out.exists());
}
