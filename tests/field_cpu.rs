//! Radiance fields, recipes and scene files on the CPU: the bundled scenes
//! satisfy what they promise, empty-space skipping is exact, baking is
//! reproducible, and bad scene files get errors that name the key.

mod common;

use std::path::{Path, PathBuf};

use glam::DVec3;
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::{field_bytes, parse_field, GridField, RadianceField};
use inlay_passes::march::{march_image, MarchKnobs};
use inlay_passes::scene::{load_scene, Scene};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn scene(name: &str) -> Scene {
    common::bundled_scene(name)
}

fn bake(scene: &Scene, resolution: u32, samples: u32, bounces: u32) -> GridField {
    common::bake_small(scene, resolution, samples, bounces)
}

fn mean_occupied_radiance(f: &GridField) -> f64 {
    let occ: Vec<f64> = f
        .nodes
        .iter()
        .filter(|n| n[3] > 0.0)
        .map(|n| (n[0] + n[1] + n[2]) as f64 / 3.0)
        .collect();
    occ.iter().sum::<f64>() / occ.len() as f64
}

#[test]
fn bundled_recipes_have_the_lights_and_volumes_they_promise() {
    let names = ["plants.toml", "books.toml", "dog.toml", "cups.toml"];
    let scenes: Vec<Scene> = names.iter().map(|n| scene(n)).collect();
    // PLANTS: every light inside the field, no environment.
    let plants = &scenes[0];
    let (inside, outside) = plants.recipe().unwrap().lights();
    assert!(!inside.is_empty() && outside.is_empty() && plants.environment.is_black());
    // The other three have sources outside the field.
    for s in &scenes[1..] {
        let (_, outside) = s.recipe().unwrap().lights();
        assert!(
            !outside.is_empty() || !s.environment.is_black(),
            "{}",
            s.name
        );
    }
    // Semi-transparent volumes: foliage (PLANTS) and glass (CUPS).
    for s in [&scenes[0], &scenes[3]] {
        assert!(s
            .recipe()
            .unwrap()
            .primitives
            .iter()
            .any(|p| p.medium_density.is_some()));
    }
    // DOG: a tiny bulb ≥ 10⁴ × the field's mean radiance.
    let dog = &scenes[2];
    let bulb = dog
        .recipe()
        .unwrap()
        .primitives
        .iter()
        .find(|p| p.name == "bulb")
        .unwrap();
    let field = bake(dog, 24, 8, 0);
    let ratio = bulb.emission.max_element() / mean_occupied_radiance(&field);
    assert!(ratio >= 1e4, "bulb / mean radiance = {ratio:.3e}");
}

/// The method represents light from outside the field as a distant
/// environment, so the recipes must place their hidden lights where that
/// model holds, or the estimate's 15 % check could not pass even for a
/// perfect estimate: each recipe's hidden lights, turned into distant lobes
/// seen from the field's centre, must deliver their own irradiance at the
/// validation points within 5 % (BOOKS' sun and sky do by construction;
/// DOG's bulb and CUPS' lamp at 2–2.5 units missed by 33 % and 19 %).
#[test]
fn recipes_hidden_lights_are_distant() {
    use inlay_passes::envest::{hidden_light_lobes, Validation};
    for name in ["books.toml", "dog.toml", "cups.toml"] {
        let s = scene(name);
        let recipe = s.recipe().unwrap();
        let centre = 0.5 * (recipe.bounds.min + recipe.bounds.max);
        let lobes = hidden_light_lobes(recipe, &s.environment, centre, 1e4);
        let v = Validation::new(&s, recipe, &lobes, 512, 3);
        let error = v.hidden_error();
        assert!(error < 0.05, "{name}: distant form off by {error:.3}");
    }
}

/// ROOM is the scene for a *near* hidden light (a ceiling bulb 1.5 m
/// above the field, as the issue asks): its distant form seen from the
/// field's centre misses the bulb's own irradiance at the validation points
/// by more than 15 %, so ROOM really tests what a distant model cannot do;
/// seen from the object instead (how `lighting::object_light_lobes` lights
/// it), the lobes deliver the bulb's irradiance at the object within 2 %.
#[test]
fn rooms_bulb_is_near() {
    use inlay_passes::envest::{
        hidden_light_lobes, light_irradiance, lobes_irradiance, Lights, Validation,
    };
    let s = scene("room.toml");
    let recipe = s.recipe().unwrap();
    let centre = 0.5 * (recipe.bounds.min + recipe.bounds.max);
    let lobes = hidden_light_lobes(recipe, &s.environment, centre, 1e4);
    let error = Validation::new(&s, recipe, &lobes, 512, 3).hidden_error();
    assert!(error > 0.15, "ROOM's bulb looks distant: {error:.3}");
    let at = s.objects[0].sphere().0;
    let object_lobes = inlay_passes::lighting::object_light_lobes(&s, at);
    let ours = lobes_irradiance(recipe, &object_lobes, at, DVec3::Y, 4096, 5, true);
    let truth = light_irradiance(
        recipe,
        &s.environment,
        Lights::Hidden,
        at,
        DVec3::Y,
        4096,
        5,
        true,
    );
    let ratio = ours.y / truth.y;
    assert!((ratio - 1.0).abs() < 0.02, "at the object: {ratio:.4}");
}

#[test]
fn skipping_empty_space_changes_nothing_and_saves_samples() {
    let s = scene("cups.toml");
    let field = bake(&s, 64, 1, 0);
    assert!(field.occupancy.empty_fraction() > 0.3);
    let camera = CameraFrame::new(&s.cameras[1], 40, 24);
    let on = MarchKnobs::default();
    let off = MarchKnobs {
        skip_empty: false,
        ..on
    };
    let a = march_image(&field, &camera, &on, &|_, _| f64::INFINITY);
    let b = march_image(&field, &camera, &off, &|_, _| f64::INFINITY);
    let (mut sa, mut sb) = (0u64, 0u64);
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(
            (x.colour, x.opacity, x.depth),
            (y.colour, y.opacity, y.depth)
        );
        sa += x.samples as u64;
        sb += y.samples as u64;
    }
    assert!(
        sa * 2 < sb,
        "skipping evaluated {sa} samples, marching everything {sb}"
    );
}

#[test]
fn baking_is_reproducible_and_density_is_zero_away_from_surfaces() {
    let s = scene("dog.toml");
    let a = bake(&s, 16, 2, 1);
    let b = bake(&s, 16, 2, 1);
    assert_eq!(a.nodes, b.nodes, "same seed, same field");
    // Bytes round-trip through the file format: a fresh bake and the same
    // bake loaded from its file (or the cache) are the same field, bounds
    // included (DOG's −0.1 and 0.9 are not f32 values).
    let back = parse_field(Path::new("x"), &field_bytes(&a)).unwrap();
    assert_eq!(back.nodes, a.nodes);
    assert_eq!(back.bounds, a.bounds);
    // High above the dog there is nothing; under the floor it is solid.
    assert_eq!(a.density(DVec3::new(-0.7, 0.8, -0.7)), 0.0);
    assert!(a.density(DVec3::new(0.0, -0.08, 0.0)) > 100.0);
    // Direct light only is darker than with a bounce.
    let direct = bake(&s, 16, 2, 0);
    assert!(mean_occupied_radiance(&direct) < mean_occupied_radiance(&a));
}

#[test]
fn density_gradient_gives_surface_normals() {
    let s = scene("cups.toml");
    let field = bake(&s, 48, 1, 0);
    // On the table (y = 0), away from the cups: −∇σ points up.
    let x = DVec3::new(-0.6, 0.0, 0.6);
    let h = 1e-3;
    let g = DVec3::new(
        field.density(x + DVec3::X * h) - field.density(x - DVec3::X * h),
        field.density(x + DVec3::Y * h) - field.density(x - DVec3::Y * h),
        field.density(x + DVec3::Z * h) - field.density(x - DVec3::Z * h),
    );
    let n = (-g).normalize();
    assert!(n.dot(DVec3::Y) > 0.99, "normal {n}");
}

fn scene_error(text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("inlay-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("s{}.toml", text.len()));
    std::fs::write(&path, text).unwrap();
    let e = load_scene(&path).unwrap_err().to_string();
    assert!(e.contains(&path.display().to_string()), "{e}");
    e
}

#[test]
fn bad_scene_files_name_the_key() {
    let base = std::fs::read_to_string(scenes_dir().join("dog.toml")).unwrap();
    let cases = [
        (base.replace("radius = 0.13", "radius = nan"), "radius"),
        (base.replace("in_field = false", "in_field = true"), "bulb"),
        (
            base.replace("type = \"sphere\"", "type = \"torus\""),
            "torus",
        ),
        (
            base.replace("albedo = [0.5, 0.5, 0.5]", "albedo = [1.5, 0.5, 0.5]"),
            "albedo",
        ),
        (base.replace("fov_y = 45", "fov_y = 0"), "cameras[0]"),
        (
            base.replace("resolution = 128", "resolution = 100000"),
            "bake.resolution",
        ),
        (base.replace("[bake]", "[bake]\nsmaples = 3"), "smaples"),
        (
            format!("{base}\n[lighting]\nlobes = 100\n"),
            "lighting.lobes",
        ),
        (
            format!("{base}\n[lighting]\nprobe_resolution = 1\n"),
            "lighting.probe_resolution",
        ),
        (
            format!("{base}\n[lighting]\nprobe_supersampling = 0\n"),
            "lighting.probe_supersampling",
        ),
        (
            format!("{base}\n[lighting]\nprobe_supersampling = 64\n"),
            "lighting.probe_supersampling",
        ),
        (
            format!("{base}\n[lighting]\nprobe_map = \"cube\"\n"),
            "cube",
        ),
        (
            format!("{base}\n[lighting]\nframe_iterations = 1000\n"),
            "lighting.frame_iterations",
        ),
        (
            format!("{base}\n[shading]\nfield_light = 17\n"),
            "shading.field_light",
        ),
        (
            format!("{base}\n[shading]\nfield_light_scale = 0\n"),
            "shading.field_light_scale",
        ),
        (
            format!("{base}\n[shading]\nfield_light_scale = 5\n"),
            "shading.field_light_scale",
        ),
        (
            format!("{base}\n[shading]\nfield_light_scale = \"big\"\n"),
            "shading.field_light_scale",
        ),
        (
            format!("{base}\n[shadows]\ncast_scale = 0\n"),
            "shadows.cast_scale",
        ),
        (
            format!("{base}\n[shadows]\ncast_scale = 9\n"),
            "shadows.cast_scale",
        ),
        (
            format!("{base}\n[shadows]\ncast_scale = \"half\"\n"),
            "shadows.cast_scale",
        ),
        (
            format!("{base}\n[shadows]\ncast_scale = -2\n"),
            "shadows.cast_scale",
        ),
        (
            format!("{base}\n[shadows]\ncast_scale = 2.5\n"),
            "shadows.cast_scale",
        ),
        (
            format!("{base}\n[shadows]\ncast_refine = -0.5\n"),
            "shadows.cast_refine",
        ),
        (
            format!("{base}\n[shadows]\ncast_refine = nan\n"),
            "shadows.cast_refine",
        ),
        (
            format!("{base}\n[shadows]\ncoarse_angle = 0.7\n"),
            "shadows.coarse_angle",
        ),
        (
            format!("{base}\n[shadows]\ncoarse_angle = nan\n"),
            "shadows.coarse_angle",
        ),
        (
            format!("{base}\n[capture]\nazimuth = [90.0, 0.0]\n"),
            "capture.azimuth",
        ),
        (
            format!("{base}\n[capture]\nazimuth = [0.0, 5.0]\n"),
            "capture.azimuth",
        ),
        (
            format!("{base}\n[capture]\nazimut = [0.0, 90.0]\n"),
            "azimut",
        ),
        (
            base.replace("max = [0.9, 0.9, 0.9]", "max = [-2.0, 0.9, 0.9]"),
            "recipe.bounds",
        ),
        (
            base.replace("sharpness = 2.0", "sharpness = -1.0"),
            "environment.lobes[0]",
        ),
    ];
    for (text, expect) in cases {
        let e = scene_error(&text);
        assert!(e.contains(expect), "`{e}` should mention `{expect}`");
    }
    let missing = load_scene(Path::new("/nonexistent/scene.toml"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("/nonexistent/scene.toml"), "{missing}");
}

#[test]
fn lighting_knobs_come_from_the_scene_file() {
    let base = std::fs::read_to_string(scenes_dir().join("dog.toml")).unwrap();
    let dir = std::env::temp_dir().join(format!("inlay-lighting-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("lit.toml");
    // The scene's object file, beside the copy.
    std::fs::create_dir_all(dir.join("objects")).unwrap();
    std::fs::copy(
        scenes_dir().join("objects/metal-sphere.gltf"),
        dir.join("objects/metal-sphere.gltf"),
    )
    .unwrap();
    let text = format!("{base}\n[lighting]\nprobe_map = \"equirect\"\nprobe_resolution = 12\nlobes = 8\nwarm_iterations = 3\n");
    std::fs::write(&path, text).unwrap();
    let s = load_scene(&path).unwrap();
    assert_eq!(s.lighting.probe.map, inlay_passes::probe::MapKind::Equirect);
    assert_eq!(s.lighting.probe.resolution, 12);
    assert_eq!(
        (s.lighting.fit.lobes, s.lighting.fit.warm_iterations),
        (8, 3)
    );
    assert_eq!(
        s.lighting.fit.cold_iterations, 40,
        "unset knobs keep their defaults"
    );
    let plain = common::bundled_scene("dog.toml");
    assert_eq!(
        plain.lighting,
        inlay_passes::scene::LightingKnobs::default()
    );
}

/// DOG-CHECKER is DOG with a checkerboard floor and nothing else changed:
/// trained side by side, the two scenes' depth errors tell what the
/// photographs leave open from what the trainer gets wrong
/// (docs/benchmarks.md, issue 25's forty-third pass).
#[test]
fn dog_checker_is_dog_with_a_checkerboard_floor() {
    let text = |n: &str| std::fs::read_to_string(scenes_dir().join(n)).unwrap();
    let from_recipe = |t: &str| t[t.find("[recipe]").unwrap()..].to_string();
    let (dog, checker) = (text("dog.toml"), text("dog-checker.toml"));
    let line = "checker = { size = 0.06, albedo = [0.3, 0.3, 0.32] }\n";
    assert_eq!(
        from_recipe(&checker).replacen(line, "", 1),
        from_recipe(&dog)
    );
    let s = scene("dog-checker.toml");
    let floor = &s.recipe().unwrap().primitives[0];
    assert_eq!(floor.name, "floor");
    assert!(floor.checker.is_some());
    assert!(scene("dog.toml").recipe().unwrap().primitives[0]
        .checker
        .is_none());
}
