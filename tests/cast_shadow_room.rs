//! The cast shadow's model against brute-force visibility on ROOM, where
//! Cycles showed its penumbra too faint: at 15 floor points of the band
//! right of and in front of the monkey (pixels of the front camera at
//! 320 × 180 that Cycles darkens below 0.9 and inlay did not), with the
//! probe's own fitted lobes and the monkey's SSDF at the scene's knobs,
//! ρ without the object's own light (`cast_shadow_factor` of an object
//! that reflects nothing) against the same lobes' light over 96²
//! cosine-weighted rays per point, each stopped or not by the monkey's
//! mesh. Ignored by default: it needs ROOM's full bake (minutes on first
//! use, then cached) — run it with
//! `cargo test --release --test cast_shadow_room -- --ignored`.

mod common;

use glam::DVec3;
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::GpuGridField;
use inlay_passes::geometry::{MeshScene, Ray};
use inlay_passes::march::march_ray;
use inlay_passes::shadow::{cast_shadow_factor, field_normal, FhTable, ObjectReflectance};
use inlay_passes::ssdf::OutsideMode;

/// The band's pixels (x, y) at 320 × 180.
const BAND: [(u32, u32); 15] = [
    (184, 131),
    (171, 138),
    (165, 137),
    (186, 128),
    (176, 134),
    (203, 95),
    (168, 139),
    (200, 137),
    (180, 131),
    (199, 130),
    (183, 134),
    (170, 135),
    (175, 139),
    (177, 132),
    (189, 137),
];

#[test]
#[ignore]
fn rooms_penumbra_darkens_as_brute_force_says() {
    let ctx = common::gpu();
    let scene = common::bundled_scene("room.toml");
    let field = inlay::field_source::scene_field(&scene, None, true, None).unwrap();
    let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
    let placed = scene.objects[0].clone();
    let (centre, _) = placed.sphere();
    // The lobes the frame lights the monkey with (the bulb is a local
    // light, shaded apart, and unblocked at these points).
    let (env, _) = inlay_passes::lighting::object_lights(&scene, centre, true);
    let traced = inlay::commands::probe::trace_and_fit(
        &ctx,
        &gpu_field,
        centre,
        scene.lighting.probe,
        scene.lighting.fit,
        scene.march,
        &env,
    )
    .unwrap();
    let lobes = &traced.lights;
    let ssdf = common::first_object_ssdf(&ctx, &gpu_field, &scene);
    let table = FhTable::new();
    let mesh = MeshScene::new(std::slice::from_ref(&placed));
    let black = ObjectReflectance {
        fill: 0.0,
        albedo: DVec3::ZERO,
    };
    let camera = CameraFrame::new(&scene.cameras[0], 320, 180);
    let (mut model, mut brute, mut worst) = (0.0, 0.0, 0.0f64);
    for (px, py) in BAND {
        let ray = camera.pixel_ray(px, py);
        let m = march_ray(&field, &ray, f64::INFINITY, &scene.march);
        let x = ray.at(m.depth / m.opacity);
        let n = field_normal(&field, x).expect("a floor point");
        let rho = cast_shadow_factor(
            &ssdf,
            &placed,
            &table,
            lobes,
            x,
            n,
            DVec3::ZERO,
            OutsideMode::Correct,
            None,
            &black,
        )
        .y;
        // Cosine-weighted rays: each carries π / N of the lobes' light.
        let (t, b) = n.any_orthonormal_pair();
        let side = 96;
        let (mut clear, mut all) = (0.0, 0.0);
        for i in 0..side {
            for j in 0..side {
                let u = (i as f64 + 0.5) / side as f64;
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / side as f64;
                let r = u.sqrt();
                let d =
                    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).sqrt()).normalize();
                let l: f64 = lobes.iter().map(|g| g.eval(d).y).sum();
                all += l;
                let shadow_ray = Ray {
                    origin: x + n * 0.01,
                    dir: d,
                };
                if mesh.intersect(&shadow_ray, 0.0, f64::INFINITY).is_none() {
                    clear += l;
                }
            }
        }
        let truth = clear / all;
        eprintln!("({px}, {py}): ρ model {rho:.3}, brute force {truth:.3}");
        model += 1.0 - rho;
        brute += 1.0 - truth;
        worst = worst.max((rho - truth).abs());
    }
    let k = BAND.len() as f64;
    eprintln!(
        "ROOM's penumbra, 15 points: darkening model {:.3}, brute force {:.3}, worst |Δρ| {:.3}",
        model / k,
        brute / k,
        worst
    );
    common::assert_no_validation_errors(&ctx);
    // Measured on lavapipe: darkening 0.627 against brute force's 0.634,
    // worst |Δρ| 0.037 (f_h's error on the broad lobes). With each lobe
    // weighted by its product with the cosine's one SG, as before the
    // fifteenth pass of docs/fidelity.md: 0.552, worst 0.118 — the
    // softbox's lobes, 34° above the floor, weighed 25 % light.
    assert!(
        (model / brute - 1.0).abs() < 0.06,
        "model / brute force {}",
        model / brute
    );
}
