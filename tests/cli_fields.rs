//! `inlay bake-scene`, `render` and `reference` end to end, and their errors
//! for bad scenes and field files.

mod common;

use std::path::{Path, PathBuf};

use inlay_engine::HdrImage;

use common::{inlay_cached as inlay, s, scene_path};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("inlay-fields-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `inlay bake-scene` of PLANTS at test size into `dir`: the field file and
/// the command's output.
fn bake_small_plants(dir: &Path) -> (PathBuf, String) {
    let field = dir.join("plants.inlayfield");
    let o = inlay(
        &[
            "bake-scene",
            &scene_path("plants.toml"),
            "--out",
            s(&field),
            "--resolution",
            "20",
            "--samples",
            "2",
            "--bounces",
            "0",
        ],
        dir,
    );
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    (field, t)
}

/// `inlay bake-scene` of bundled scene `name` at 24 nodes, 2 samples, no
/// bounce into `dir`: the scene file's path and the field file.
fn bake_scene_at_test_size(dir: &Path, name: &str) -> (String, PathBuf) {
    let scene = scene_path(&format!("{name}.toml"));
    let field = dir.join(format!("{name}.inlayfield"));
    let o = inlay(
        &[
            "bake-scene",
            &scene,
            "--out",
            s(&field),
            "--resolution",
            "24",
            "--samples",
            "2",
            "--bounces",
            "0",
        ],
        dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    (scene, field)
}

#[test]
fn bake_render_and_reference_write_images() {
    let dir = scratch("bake");
    let (field, t) = bake_small_plants(&dir);
    assert!(t.contains("lights inside the field: lamp"), "{t}");
    assert!(t.contains("lights outside the field: none"), "{t}");
    let exr = dir.join("r.exr");
    let o = inlay(
        &[
            "--validate",
            "render",
            &scene_path("plants.toml"),
            "--field",
            s(&field),
            "--width",
            "32",
            "--height",
            "20",
            "--frames",
            "2",
            "--camera",
            "high",
            "--no-shadows",
            "--out",
            s(&exr),
        ],
        &dir,
    );
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("nerf-march"), "per-pass timings: {t}");
    let img = HdrImage::load_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (32, 20));
    assert_eq!(img.non_finite_count(), 0);
    assert!(
        img.pixels.iter().any(|p| p[3] > 0.9),
        "the field is visible"
    );
    let refr = dir.join("ref.exr");
    let o = inlay(
        &[
            "reference",
            &scene_path("plants.toml"),
            "--width",
            "24",
            "--height",
            "16",
            "--samples",
            "2",
            "--out",
            s(&refr),
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    let img = HdrImage::load_exr(&refr).unwrap();
    assert_eq!((img.width, img.height), (24, 16));
}

#[test]
fn bad_inputs_get_errors_naming_the_file_and_field() {
    let dir = scratch("bad");
    // A truncated field file.
    let broken = dir.join("broken.inlayfield");
    let mut bytes = b"INLAYFLD".to_vec();
    bytes.extend_from_slice(&1u32.to_le_bytes());
    bytes.extend_from_slice(&[0; 60]);
    std::fs::write(&broken, &bytes).unwrap();
    let cases: Vec<(Vec<String>, String)> = vec![
        (
            vec![
                "render".into(),
                scene_path("cups.toml"),
                "--field".into(),
                s(&broken).into(),
            ],
            format!("{}: resolution.x", broken.display()),
        ),
        (
            vec!["render".into(), "/nonexistent/x.toml".into()],
            "/nonexistent/x.toml: file".into(),
        ),
        (
            vec![
                "render".into(),
                scene_path("cups.toml"),
                "--camera".into(),
                "9".into(),
            ],
            "no camera `9`".into(),
        ),
        (
            vec![
                "render".into(),
                scene_path("cups.toml"),
                "--samples-per-ray".into(),
                "0".into(),
            ],
            "samples_per_ray".into(),
        ),
        (
            vec![
                "bake-scene".into(),
                scene_path("cups.toml"),
                "--resolution".into(),
                "2".into(),
            ],
            "resolution".into(),
        ),
    ];
    for (args, expect) in cases {
        let args: Vec<&str> = args.iter().map(|a| a.as_str()).collect();
        let o = inlay(&args, &dir);
        let t = common::output_text(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(
            t.contains(&expect),
            "{args:?}: `{t}` should mention `{expect}`"
        );
        assert!(!t.contains("panicked"), "{t}");
    }
    // Names that must pick one camera or object, and a frame count of 0:
    // errors, not the first of two or a silent 1.
    let recipe = "[recipe]\nbounds = { min = [-1, -1, -1], max = [1, 1, 1] }\n\
                  [[recipe.primitives]]\nname = \"ball\"\ntype = \"sphere\"\n\
                  center = [0, 0, 0]\nradius = 0.5\n";
    let camera = |name: &str| {
        format!("[[cameras]]\nname = \"{name}\"\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n")
    };
    let two_cameras = dir.join("two-cameras.toml");
    std::fs::write(
        &two_cameras,
        format!("{recipe}{}{}", camera("a"), camera("a")),
    )
    .unwrap();
    let cube = common::objects_dir().join("checker-cube.gltf");
    let object = format!("[[objects]]\nfile = {:?}\nposition = [0, 0, 0]\n", s(&cube));
    let two_objects = dir.join("two-objects.toml");
    std::fs::write(
        &two_objects,
        format!("{recipe}{}{object}{object}", camera("a")),
    )
    .unwrap();
    // A vector of four numbers where three are expected, not truncated.
    let four = dir.join("four.toml");
    std::fs::write(
        &four,
        format!("{recipe}[[cameras]]\nposition = [0, 0, 3, 5]\nlook_at = [0, 0, 0]\n"),
    )
    .unwrap();
    // Radiance beyond what the fit stays finite for, refused up front.
    let bright = dir.join("bright.toml");
    std::fs::write(
        &bright,
        format!("{}emission = [1e7, 1e7, 1e7]\n{}", recipe, camera("a")),
    )
    .unwrap();
    let bright_sky = dir.join("bright-sky.toml");
    std::fs::write(
        &bright_sky,
        format!(
            "{recipe}{}[environment]\nlobes = [{{ direction = [0, 1, 0], sharpness = 2, amplitude = [1e21, 1, 1] }}]\n",
            camera("a")
        ),
    )
    .unwrap();
    for (args, expect) in [
        (vec!["render", s(&bright)], "above the radiance limit"),
        (
            vec!["render", s(&bright_sky)],
            "environment.lobes[0]: amplitude",
        ),
        (
            vec!["render", s(&four)],
            "invalid length 4, expected an array of 3 numbers",
        ),
        (
            vec!["render", s(&two_cameras)],
            "cameras[1].name: duplicate name `a`",
        ),
        (
            vec!["render", s(&two_objects)],
            "objects[1].name: duplicate name `checker-cube`",
        ),
        (
            vec!["render", &scene_path("cups.toml"), "--frames", "0"],
            "--frames",
        ),
        (
            vec!["profile", &scene_path("cups.toml"), "--frames", "0"],
            "--frames",
        ),
    ] {
        let o = inlay(&args, &dir);
        let t = common::output_text(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(
            t.contains(expect),
            "{args:?}: `{t}` should mention `{expect}`"
        );
    }
    // A scene whose field is a file has no ground truth to trace.
    let scene = dir.join("file-scene.toml");
    std::fs::write(
        &scene,
        "field = \"broken.inlayfield\"\n[[cameras]]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n",
    )
    .unwrap();
    let o = inlay(&["reference", s(&scene)], &dir);
    assert!(!o.status.success());
    assert!(common::output_text(&o).contains("not a [recipe]"));
}

#[test]
fn probe_writes_probe_fit_and_error_and_rejects_bad_points() {
    let dir = scratch("probe");
    let (field, _) = bake_small_plants(&dir);
    let exr = dir.join("probe.exr");
    let probe = |extra: &[&str]| {
        let mut args = vec![
            "--validate",
            "probe",
            &scene_path("plants.toml"),
            "--field",
            s(&field),
            "--resolution",
            "8",
            "--iterations",
            "6",
            "--out",
            s(&exr),
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
        args.extend(extra.iter().map(|a| a.to_string()));
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        inlay(&refs, &dir)
    };
    let o = probe(&[
        "--at",
        "0,0.4,0",
        "--lobes",
        "4",
        "--cpu-check",
        "--zoom",
        "2",
    ]);
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("environment: none (L_env not evaluated)"), "{t}");
    assert!(
        t.contains("relative residual") && t.contains("CPU reference"),
        "{t}"
    );
    assert!(t.contains("sg-fit:") && t.contains("probe-trace:"), "{t}");
    let img = HdrImage::load_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (3 * 8 * 2, 8 * 2));
    assert_eq!(img.non_finite_count(), 0);
    for (at, expect) in [
        ("nan,0,0", "three finite numbers"),
        ("1,2", "three finite numbers"),
        ("1e9,0,0", "scene units from the field"),
    ] {
        let o = probe(&["--at", at]);
        let t = common::output_text(&o);
        assert!(!o.status.success() && t.contains(expect), "--at {at}: {t}");
    }
    let o = probe(&["--at", "0,0.4,0", "--lobes", "0"]);
    let t = common::output_text(&o);
    assert!(!o.status.success() && t.contains("fit knob `lobes`"), "{t}");
}

/// `render` and `reference` insert the scene's objects (PLANTS has a toy
/// behind its foliage); `--no-objects` leaves the bare field, and bad
/// object entries are errors naming the scene file and the key.
#[test]
fn render_and_reference_insert_objects() {
    let dir = scratch("objects");
    let (field, _) = bake_small_plants(&dir);
    let plants = scene_path("plants.toml");
    let run = |extra: &[&str], out: &Path| {
        let mut args = vec![
            "--validate",
            "render",
            &plants,
            "--field",
            s(&field),
            "--width",
            "48",
            "--height",
            "27",
            "--frames",
            "2",
            "--camera",
            "high",
            "--ssdf-grid",
            "4",
            "--ssdf-directions",
            "8",
            "--out",
            s(out),
        ];
        args.extend_from_slice(extra);
        let o = inlay(&args, &dir);
        let t = common::output_text(&o);
        assert!(o.status.success(), "{t}");
        (t, HdrImage::load_exr(out).unwrap())
    };
    let (t, with) = run(&[], &dir.join("with.exr"));
    for pass in [
        "probe-trace",
        "sg-fit",
        "object-gbuffer",
        "object-shade",
        "cast-shadow",
        "composite",
    ] {
        assert!(t.contains(pass), "{pass} missing: {t}");
    }
    assert_eq!(with.non_finite_count(), 0);
    let (t, without) = run(&["--no-objects"], &dir.join("without.exr"));
    assert!(!t.contains("object-shade") && !t.contains("sg-fit"), "{t}");
    let (t, _) = run(&["--no-shadows"], &dir.join("unshadowed.exr"));
    assert!(!t.contains("cast-shadow") && !t.contains("ssdf"), "{t}");
    let changed = with
        .pixels
        .iter()
        .zip(&without.pixels)
        .filter(|(a, b)| (a[0] - b[0]).abs() > 1e-3)
        .count();
    assert!(changed >= 3, "{changed} pixels changed by the object");

    let reference = |extra: &[&str], name: &str| {
        let out = dir.join(name);
        let mut args = vec![
            "reference",
            &plants,
            "--width",
            "24",
            "--height",
            "14",
            "--samples",
            "2",
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        let o = inlay(&args, &dir);
        assert!(o.status.success(), "{}", common::output_text(&o));
        HdrImage::load_exr(&out).unwrap()
    };
    let a = reference(&[], "ref-with.exr");
    let b = reference(&["--no-objects"], "ref-without.exr");
    assert_ne!(a.pixels, b.pixels);

    // Bad object entries.
    let scene_text = std::fs::read_to_string(&plants).unwrap();
    let objects_dir = common::objects_dir();
    for (edit, field_key) in [
        ("file = \"objects/toy.glb\"", "objects[0].file"),
        ("scale = 0.3", "objects[0].scale"),
    ] {
        let replaced = match field_key {
            "objects[0].file" => scene_text.replace(edit, "file = \"objects/none.glb\""),
            _ => scene_text.replace(edit, "scale = 1e9"),
        };
        let bad = dir.join("bad-objects.toml");
        std::fs::write(&bad, replaced).unwrap();
        // The scene refers to objects beside it.
        let _ = std::fs::create_dir_all(dir.join("objects"));
        let _ = std::fs::copy(objects_dir.join("toy.glb"), dir.join("objects/toy.glb"));
        let o = inlay(&["render", s(&bad), "--field", s(&field)], &dir);
        let t = common::output_text(&o);
        assert!(!o.status.success(), "{t}");
        assert!(t.contains(&format!("bad-objects.toml: {field_key}")), "{t}");
    }
}

/// Every bundled scene renders headless with its object, the object's
/// self-shadows and its cast shadow (small fields, a 4³ SSDF grid of 8²
/// directions baked on first use): the cast shadow only ever darkens the
/// field, and darkens some of it. Compared without edge anti-aliasing: its
/// blend at the objects' outlines follows the neighbourhood's luma, so a
/// neighbour in shadow may lighten an outline pixel (CUPS' cube did, by
/// 0.7 % in blue, once its lamp's shadow was cast per point).
#[test]
fn every_bundled_scene_renders_with_shadows() {
    let dir = scratch("shadows");
    for name in ["books", "cups", "dog", "plants"] {
        let (scene, field) = bake_scene_at_test_size(&dir, name);
        let render = |extra: &[&str], out: &Path| {
            let mut args = vec![
                "--validate",
                "render",
                &scene,
                "--field",
                s(&field),
                "--width",
                "64",
                "--height",
                "36",
                "--frames",
                "1",
                "--ssdf-grid",
                "4",
                "--ssdf-directions",
                "8",
                "--no-edge-aa",
                "--out",
                s(out),
            ];
            args.extend_from_slice(extra);
            let o = inlay(&args, &dir);
            let t = common::output_text(&o);
            assert!(o.status.success(), "{name}: {t}");
            (t, HdrImage::load_exr(out).unwrap())
        };
        let (t, shadowed) = render(&[], &dir.join(format!("{name}.exr")));
        for pass in ["object-shade", "cast-shadow", "composite"] {
            assert!(t.contains(pass), "{name}: {pass} missing: {t}");
        }
        assert_eq!(shadowed.non_finite_count(), 0, "{name}");
        let (_, plain) = render(
            &["--no-cast-shadow"],
            &dir.join(format!("{name}-plain.exr")),
        );
        let mut darker = 0;
        for (a, b) in shadowed.pixels.iter().zip(&plain.pixels) {
            for c in 0..3 {
                assert!(
                    a[c] <= b[c] * (1.0 + 1e-5) + 1e-6,
                    "{name}: the cast shadow brightened a pixel: {a:?} vs {b:?}"
                );
            }
            darker += (a[1] < b[1] * 0.995) as u32;
        }
        assert!(darker >= 1, "{name}: no pixel is in the cast shadow");
    }
}

/// `inlay bake-ssdf` prints its time, sizes and compression ratio and
/// writes a field a scene can name; a knob out of range is refused by its
/// flag; a corrupt field file is an error naming the file and the field.
#[test]
fn bake_ssdf_writes_a_field_scenes_can_use() {
    let dir = scratch("bake-ssdf");
    let objects = common::objects_dir();
    let out = dir.join("sphere.inlayssdf");
    let o = inlay(
        &[
            "--validate",
            "bake-ssdf",
            s(&objects.join("metal-sphere.gltf")),
            "--out",
            s(&out),
            "--grid",
            "4",
            "--directions",
            "8",
            "--components",
            "4",
        ],
        &dir,
    );
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    for what in ["bake", "raw", "compressed", "% of raw", "PCA error"] {
        assert!(t.contains(what), "{what} missing: {t}");
    }
    let field = inlay_passes::ssdf::load_ssdf(&out).unwrap();
    assert_eq!(
        (field.grid.nodes, field.directions, field.components),
        (4, 8, 4)
    );
    for (flag, value, said) in [
        ("--grid", "1", "--grid"),
        ("--coarse-angle", "0.9", "--coarse-angle: 0.9"),
    ] {
        let sphere = objects.join("metal-sphere.gltf");
        let o = inlay(&["bake-ssdf", s(&sphere), flag, value], &dir);
        let t = common::output_text(&o);
        assert!(!o.status.success() && t.contains(said), "{t}");
    }

    // A scene naming the baked field, and one naming a corrupt copy.
    let text = std::fs::read_to_string(scene_path("books.toml")).unwrap();
    let text = text.replace(
        "objects/metal-sphere.gltf",
        s(&objects.join("metal-sphere.gltf")),
    );
    let named = dir.join("named.toml");
    std::fs::write(
        &named,
        text.replace(
            "scale = 0.1",
            &format!("scale = 0.1\nssdf = \"{}\"", s(&out)),
        ),
    )
    .unwrap();
    let bad_file = dir.join("bad.inlayssdf");
    let mut bytes = std::fs::read(&out).unwrap();
    bytes.truncate(bytes.len() - 4);
    std::fs::write(&bad_file, bytes).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        text.replace(
            "scale = 0.1",
            &format!("scale = 0.1\nssdf = \"{}\"", s(&bad_file)),
        ),
    )
    .unwrap();
    let field_file = dir.join("books.inlayfield");
    let o = inlay(
        &[
            "bake-scene",
            s(&named),
            "--out",
            s(&field_file),
            "--resolution",
            "16",
            "--samples",
            "1",
            "--bounces",
            "0",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", common::output_text(&o));
    let args = |scene: &Path, out: &Path| -> Vec<String> {
        [
            "render",
            s(scene),
            "--field",
            s(&field_file),
            "--width",
            "32",
            "--height",
            "18",
            "--frames",
            "1",
            "--out",
            s(out),
        ]
        .map(String::from)
        .to_vec()
    };
    let o = inlay(
        &args(&named, &dir.join("named.exr"))
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        &dir,
    );
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        !t.contains("baked the SSDF"),
        "the named field is used: {t}"
    );
    let o = inlay(
        &args(&bad, &dir.join("bad.exr"))
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        &dir,
    );
    let t = common::output_text(&o);
    assert!(!o.status.success());
    assert!(t.contains("bad.inlayssdf") && t.contains("data"), "{t}");
}

#[test]
fn estimate_env_writes_a_file_render_can_light_objects_with() {
    let dir = scratch("estimate-env");
    let (scene, field) = bake_scene_at_test_size(&dir, "books");
    let env = dir.join("books-env.toml");
    let picture = dir.join("books-env.exr");
    let compare = dir.join("compare.png");
    // A light the field's photographs saw past its bounds, in the file
    // beside the field: the estimate takes it as known and carries it.
    let bulb = inlay_passes::field::SeenLight {
        centre: glam::DVec3::new(0.3, 4.0, 0.2),
        radius: 0.05,
        radiance: glam::DVec3::new(500.0, 450.0, 400.0),
        views: 5,
        residual: 0.01,
    };
    std::fs::write(
        inlay_passes::field::seen_lights_path(&field),
        inlay_passes::field::seen_lights::seen_lights_text(&[bulb]),
    )
    .unwrap();
    let args = [
        "--validate",
        "estimate-env",
        &scene,
        "--field",
        s(&field),
        "--out",
        s(&env),
        "--picture",
        s(&picture),
        "--views",
        "3",
        "--view-size",
        "32",
        "--pixels",
        "8",
        "--rays",
        "64",
        "--iterations",
        "20",
        "--batch",
        "16",
        "--lobes",
        "4",
        "--albedo-width",
        "8",
        // The plumbing, not the test of whether the points need the light
        // (20 steps pin neither fit).
        "--min-loss-gain",
        "0",
        "--compare",
        s(&compare),
        "--compare-width",
        "48",
        "--compare-height",
        "27",
    ];
    let o = inlay(&args, &dir);
    let text = common::output_text(&o);
    // The status names a signal where the program printed nothing (one
    // clean-clone run ended so after the SSDF bake, under load; it did
    // not recur alone).
    assert!(o.status.success(), "{}\n{text}", o.status);
    for want in [
        "views: 3 kept",
        "near field",
        "hidden-light irradiance error",
        "mean relative difference",
        "kept without asking",
        "the points' loss under the recipe's hidden light",
        "known light (seen past the field's bounds) at 0.300 4.000 0.200",
    ] {
        assert!(text.contains(want), "no `{want}` in:\n{text}");
    }
    let written = inlay_passes::envest::load_environment_file(&env).unwrap();
    assert_eq!(written.seen_lights, vec![bulb]);
    let lobes = written.lobes;
    assert_eq!(lobes.len(), 4);
    let img = HdrImage::load_exr(&picture).unwrap();
    assert_eq!((img.width, img.height), (256, 128));
    assert_eq!(img.non_finite_count(), 0);
    assert!(compare.exists());
    // The same seed writes the same lobes.
    let again = dir.join("again.toml");
    let mut args2 = args.to_vec();
    args2[6] = s(&again);
    let o = inlay(&args2[..args2.len() - 6], &dir);
    assert!(o.status.success(), "{}", common::output_text(&o));
    assert_eq!(
        inlay_passes::envest::load_environment_file(&again)
            .unwrap()
            .lobes,
        lobes
    );
    // `--seen-lights off` estimates all the outside light, the bulb's too,
    // and its file carries no seen light.
    let off = dir.join("off.toml");
    args2[6] = s(&off);
    let mut args3 = args2[..args2.len() - 6].to_vec();
    args3.extend(["--seen-lights", "off"]);
    let o = inlay(&args3, &dir);
    let text = common::output_text(&o);
    assert!(
        o.status.success() && !text.contains("known light"),
        "{text}"
    );
    let off = inlay_passes::envest::load_environment_file(&off).unwrap();
    assert!(off.seen_lights.is_empty() && off.lobes != lobes);
    // render lights the objects with it; a bad file is named.
    let out = dir.join("lit.png");
    let render = |env: &Path| {
        inlay(
            &[
                "--validate",
                "render",
                &scene,
                "--field",
                s(&field),
                "--environment",
                s(env),
                "--width",
                "48",
                "--height",
                "27",
                "--frames",
                "1",
                "--no-shadows",
                "--out",
                s(&out),
            ],
            &dir,
        )
    };
    let o = render(&env);
    assert!(o.status.success(), "{}", common::output_text(&o));
    let bad = dir.join("bad-env.toml");
    std::fs::write(&bad, "format = \"inlay-environment\"\nversion = 1\n[[lobes]]\ndirection = [0, 1, 0]\nsharpness = -2.0\namplitude = [1, 1, 1]\n").unwrap();
    let o = render(&bad);
    let text = common::output_text(&o);
    assert!(
        !o.status.success() && text.contains("bad-env.toml") && text.contains("lobes[0]"),
        "{text}"
    );
}

/// Runs `inlay --validate profile` on PLANTS at 32 × 18 over a small
/// field in a scratch folder `name`, shadows off, with `extra` arguments;
/// returns its output and where it wrote the JSON and the trace.
fn profile_plants(name: &str, extra: &[&str]) -> (String, PathBuf, PathBuf) {
    let dir = scratch(name);
    let (field, _) = bake_small_plants(&dir);
    let (json, trace) = (dir.join("p.json"), dir.join("p.trace.json"));
    let scene = scene_path("plants.toml");
    let mut args = vec![
        "--validate",
        "profile",
        &scene,
        "--field",
        s(&field),
        "--width",
        "32",
        "--height",
        "18",
        "--no-shadows",
        "--json",
        s(&json),
        "--trace",
        s(&trace),
    ];
    args.extend_from_slice(extra);
    let o = inlay(&args, &dir);
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    (t, json, trace)
}

/// `inlay profile` on PLANTS (small field, tiny image, shadows off, the
/// object still): the Table 1 layout with the probe and fit run once and
/// skipped after, the cast shadow reported as skipped with its reason, and
/// JSON and Chrome-trace files that parse and agree with the table.
#[test]
fn profile_prints_table_1_and_writes_json_and_a_trace() {
    let (t, json, trace) = profile_plants("profile", &["--frames", "4", "--motion", "still"]);
    for module in [
        "NeRF rendering",
        "Lighting",
        "SG updating",
        "Rendering",
        "Compositing",
        "Shadow",
    ] {
        assert!(t.contains(module), "{module} missing: {t}");
    }
    assert!(
        t.contains("1 of 4 frames; otherwise skipped (object and lighting unchanged)"),
        "{t}"
    );
    assert!(t.contains("skipped (cast shadows off)"), "{t}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["frames"].as_array().unwrap().len(), 4);
    let sg = &report["table"]["modules"][2];
    assert_eq!(sg["module"], "SG updating");
    assert_eq!(sg["ran_in"], 1);
    assert!(sg["first_frame_ms"].as_f64().unwrap() > 0.0);
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let marches = events.iter().filter(|e| e["name"] == "nerf-march").count();
    assert_eq!(marches, 4, "one march event per frame");
    assert!(events.iter().any(|e| e["name"] == "sg-fit skipped"));
}

/// `inlay profile --viewer` on PLANTS (small field, tiny image, shadows
/// off, the object dragged): the viewer's pacing, the dragged frames
/// fitting in turn with tracing (the cold fit, then every other frame) and
/// the kept march's copies and the object's rectangle timed as the march.
#[test]
fn profile_paces_frames_as_the_viewer_does() {
    let (t, _, trace) = profile_plants("profile-viewer", &["--frames", "6", "--viewer"]);
    assert!(
        t.contains("3 of 6 frames; otherwise skipped (interleaved: the probe traced this frame, fitted the next)"),
        "{t}"
    );
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let marches = events.iter().filter(|e| e["name"] == "nerf-march").count();
    assert!(
        marches > 6,
        "the kept march's copies are march passes: {marches}"
    );
}

/// `inlay sweep` over a small full grid (two march step counts × two PCA
/// component counts on DOG at 32×18, a test-size field): every
/// configuration gets a time per Table 1 module and a finite error against
/// the path-traced truth; the JSON, Markdown and SVG agree on the count
/// and on the Pareto front; a sweep without the frames it needs is refused.
#[test]
fn sweep_measures_each_configuration_and_finds_the_pareto_front() {
    let dir = scratch("sweep");
    let (scene, field) = bake_scene_at_test_size(&dir, "dog");
    let out = dir.join("sweep");
    let args = |frames: &str| -> Vec<String> {
        [
            "--validate",
            "sweep",
            &scene,
            "--field",
            s(&field),
            "--sizes",
            "32x18",
            "--samples-per-ray",
            "32,128",
            "--probe",
            "8",
            "--lobes",
            "4",
            "--iterations",
            "4",
            "--ssdf-grid",
            "4",
            "--components",
            "2,4",
            "--grid",
            "full",
            "--frames",
            frames,
            "--reference-samples",
            "4",
            "--out-dir",
            s(&out),
        ]
        .iter()
        .map(|a| a.to_string())
        .collect()
    };
    let refused = inlay(
        &args("1").iter().map(String::as_str).collect::<Vec<_>>(),
        &dir,
    );
    let t = common::output_text(&refused);
    assert!(
        !refused.status.success() && t.contains("--frames must be at least 2"),
        "{t}"
    );
    let o = inlay(
        &args("3").iter().map(String::as_str).collect::<Vec<_>>(),
        &dir,
    );
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("4 configurations (Full grid)") && t.contains("Pareto front"),
        "{t}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let configs = report["configurations"].as_array().unwrap();
    assert_eq!(configs.len(), 4);
    let mut seen = Vec::new();
    for c in configs {
        let k = &c["knobs"];
        assert_eq!(
            (k["width"].as_u64(), k["probe"].as_u64()),
            (Some(32), Some(8))
        );
        seen.push((
            k["samples_per_ray"].as_u64().unwrap(),
            k["components"].as_u64().unwrap(),
        ));
        let error = c["error"].as_f64().expect("a finite error");
        assert!(error > 0.0 && error < 1.0, "{c}");
        assert!(c["frame_ms"].as_f64().unwrap() >= 0.0);
        for module in [
            "NeRF rendering",
            "Lighting",
            "SG updating",
            "Rendering",
            "Shadow",
        ] {
            assert!(
                c["modules_ms"][module].is_number(),
                "{module} ran while dragged: {c}"
            );
        }
    }
    seen.sort();
    assert_eq!(seen, vec![(32, 2), (32, 4), (128, 2), (128, 4)]);
    let front: Vec<u64> = report["pareto_front"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i.as_u64().unwrap())
        .collect();
    assert!(!front.is_empty());
    for (i, c) in configs.iter().enumerate() {
        assert_eq!(c["pareto"].as_bool(), Some(front.contains(&(i as u64))));
    }
    let md = std::fs::read_to_string(out.join("sweep.md")).unwrap();
    assert_eq!(md.matches("| yes |").count(), front.len(), "{md}");
    let svg = std::fs::read_to_string(out.join("sweep.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.matches("<circle").count() == 4,
        "{svg}"
    );
}
