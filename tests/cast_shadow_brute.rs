//! The cast shadow's model against brute force through the field, at every
//! pixel of the shadow (eighteenth pass of docs/fidelity.md). At each field
//! point a camera sees within 4 bounding radii of the object, at 320 × 180:
//! ρ of the model as the frame takes it (`cast_shadow_factor` of an object
//! that reflects nothing, with the light the frame assembles: the fitted
//! lobes of a probe the local lights are left out of, then each local
//! light, weighed by its light at the point and shadowed by rays to its
//! disk) against ρ of the light that reaches the point itself — 16²
//! cosine-weighted rays marched through the field from the point (light
//! past the field as the probe adds it), each cut where the object's mesh
//! crosses it, and every spherical emitter of the recipe sampled over its
//! disk through the field's transmittance (an emitter inside the field is
//! cut off the rays). The object's own light is in neither. Ignored by
//! default: it needs the full bakes (minutes on first use, then cached) —
//! run it with
//! `cargo test --release --test cast_shadow_brute -- --ignored --nocapture`;
//! with `CAST_SHADOW_BRUTE_OUT=DIR` each point's pixel, model and brute
//! force are written to `DIR/<scene>-<camera>.txt`.

mod common;

use glam::DVec3;
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::{GpuGridField, GridField};
use inlay_passes::geometry::{MeshScene, Ray};
use inlay_passes::lighting::direct_reference::direct_and_local_lights;
use inlay_passes::lighting::local::Emission;
use inlay_passes::lighting::sharp::lobe_rays;
use inlay_passes::lighting::LocalLight;
use inlay_passes::march::march_ray;
use inlay_passes::scene::{Scene, Shape};
use inlay_passes::sg::Sg64;
use inlay_passes::shadow::{
    cast_shadow_factor, field_normal, DirectOcclusion, FhTable, ObjectReflectance,
};
use inlay_passes::ssdf::OutsideMode;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Rays per side of the cosine-weighted hemisphere at each point.
const SIDE: usize = 16;
/// Rays per side over an emitter's disk.
const DISK_SIDE: usize = 8;

fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The nearest entry of the ray o + t·d (d unit) into a sphere, if ahead.
fn sphere_entry(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - r * r);
    let t = -b - disc.max(0.0).sqrt();
    (disc >= 0.0 && t > 0.0).then_some(t)
}

/// How far past an emitter's radius its light ends in the field: two
/// node spacings (trilinear interpolation spreads its nodes' density and
/// colour that far).
fn cut_margin(field: &GridField) -> f64 {
    2.0 * field.spacing().max_element()
}

/// A spherical emitter of the recipe.
#[derive(Clone, Copy)]
struct Emitter {
    centre: DVec3,
    radius: f64,
    luminance: f64,
    in_field: bool,
}

fn emitters(scene: &Scene) -> Vec<Emitter> {
    let recipe = scene.recipe().expect("a recipe scene");
    recipe
        .primitives
        .iter()
        .filter(|p| p.is_emitter())
        .filter_map(|p| match p.shape {
            Shape::Sphere { centre, radius } => Some(Emitter {
                centre,
                radius,
                luminance: luminance(p.emission),
                in_field: p.in_field == Some(true),
            }),
            _ => None,
        })
        .collect()
}

/// Cosine-weighted stratified directions about `n`: each carries π / N.
fn hemisphere(n: DVec3, side: usize) -> Vec<DVec3> {
    let (t, b) = n.any_orthonormal_pair();
    let mut dirs = Vec::with_capacity(side * side);
    for i in 0..side {
        for j in 0..side {
            let u = (i as f64 + 0.5) / side as f64;
            let phi = 2.0 * PI * (j as f64 + 0.5) / side as f64;
            let r = u.sqrt();
            dirs.push(
                (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).sqrt()).normalize(),
            );
        }
    }
    dirs
}

/// The light reaching `o` (normal `n`) without and with the object: the
/// field's along the hemisphere's rays, then each emitter's over its disk.
struct Light {
    field: (f64, f64),
    outside: (f64, f64),
}

fn light_at(
    field: &GridField,
    scene: &Scene,
    mesh: &MeshScene,
    env: &[Sg64],
    lights: &[Emitter],
    o: DVec3,
    n: DVec3,
) -> Light {
    let mut l = Light {
        field: (0.0, 0.0),
        outside: (0.0, 0.0),
    };
    let k = PI / (SIDE * SIDE) as f64;
    for d in hemisphere(n, SIDE) {
        let ray = Ray { origin: o, dir: d };
        let cut = lights
            .iter()
            .filter(|e| e.in_field)
            .filter_map(|e| sphere_entry(o, d, e.centre, e.radius + cut_margin(field)))
            .fold(f64::INFINITY, f64::min);
        let m = march_ray(field, &ray, cut, &scene.march);
        let past: DVec3 = if cut.is_finite() {
            DVec3::ZERO
        } else {
            env.iter().map(|g| g.eval(d)).sum()
        };
        let all = luminance(m.colour) + (1.0 - m.opacity) * luminance(past);
        let with = match mesh.intersect(&ray, 0.0, cut) {
            Some(hit) => luminance(march_ray(field, &ray, hit.t, &scene.march).colour),
            None => all,
        };
        l.field.0 += k * all;
        l.field.1 += k * with;
    }
    for e in lights {
        let to = e.centre - o;
        let dist = to.length();
        let axis = to / dist;
        let cos_max = (1.0 - (e.radius / dist).powi(2)).max(0.0).sqrt();
        let omega = 2.0 * PI * (1.0 - cos_max);
        let (ta, tb) = axis.any_orthonormal_pair();
        let slot = if e.in_field {
            &mut l.field
        } else {
            &mut l.outside
        };
        for i in 0..DISK_SIDE {
            for j in 0..DISK_SIDE {
                let u = (i as f64 + 0.5) / DISK_SIDE as f64;
                let phi = 2.0 * PI * (j as f64 + 0.5) / DISK_SIDE as f64;
                let ct = 1.0 - u * (1.0 - cos_max);
                let st = (1.0 - ct * ct).max(0.0).sqrt();
                let d = (ta * (st * phi.cos()) + tb * (st * phi.sin()) + axis * ct).normalize();
                let cos_n = d.dot(n);
                if cos_n <= 0.0 {
                    continue;
                }
                // The field's transmittance up to the emitter's blurred
                // shell (its nodes' density reaches past its radius).
                let margin = if e.in_field { cut_margin(field) } else { 0.0 };
                let t = sphere_entry(o, d, e.centre, e.radius + margin).unwrap_or(dist);
                let ray = Ray { origin: o, dir: d };
                let clear = 1.0 - march_ray(field, &ray, t, &scene.march).opacity;
                let light = e.luminance * clear * cos_n * omega / (DISK_SIDE * DISK_SIDE) as f64;
                slot.0 += light;
                if !mesh.occluded(&ray, 0.0, t) {
                    slot.1 += light;
                }
            }
        }
    }
    l
}

/// Figures over the shadow: (model ρ, brute-force ρ) at each point either
/// darkens below 0.985.
fn shadow_points(scene_file: &str, camera: usize) -> Vec<(u32, u32, f64, f64)> {
    let ctx = common::gpu();
    let scene = common::bundled_scene(scene_file);
    let field = inlay::field_source::scene_field(&scene, None, true, None).unwrap();
    let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
    let placed = scene.objects[0].clone();
    let (centre, radius) = placed.sphere();
    // The light as the frame assembles it: the fitted lobes of a probe
    // the local lights (the field's own emitters, a recipe's hidden
    // bulbs) are left out of, L_env's sharp lobes, then each local light
    // as the centre sees it.
    let (env, hidden) = inlay_passes::lighting::object_lights(&scene, centre, true);
    let local: Vec<LocalLight> = scene
        .lighting
        .local
        .choose(&gpu_field.emitters, &gpu_field.bounds)
        .into_iter()
        .chain(hidden)
        .collect();
    let side = scene.lighting.local.rays;
    let knobs = (scene.lighting.probe, scene.lighting.fit, scene.march);
    let traced = inlay::commands::probe::trace_and_fit_with_local(
        &ctx, &gpu_field, centre, knobs, &env, &local, side,
    )
    .unwrap();
    let lobes = traced.lights.clone();
    let rays: Vec<Vec<DVec3>> = traced.lights[traced.report.lobes.len()..lobes.len() - local.len()]
        .iter()
        .map(|g| lobe_rays(g, scene.lighting.probe.supersampling))
        .collect();
    let (_, emissions) =
        direct_and_local_lights(&field, centre, &[], &[], 1, &local, side, &scene.march);
    let local_emitting: Vec<(LocalLight, Emission)> = local
        .iter()
        .zip(emissions)
        .map(|(l, e)| {
            let e = e.unwrap_or(Emission {
                intensity: DVec3::ZERO,
                radius: l.radius,
            });
            (*l, e)
        })
        .collect();
    let object_scene = inlay_passes::ssdf::object_scene(&placed.mesh);
    let occlusion = DirectOcclusion {
        scene: &object_scene,
        rays: &rays,
        local: &local_emitting,
        local_side: side,
        field: Some((&field, scene.march)),
    };
    let ssdf = common::first_object_ssdf(&ctx, &gpu_field, &scene);
    common::assert_no_validation_errors(&ctx);
    let table = FhTable::new();
    let mesh = MeshScene::new(std::slice::from_ref(&placed));
    let black = ObjectReflectance {
        fill: 0.0,
        albedo: DVec3::ZERO,
    };
    let lights = emitters(&scene);
    let view = CameraFrame::new(&scene.cameras[camera], 320, 180);
    let pixels: Vec<(u32, u32)> = (0..180)
        .flat_map(|y| (0..320).map(move |x| (x, y)))
        .collect();
    pixels
        .par_iter()
        .filter_map(|&(px, py)| {
            let ray = view.pixel_ray(px, py);
            let m = march_ray(&field, &ray, f64::INFINITY, &scene.march);
            if m.opacity < 0.5 {
                return None;
            }
            let depth = m.depth / m.opacity;
            if mesh.intersect(&ray, 0.0, depth).is_some() {
                return None;
            }
            let x = ray.at(depth);
            if (x - centre).length() > 4.0 * radius {
                return None;
            }
            let n = field_normal(&field, x)?;
            let o = x + n * 0.01;
            let l = light_at(&field, &scene, &mesh, &env, &lights, o, n);
            let total = l.field.0 + l.outside.0;
            if total <= 0.0 {
                return None; // a point the rays leave in the dark (a box's inside)
            }
            let brute = (l.field.1 + l.outside.1) / total;
            let model = luminance(cast_shadow_factor(
                &ssdf,
                &placed,
                &table,
                &lobes,
                x,
                n,
                m.colour,
                OutsideMode::Correct,
                (!local.is_empty() || !rays.is_empty()).then_some(occlusion),
                &black,
            ));
            (brute < 0.985 || model < 0.985).then_some((px, py, model, brute))
        })
        .collect()
}

/// Prints the figures; returns (total darkening model / brute force, mean
/// |Δρ|, area below 0.9 model / brute force).
fn report(name: &str, pixels: &[(u32, u32, f64, f64)]) -> (f64, f64, f64) {
    if let Ok(dir) = std::env::var("CAST_SHADOW_BRUTE_OUT") {
        let text: String = pixels
            .iter()
            .map(|(x, y, m, b)| format!("{x} {y} {m:.5} {b:.5}\n"))
            .collect();
        let path = std::path::Path::new(&dir).join(format!("{name}.txt"));
        std::fs::write(&path, text).unwrap();
    }
    let points: Vec<(f64, f64)> = pixels.iter().map(|p| (p.2, p.3)).collect();
    let dark =
        |f: fn(&(f64, f64)) -> f64| points.iter().map(|p| (1.0 - f(p)).max(0.0)).sum::<f64>();
    let ratio = dark(|p| p.0) / dark(|p| p.1);
    let mean_diff = points.iter().map(|p| (p.0 - p.1).abs()).sum::<f64>() / points.len() as f64;
    let below = |f: fn(&(f64, f64)) -> f64| points.iter().filter(|p| f(p) < 0.9).count() as f64;
    let area = below(|p| p.0) / below(|p| p.1).max(1.0);
    eprintln!(
        "{name}: {} points; total darkening model / brute force {ratio:.3}; mean |Δρ| {mean_diff:.3}; area below 0.9 {area:.2}",
        points.len()
    );
    for (lo, hi) in [
        (0.0, 0.5),
        (0.5, 0.7),
        (0.7, 0.85),
        (0.85, 0.95),
        (0.95, 2.0),
    ] {
        let bin: Vec<_> = points.iter().filter(|p| p.1 >= lo && p.1 < hi).collect();
        if !bin.is_empty() {
            let k = bin.len() as f64;
            eprintln!(
                "  brute force in [{lo:.2}, {hi:.2}): {} points, brute force {:.3}, model {:.3}",
                bin.len(),
                bin.iter().map(|p| p.1).sum::<f64>() / k,
                bin.iter().map(|p| p.0).sum::<f64>() / k
            );
        }
    }
    (ratio, mean_diff, area)
}

#[test]
#[ignore]
fn the_model_darkens_the_floor_as_its_light_says() {
    // ROOM: the bulb overhead and the softbox on the wall are local
    // lights, weighed at each point; the walls' light at the monkey's
    // centre is what its floor receives. Measured on lavapipe (the 2-core
    // machine): total darkening 1.010 of brute force's, mean |Δρ| 0.013,
    // area below 0.9 1.00. With the softbox among the fitted lobes (seen
    // from the centre, 0.2 m above the floor and nearer the softbox), the
    // floor beside the monkey lost 0.42 of its light where it loses 0.31:
    // 0.971, 0.016 and 1.09.
    let (ratio, mean_diff, area) = report("room-front", &shadow_points("room.toml", 0));
    assert!(
        (ratio - 1.0).abs() < 0.1,
        "ROOM: total darkening model / brute force {ratio}"
    );
    assert!(mean_diff < 0.04, "ROOM: mean |Δρ| {mean_diff}");
    assert!(
        (area - 1.0).abs() < 0.05,
        "ROOM: area below 0.9, model / brute force {area}"
    );
    // PLANTS' high view: the lamp reaches the toy's centre through the
    // left plant's foliage and the floor around the shadow in the open.
    // With the lamp weighed at the object's centre the model's shadow
    // covered 1.14× brute force's area below 0.9 (a ring too dark); with
    // it weighed at each point, 1.05 (total darkening 0.932, mean |Δρ|
    // 0.053: the umbra, lit by less of the room than the centre is, stays
    // too light; 1.06 and 0.943 before the fit's staged solve, issue 26,
    // rounded it elsewhere).
    let (ratio, _, area) = report("plants-high", &shadow_points("plants.toml", 1));
    assert!(
        (area - 1.0).abs() < 0.1,
        "PLANTS: area below 0.9, model / brute force {area}"
    );
    assert!(
        (ratio - 1.0).abs() < 0.1,
        "PLANTS: total darkening model / brute force {ratio}"
    );
}
