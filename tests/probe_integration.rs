//! The probe integrates its texels: each holds the mean radiance over its
//! solid angle, so a light smaller than a texel keeps its energy wherever it
//! falls, and the probe does not flicker as the object slides by fractions
//! of a texel. Checked against closed forms (an SG lobe's sphere integral)
//! and against a dense quadrature of the same field over the light's cone,
//! which shares nothing with the probe's map or sub-samples.

mod common;

use std::f64::consts::PI;

use glam::{DVec3, UVec3};
use inlay_engine::{ImageDesc, Readback};
use inlay_passes::field::{GpuGridField, GridField, RadianceField};
use inlay_passes::geometry::{Aabb, Ray};
use inlay_passes::march::{march_ray, MarchKnobs};
use inlay_passes::probe::{
    trace_probe, DirectionMap, MapKind, ProbeKnobs, ProbePass, PROBE_FORMAT,
};
use inlay_passes::sg::Sg64;
use inlay_passes::shaders::embedded_library;

fn march() -> MarchKnobs {
    MarchKnobs {
        samples_per_ray: 1024,
        ..MarchKnobs::default()
    }
}

/// Σ_t L_t Ω_t: the probe's energy ∫ L dω (rgb summed).
fn probe_energy(map: &DirectionMap, texels: &[[f64; 4]]) -> f64 {
    texels
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (x, y) = (i as u32 % map.width, i as u32 / map.width);
            (t[0] + t[1] + t[2]) * map.solid_angle(x, y)
        })
        .sum()
}

/// A field with nothing in it.
fn empty_field() -> GridField {
    GridField::new(
        UVec3::splat(2),
        Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
        vec![[0.0; 4]; 8],
        1,
    )
}

/// A 48³ field over [−1, 1]³ holding one emitting sphere of `radius` at
/// `centre` with radiance `radiance` (grey), its density built as the bake
/// builds a surface's: 40/voxel inside, a smooth edge 1.5 voxels wide.
fn sphere_light(centre: DVec3, radius: f64, radiance: f64) -> GridField {
    let n = 48u32;
    let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    let voxel = 2.0 / (n - 1) as f64;
    let width = 1.5 * voxel;
    let mut nodes = Vec::with_capacity((n * n * n) as usize);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = DVec3::new(i as f64, j as f64, k as f64) * voxel - DVec3::ONE;
                let d = (p - centre).length() - radius;
                let sigma = 40.0 / voxel * inlay_passes::bake::edge_profile(d / width);
                let c = if d <= width + voxel { radiance } else { 0.0 };
                nodes.push([c as f32, c as f32, c as f32, sigma as f32]);
            }
        }
    }
    GridField::new(UVec3::splat(n), bounds, nodes, 4)
}

/// ∫ Ĉ dω (rgb summed) over the cone around the light seen from `origin`,
/// by a dense midpoint rule in (cos θ, φ) about the light's direction: the
/// truth the probe must keep, from the same field and march.
fn cone_energy(field: &dyn RadianceField, origin: DVec3, centre: DVec3, outer: f64) -> f64 {
    let axis = (centre - origin).normalize();
    let dist = (centre - origin).length();
    let half = (outer / dist).min(0.99).asin() * 1.1;
    let (t, b) = axis.any_orthonormal_pair();
    let (nc, np) = (160, 160);
    let cos_lo = half.cos();
    let mut sum = 0.0;
    for a in 0..nc {
        let c = 1.0 - (1.0 - cos_lo) * (a as f64 + 0.5) / nc as f64;
        let s = (1.0 - c * c).sqrt();
        for p in 0..np {
            let phi = 2.0 * PI * (p as f64 + 0.5) / np as f64;
            let dir = axis * c + (t * phi.cos() + b * phi.sin()) * s;
            let r = march_ray(field, &Ray { origin, dir }, f64::INFINITY, &march());
            sum += r.colour.element_sum();
        }
    }
    sum * 2.0 * PI * (1.0 - cos_lo) / (nc * np) as f64
}

fn knobs(map: MapKind, resolution: u32, supersampling: u32) -> ProbeKnobs {
    ProbeKnobs {
        map,
        resolution,
        supersampling,
        stride: 1,
    }
}

/// A needle lobe (a bulb's λ up to 10⁵) anywhere on the sphere keeps its
/// energy in the probe within 2 %; a point-sampled probe (one ray per texel
/// centre, the lobe unblurred) keeps anything from almost none of it to
/// several times it.
#[test]
fn environment_lobes_of_any_sharpness_keep_their_energy() {
    let field = empty_field();
    let mut worst: f64 = 0.0;
    let mut point_range = (f64::MAX, 0.0f64);
    for (map, n, s) in [
        (MapKind::Octahedral, 32, 4),
        (MapKind::Octahedral, 16, 2),
        (MapKind::Equirect, 16, 4),
    ] {
        let k = knobs(map, n, s);
        let dirs = k.direction_map();
        for (i, sharpness) in [2.0, 50.0, 1e3, 1e4, 8e4].into_iter().enumerate() {
            for j in 0..5 {
                // Directions spread over the sphere, none on a texel centre.
                let a = inlay_passes::sgfit::fibonacci_axis(7 * i as u32 + j, 37);
                let lobe = Sg64 {
                    direction: a,
                    sharpness,
                    amplitude: DVec3::new(3.0, 2.0, 1.0) * sharpness,
                };
                let truth = lobe.integral().element_sum();
                let got = probe_energy(
                    &dirs,
                    &trace_probe(&field, DVec3::ZERO, &k, &march(), &[lobe]),
                );
                let err = (got / truth - 1.0).abs();
                worst = worst.max(err);
                assert!(
                    err < 0.02,
                    "{map:?} {n} s={s}: lobe λ={sharpness} along {a}: probe energy {got:.5e} against {truth:.5e}"
                );
                if sharpness >= 1e4 {
                    // The old probe: the raw lobe at texel centres.
                    let point: f64 = (0..dirs.texels() as u32)
                        .map(|t| {
                            let (x, y) = (t % dirs.width, t / dirs.width);
                            lobe.eval(dirs.direction(x, y)).element_sum() * dirs.solid_angle(x, y)
                        })
                        .sum();
                    let f = point / truth;
                    point_range = (point_range.0.min(f), point_range.1.max(f));
                }
            }
        }
    }
    eprintln!(
        "worst energy error {:.3} %; point-sampled needles kept {:.4}..{:.2} of their energy",
        100.0 * worst,
        point_range.0,
        point_range.1
    );
}

/// Emitting spheres from 1.5 to 8 voxels in radius, at several distances
/// and directions: the probe's energy matches the dense quadrature of the
/// same field within 2 %.
#[test]
fn a_sphere_light_in_the_field_keeps_its_energy() {
    let k = ProbeKnobs::default();
    let dirs = k.direction_map();
    let voxel = 2.0 / 47.0;
    for (radius_voxels, centre, origin) in [
        (1.5, DVec3::new(0.6, 0.7, -0.3), DVec3::new(-0.2, -0.3, 0.1)),
        (
            2.5,
            DVec3::new(-0.5, 0.4, 0.55),
            DVec3::new(0.3, -0.2, -0.4),
        ),
        (4.0, DVec3::new(0.2, 0.75, 0.1), DVec3::new(0.0, -0.6, 0.0)),
        (8.0, DVec3::new(-0.4, -0.3, 0.3), DVec3::new(0.5, 0.4, -0.2)),
    ] {
        let radius = radius_voxels * voxel;
        let field = sphere_light(centre, radius, 50.0);
        let truth = cone_energy(&field, origin, centre, radius + 3.0 * voxel);
        let got = probe_energy(&dirs, &trace_probe(&field, origin, &k, &march(), &[]));
        let err = got / truth - 1.0;
        eprintln!("sphere light of {radius_voxels} voxels at {centre}: probe {got:.5} against quadrature {truth:.5} ({:+.2} %)", 100.0 * err);
        assert!(
            err.abs() < 0.02,
            "sphere of {radius_voxels} voxels: {got} against {truth}"
        );
    }
}

/// The probe at the default knobs, on the GPU, as the object slides past a
/// small light (0.07 rad across, under a texel's 0.11) in steps of an
/// eighth of a texel: its energy relative to the quadrature truth at each
/// position varies by at most 1 %. Measured on lavapipe, the spread is
/// 9.6 % with one ray per texel, 2.0 % with 4 × 4, 0.56 % with 6 × 6 (the
/// default) and 0.09 % with 8 × 8.
#[test]
fn the_probe_does_not_flicker_as_the_object_slides() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let k = ProbeKnobs::default();
    let dirs = k.direction_map();
    let voxel = 2.0 / 47.0;
    let (centre, radius) = (DVec3::new(0.1, 0.7, 0.05), 2.0 * voxel);
    let field = sphere_light(centre, radius, 50.0);
    let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
    let pass = ProbePass::new(&ctx, &lib, k, march(), &[], &[]).unwrap();
    let rb = Readback::new(
        &ctx,
        ImageDesc {
            width: dirs.width,
            height: dirs.height,
            format: PROBE_FORMAT,
        },
    )
    .unwrap();
    // A texel is about √(4π/1024) ≈ 0.11 rad; the light is 1.1 away.
    let start = DVec3::new(-0.1, -0.4, 0.0);
    let texel = (4.0 * PI / dirs.texels() as f64).sqrt();
    let (mut lo, mut hi) = (f64::MAX, 0.0f64);
    for step in 0..=8 {
        let origin = start + DVec3::X * (step as f64 / 8.0) * texel * 1.1;
        common::run_frame(&ctx, |graph| {
            let probe = pass.add(graph, &gpu_field, origin);
            rb.add_to_graph(graph, probe);
        });
        let img = rb.read().unwrap();
        let texels: Vec<[f64; 4]> = img.pixels.iter().map(|p| p.map(f64::from)).collect();
        let ratio = probe_energy(&dirs, &texels)
            / cone_energy(&field, origin, centre, radius + 3.0 * voxel);
        lo = lo.min(ratio);
        hi = hi.max(ratio);
    }
    eprintln!("probe energy / truth as the object slides one texel: {lo:.4}..{hi:.4}");
    assert!(hi / lo - 1.0 <= 0.01, "flicker {lo}..{hi}");
    assert!(
        (lo - 1.0).abs() < 0.02 && (hi - 1.0).abs() < 0.02,
        "{lo}..{hi}"
    );
    common::assert_no_validation_errors(&ctx);
}

/// The lobes fitted to the probe (f64 reference fit, the default knobs)
/// hand shading the irradiance the probe holds: small sphere lights in the
/// field and a needle environment lobe keep it within 3 % (measured 0.6 to
/// 0.9 % under). With the probe read unfiltered and the sharpness capped
/// only at the texel count (the fit before this), a needle came out at 0.61
/// of its irradiance and a 1.5-voxel light at 1.24; with the filter and the
/// cap but without the energy step, 1.016 to 1.057.
#[test]
fn the_fitted_lobes_keep_a_small_lights_irradiance() {
    use inlay_passes::probe::{lobes_irradiance, probe_irradiance};
    use inlay_passes::sgfit::{fit_reference, FitKnobs, ProbeSamples, Start};
    let k = ProbeKnobs::default();
    let dirs = k.direction_map();
    let voxel = 2.0 / 47.0;
    let fit_knobs = FitKnobs::default();
    let check = |texels: &[[f64; 4]], n: DVec3, what: &str| {
        let probe = probe_irradiance(&dirs, texels, n).x;
        let fit = fit_reference(
            &ProbeSamples::new(&dirs, texels),
            &fit_knobs,
            Start::Cold,
            40,
        );
        let lobes = lobes_irradiance(&fit.lobes, n).x;
        eprintln!(
            "{what}: probe E {probe:.4}, lobes E {lobes:.4} ({:+.1} %)",
            100.0 * (lobes / probe - 1.0)
        );
        assert!(
            (lobes / probe - 1.0).abs() < 0.03,
            "{what}: {lobes} against {probe}"
        );
    };
    for (radius_voxels, centre, origin) in [
        (1.5, DVec3::new(0.6, 0.7, -0.3), DVec3::new(-0.2, -0.3, 0.1)),
        (
            2.5,
            DVec3::new(-0.5, 0.4, 0.55),
            DVec3::new(0.3, -0.2, -0.4),
        ),
    ] {
        let field = sphere_light(centre, radius_voxels * voxel, 50.0);
        let texels = trace_probe(&field, origin, &k, &march(), &[]);
        check(
            &texels,
            (centre - origin).normalize(),
            &format!("{radius_voxels}-voxel light"),
        );
    }
    let needle = Sg64 {
        direction: DVec3::new(0.5, 0.7, 0.3).normalize(),
        sharpness: 1e4,
        amplitude: DVec3::splat(1e4),
    };
    let sky = Sg64 {
        direction: DVec3::Y,
        sharpness: 2.0,
        amplitude: DVec3::splat(0.1),
    };
    let texels = trace_probe(&empty_field(), DVec3::ZERO, &k, &march(), &[needle, sky]);
    check(&texels, DVec3::Y, "needle lobe and sky");
}
