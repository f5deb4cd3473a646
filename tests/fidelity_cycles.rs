//! inlay against an independent renderer: the Blender Cycles renders
//! committed in `docs/cycles/` (made by `tools/cycles/render_cycles.py`,
//! see `docs/fidelity.md`). Held here, with tolerances from the measured
//! Monte-Carlo noise of both renderers:
//! - the recipe path tracer (`inlay reference`) against Cycles, per scene
//!   and camera, bare: the images' 8 × 8-block means over the pixels the
//!   field covers;
//! - the incident light at each object's centre: the GPU probe's
//!   irradiance from the upper hemisphere against Cycles' irradiance
//!   sensor, on a field baked at test size;
//! - the cast shadow's darkening far from the object (CUPS, ROOM), on a
//!   field baked at test size: it does not depend on the field's
//!   resolution the way the shadow's shape does.
//!
//! The rest of the insertion's figures (object brightness, the shadow's
//! shape and depth) need the full bakes; `inlay fidelity` measures them
//! (docs/fidelity.md).

mod common;

use std::path::{Path, PathBuf};

use glam::DVec3;
use inlay::commands::fidelity::render_over_field;
use inlay::fidelity::{
    block_means, box_shadow_ratio, coverage, far_pixels, luminance, mean_ratio,
    median_relative_error, relative_l1, shadow_figures, Rgb,
};
use inlay_engine::HdrImage;
use inlay_passes::bake::{render_reference, ReferenceOptions};
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::GpuGridField;
use inlay_passes::probe::{probe_irradiance, ProbePass};
use inlay_passes::shaders::embedded_library;

fn cycles_dir(scene: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/cycles")
        .join(scene)
}

fn load(path: &Path) -> Rgb {
    Rgb::of(&HdrImage::load_exr(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
}

const SCENES: [&str; 5] = ["dog", "cups", "books", "plants", "room"];

/// The reference's 8 × 8-block tolerance per scene: 1.5 % where Cycles'
/// two seeds differ by 0.1–0.6 % on the blocks; ROOM's 3 cm bulb is a mesh
/// light Cycles samples by its triangles, and its seeds differed by 2.4 %
/// there at 512 samples (0.8 % at the 4096 now committed), so its
/// tolerance is 4 % (measured 2.16 %; the path tracer's 32 samples × 2
/// seeds of the bulb carry the rest).
fn reference_tolerance(scene: &str) -> f64 {
    if scene == "room" {
        0.04
    } else {
        0.015
    }
}

/// The path tracer's bare image against Cycles' (both with the scene's
/// bounces) on 8 × 8 blocks of the pixels the field covers, media
/// included: within 1.5 % relative L1 on every camera (measured
/// 0.20–0.60 %, the most on BOOKS; DOG 0.20, CUPS 0.28 and 0.44, PLANTS
/// 0.33 and 0.37). Cycles' own two seeds differed by 0.1–0.6 % on these
/// blocks at 512 samples and by less at the 4096 now committed (the mean
/// of two by about half that); the path tracer at
/// 32 samples × 2 seeds adds its own.
#[test]
fn the_reference_path_tracer_matches_cycles() {
    for name in SCENES {
        let dir = cycles_dir(name);
        let scene = common::bundled_scene(&format!("{name}.toml"));
        let recipe = scene.recipe().unwrap();
        for (ci, camera) in scene.cameras.iter().enumerate() {
            let cam = camera.name.clone().unwrap_or_else(|| ci.to_string());
            let (a, b) = (
                dir.join(format!("{cam}-bare-full-s1.exr")),
                dir.join(format!("{cam}-bare-full-s2.exr")),
            );
            assert!(
                a.exists() && b.exists(),
                "{}: Cycles renders missing",
                a.display()
            );
            let cycles = Rgb::mean(&load(&a), &load(&b));
            let frame = CameraFrame::new(camera, cycles.width, cycles.height);
            let cover = coverage(recipe, &[], &frame, 2);
            // Media included: they agree since the Cycles translation
            // flat-shades a medium's boundary (docs/fidelity.md, seventh pass).
            let mask = |i: usize| cover.field[i] >= 1.0;
            let trace = |seed| {
                let pixels = render_reference(
                    recipe,
                    &scene.environment,
                    &[],
                    &frame,
                    &ReferenceOptions {
                        samples: 32,
                        bounces: scene.bake.bounces,
                        seed,
                        antialias: true,
                        sky_behind: false,
                    },
                    &|_, _| {},
                );
                Rgb::of(&HdrImage {
                    width: frame.width,
                    height: frame.height,
                    pixels,
                })
            };
            let ours = Rgb::mean(&trace(1), &trace(2));
            let blocks = |x: &Rgb| block_means(x, 8, mask);
            let err = relative_l1(&blocks(&ours), &blocks(&cycles), |_| true);
            eprintln!("{name} {cam}: reference against Cycles, 8×8 blocks: relative L1 {err:.4}");
            assert!(err < reference_tolerance(name), "{name} {cam}: {err}");
        }
    }
}

/// The probe's irradiance from the upper hemisphere at each object's
/// centre against Cycles' sensor there. The field is baked at 64 nodes and
/// 8 samples (the scenes bake 128 and 32): its light is noisier and
/// blurrier than the full bake's, so the tolerance is 8 % where the full
/// bake measures within 2.6 % (docs/fidelity.md); measured −0.1 to +4.0 %.
#[test]
fn the_probe_irradiance_matches_cycles_sensors() {
    let ctx = common::gpu();
    let lib = embedded_library();
    for name in SCENES {
        let scene = common::bundled_scene(&format!("{name}.toml"));
        let field = common::bake_small(&scene, 64, 8, scene.bake.bounces);
        let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
        let knobs = scene.lighting.probe;
        let map = knobs.direction_map();
        let rb = common::probe_readback(&ctx, &map);
        for object in &scene.objects {
            let path = cycles_dir(name).join(format!("irradiance-{}.json", object.name));
            let json: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            let sensor = |seed: &str| {
                let v: Vec<f64> = json["irradiance"][seed]["+y"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                luminance(DVec3::new(v[0], v[1], v[2]))
            };
            let cycles = 0.5 * (sensor("s1") + sensor("s2"));
            let (centre, _) = object.sphere();
            let env = inlay_passes::lighting::object_light_lobes(&scene, centre);
            let pass = ProbePass::new(&ctx, &lib, knobs, scene.march, &env, &[]).unwrap();
            common::run_frame(&ctx, |graph| {
                let probe = pass.add(graph, &gpu_field, centre);
                rb.add_to_graph(graph, probe);
            });
            let texels: Vec<[f64; 4]> = rb
                .read()
                .unwrap()
                .pixels
                .iter()
                .map(|p| p.map(f64::from))
                .collect();
            let ours = luminance(probe_irradiance(&map, &texels, DVec3::Y));
            eprintln!(
                "{name} {}: upper-hemisphere irradiance {ours:.4}, Cycles {cycles:.4} ({:+.2} %)",
                object.name,
                100.0 * (ours / cycles - 1.0)
            );
            assert!(
                (ours / cycles - 1.0).abs() < 0.08,
                "{name} {}: {ours} against {cycles}",
                object.name
            );
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// The cast shadow far from the object (surface points over 4 bounding
/// radii from it, 3 × 3 means of the field's own pixels) against Cycles,
/// on fields baked at test size (64 nodes, 8 samples) with the objects'
/// SSDFs at the scenes' knobs: the mean darkening within the issue's
/// 0.3 %. Measured: CUPS front 0.13 %, side 0.07 %, ROOM 0.035 %
/// (0.07 % while its softbox was among the fitted lobes; Cycles: 0.22 %,
/// 0.19 %, −0.28 %); before each lobe's loss was held to
/// its light over the object's cone (docs/fidelity.md, fifteenth pass),
/// 0.42 %, 0.32 % and 0.43 % on the same fields — what it was at full
/// size too (0.43 %, 0.32 %, 0.32 %). The shadow's shape and depth need
/// the full bake (at 64 nodes the field's normals and depths blur the
/// receivers: correlation 0.5–0.7).
#[test]
fn the_far_field_darkens_as_little_as_in_cycles() {
    let ctx = common::gpu();
    for name in ["cups", "room"] {
        let scene = common::bundled_scene(&format!("{name}.toml"));
        let recipe = scene.recipe().unwrap().clone();
        let field = common::bake_small(&scene, 64, 8, scene.bake.bounces);
        let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
        let library = gpu_field.library(&embedded_library());
        let spheres: Vec<(DVec3, f64)> = scene.objects.iter().map(|o| o.sphere()).collect();
        for camera in &scene.cameras {
            let camera_name = camera.name.clone().unwrap();
            let cycles = |what: &str| {
                let seed = |s: &str| {
                    load(&cycles_dir(name).join(format!("{camera_name}-{what}-full-{s}.exr")))
                };
                Rgb::mean(&seed("s1"), &seed("s2"))
            };
            let (bare, with) = (cycles("bare"), cycles("objects"));
            let (w, h) = (bare.width, bare.height);
            let frame = CameraFrame::new(camera, w, h);
            let bare_cover = coverage(&recipe, &[], &frame, 4);
            let object_cover = coverage(&recipe, &scene.objects, &frame, 4).object;
            let field_only = |i: usize| bare_cover.field[i] >= 1.0 && object_cover[i] == 0.0;
            let far = far_pixels(&bare_cover, &spheres);
            let render = |objects| {
                render_over_field(&ctx, &library, &scene, &gpu_field, camera, (w, h), objects)
                    .unwrap()
            };
            let ours = box_shadow_ratio(&render(true), &render(false), field_only);
            let theirs = box_shadow_ratio(&with, &bare, field_only);
            let figures = shadow_figures(&ours, &theirs, field_only, |i| far[i]);
            eprintln!(
                "{name} {camera_name}: far darkening {:.3} % over {} pixels (Cycles {:.3} %)",
                100.0 * figures.far_darkening,
                figures.far_pixels,
                100.0 * figures.truth_far_darkening
            );
            assert!(figures.far_pixels > 10_000, "{}", figures.far_pixels);
            assert!(
                figures.far_darkening < 0.003,
                "{name} {camera_name}: far darkening {} %",
                100.0 * figures.far_darkening
            );
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// The field's light at the object's surface (`[shading] field_light`) on
/// PLANTS' toy among the foliage, on a field baked at test size (64
/// nodes, 8 samples): against Cycles, the toy's median relative error
/// (pixels whose 4² rays all hit it) with the scene's 16² rays a tile is
/// no worse than the paper's shading (0 rays) on either camera and well
/// below it on one, and the toy's mean brightness stays within the
/// issue's ±10 %. Measured on the 2-core machine against the
/// 4096-sample truth: front 0.162 with and 0.191 without (brightness
/// 1.041), high 0.160 and 0.312 (0.921); on the full bake 0.072 and
/// 0.127 with (`docs/fidelity.md`, seventeenth pass). Against the
/// 512-sample truth: 0.197 and 0.197, 0.196 and 0.314; on the full bake
/// 0.121 and 0.167, 0.170 and 0.288 (sixteenth pass). The margins: 0.005
/// is the change 12² against 16² rays makes on the full bake's high view
/// (0.008) rounded down, and the 0.05 of improvement is under half the
/// 0.118 measured against the older truth (0.152 now).
#[test]
fn the_toy_among_leaves_is_lit_by_what_reaches_it() {
    let ctx = common::gpu();
    let name = "plants";
    let scene = common::bundled_scene(&format!("{name}.toml"));
    assert!(
        scene.shading.field_light > 0,
        "the scene's shading takes the field's light"
    );
    let recipe = scene.recipe().unwrap().clone();
    let field = common::bake_small(&scene, 64, 8, scene.bake.bounces);
    let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
    let library = gpu_field.library(&embedded_library());
    let mut best = 0.0f64;
    for camera in &scene.cameras {
        let camera_name = camera.name.clone().unwrap();
        let seed =
            |s: &str| load(&cycles_dir(name).join(format!("{camera_name}-objects-full-{s}.exr")));
        let truth = Rgb::mean(&seed("s1"), &seed("s2"));
        let (w, h) = (truth.width, truth.height);
        let frame = CameraFrame::new(camera, w, h);
        let object = coverage(&recipe, &scene.objects, &frame, 4).object;
        let mask = |i: usize| object[i] >= 1.0;
        let pixels = (0..(w * h) as usize).filter(|&i| mask(i)).count();
        assert!(pixels > 300, "{camera_name}: {pixels} toy pixels");
        let figures = |side: u32| {
            let mut s = scene.clone();
            s.shading.field_light = side;
            let ours =
                render_over_field(&ctx, &library, &s, &gpu_field, camera, (w, h), true).unwrap();
            (
                median_relative_error(&ours, &truth, mask),
                mean_ratio(&ours, &truth, mask),
            )
        };
        let (paper, paper_brightness) = figures(0);
        let (ours, brightness) = figures(scene.shading.field_light);
        eprintln!(
            "{name} {camera_name}: toy median error {ours:.3} with the field's light, {paper:.3} without; brightness {brightness:.3} and {paper_brightness:.3}"
        );
        assert!(
            ours <= paper + 0.005,
            "{camera_name}: {ours} against {paper}"
        );
        assert!(
            (brightness - 1.0).abs() < 0.1,
            "{camera_name}: brightness {brightness}"
        );
        best = best.max(paper - ours);
    }
    assert!(
        best > 0.05,
        "the field's light improved the toy by {best} at most"
    );
    common::assert_no_validation_errors(&ctx);
}
