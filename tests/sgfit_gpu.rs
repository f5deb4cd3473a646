//! The Levenberg–Marquardt SG fit on the GPU (lavapipe) against its f64 CPU
//! reference on the same probe, and at the extremes: black, uniform, one
//! tiny source 10⁵ × brighter, NaN/Inf texels, lobes driven to the sharpness
//! limits, and a warm start after the object jumps.

mod common;

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::{vk, Context, Image, ImageDesc};
use inlay_passes::probe::{DirectionMap, MapKind, PROBE_FORMAT};
use inlay_passes::sg::{Sg32, Sg64};
use inlay_passes::sgfit::model::{self, MAX_SHARPNESS, MIN_SHARPNESS};
use inlay_passes::sgfit::{
    fit_reference, FitKnobs, FitReport, FitStart, ProbeSamples, SgFitPass, Start,
};
use inlay_passes::shaders::embedded_library;

fn sky_and_sun() -> Vec<Sg64> {
    vec![
        Sg64 {
            direction: DVec3::new(0.3, 1.0, 0.2).normalize(),
            sharpness: 60.0,
            amplitude: DVec3::new(50.0, 45.0, 40.0),
        },
        Sg64 {
            direction: DVec3::Y,
            sharpness: 1.5,
            amplitude: DVec3::new(0.3, 0.5, 0.9),
        },
        Sg64 {
            direction: DVec3::new(-1.0, -0.2, 0.4).normalize(),
            sharpness: 8.0,
            amplitude: DVec3::new(2.0, 1.0, 0.5),
        },
    ]
}

/// Texels of a probe holding `lobes`, with `edit` applied per texel.
fn texels_of(
    map: &DirectionMap,
    lobes: &[Sg64],
    edit: impl Fn(usize, [f32; 4]) -> [f32; 4],
) -> Vec<[f32; 4]> {
    (0..map.texels())
        .map(|i| {
            let d = map.direction(i as u32 % map.width, i as u32 / map.width);
            let l = model::model(lobes, d);
            edit(i, [l.x as f32, l.y as f32, l.z as f32, 1.0])
        })
        .collect()
}

fn samples_of(map: &DirectionMap, texels: &[[f32; 4]]) -> ProbeSamples {
    let t: Vec<[f64; 4]> = texels.iter().map(|t| t.map(|v| v as f64)).collect();
    ProbeSamples::new(map, &t)
}

fn probe_image(ctx: &Arc<Context>, map: &DirectionMap, texels: &[[f32; 4]]) -> Arc<Image> {
    let image = Image::new(
        ctx,
        "test-probe",
        ImageDesc {
            width: map.width,
            height: map.height,
            format: PROBE_FORMAT,
        },
        vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::TRANSFER_DST,
    )
    .unwrap();
    image.write_rgba32f(texels).unwrap();
    Arc::new(image)
}

/// Runs one GPU fit of `texels` and reads its report.
fn gpu_fit(
    ctx: &Arc<Context>,
    fit: &SgFitPass,
    map: &DirectionMap,
    texels: &[[f32; 4]],
    start: FitStart,
    iterations: u32,
) -> FitReport {
    let image = probe_image(ctx, map, texels);
    common::run_frame(ctx, |graph| {
        let probe = graph.import_image(&image, "probe", None);
        fit.add(graph, probe, start, iterations).unwrap();
        fit.add_readback(graph);
    });
    fit.read_report().unwrap()
}

/// Every number that leaves the fit is finite and every lobe is legal.
fn assert_sane(what: &str, r: &FitReport) {
    assert!(
        r.costs.iter().all(|c| c.is_finite() && *c >= 0.0),
        "{what}: costs {:?}",
        r.costs
    );
    assert!(
        r.energy.is_finite() && r.damping.is_finite(),
        "{what}: {r:?}"
    );
    for g in &r.lobes {
        assert!(
            g.direction.is_finite() && (g.direction.length() - 1.0).abs() < 1e-4,
            "{what}: axis {g:?}"
        );
        assert!(
            g.sharpness.is_finite()
                && g.sharpness >= (MIN_SHARPNESS as f32) * 0.999
                && g.sharpness <= (MAX_SHARPNESS as f32) * 1.001,
            "{what}: sharpness {g:?}"
        );
        assert!(
            g.amplitude.is_finite() && g.amplitude.min_element() >= 0.0,
            "{what}: amplitude {g:?}"
        );
    }
    // Costs never rise: rejected steps keep the lobes.
    assert!(
        r.costs.windows(2).all(|w| w[1] <= w[0]),
        "{what}: {:?}",
        r.costs
    );
}

#[test]
fn gpu_fit_reaches_the_cpu_residual() {
    let ctx = common::gpu();
    let lib = embedded_library();
    for (kind, n) in [(MapKind::Octahedral, 24), (MapKind::Equirect, 16)] {
        let map = DirectionMap::new(kind, n);
        let knobs = FitKnobs {
            lobes: 8,
            ..FitKnobs::default()
        };
        let fit = SgFitPass::new(&ctx, &lib, knobs, map).unwrap();
        let texels = texels_of(&map, &sky_and_sun(), |_, t| t);
        let gpu = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 30);
        let cpu = fit_reference(&samples_of(&map, &texels), &knobs, Start::Cold, 30);
        assert_sane("sky and sun", &gpu);
        // Same start: the cold starts agree to f32 precision.
        let (g0, c0) = (gpu.costs[0], cpu.costs[0]);
        assert!(
            (g0 - c0).abs() <= 1e-4 * c0,
            "{kind:?}: cold-start cost GPU {g0} vs CPU {c0}"
        );
        let (g, c) = (gpu.relative_residual(), cpu.relative_residual());
        eprintln!(
            "{kind:?} {n}: relative residual GPU {g:.5} (accepted {}), CPU {c:.5} (accepted {})",
            gpu.accepted, cpu.accepted
        );
        // f32 normal equations take slightly different steps; both must
        // reach a good fit, the GPU within 1.5× (+1 %) of the CPU. (The fit
        // sees the probe filtered, sgfit/probe_filter.rs: on this small
        // equirect map the filter moves a constant by up to 2.5 % near the
        // poles, which no sum of lobes follows; the CPU reaches 0.058.)
        assert!(c < 0.07, "{kind:?}: CPU residual {c}");
        // The last step sets the amplitudes to hold the probe's energy
        // (sgfit/energy.rs): on the GPU too, to f32 precision.
        let samples = samples_of(&map, &texels);
        let energy: DVec3 = samples
            .weights
            .iter()
            .zip(&samples.radiance)
            .map(|(w, l)| *w * *l)
            .sum();
        let held: DVec3 = gpu.lobes.iter().map(|g| g.to_f64().integral()).sum();
        assert!(
            (held / energy - DVec3::ONE).abs().max_element() < 1e-3,
            "{kind:?}: the GPU lobes hold {held}, the probe {energy}"
        );
        assert!(g <= 1.5 * c + 0.01, "{kind:?}: GPU residual {g} vs CPU {c}");
    }
}

fn small_fit(ctx: &Arc<Context>) -> (SgFitPass, DirectionMap) {
    let map = DirectionMap::new(MapKind::Octahedral, 16);
    let knobs = FitKnobs {
        lobes: 8,
        ..FitKnobs::default()
    };
    (
        SgFitPass::new(ctx, &embedded_library(), knobs, map).unwrap(),
        map,
    )
}

#[test]
fn black_and_uniform_probes() {
    let ctx = common::gpu();
    let (fit, map) = small_fit(&ctx);
    let black = vec![[0.0f32; 4]; map.texels()];
    // A warm start before any fit begins from legal, dark lobes.
    let r = gpu_fit(&ctx, &fit, &map, &black, FitStart::Warm, 3);
    assert_sane("black, warm before any fit", &r);
    assert!(
        !r.started_cold,
        "nothing beats the dark lobes on a black probe"
    );
    let r = gpu_fit(&ctx, &fit, &map, &black, FitStart::Cold, 10);
    assert_sane("black", &r);
    assert_eq!(r.relative_residual(), 0.0);
    assert!(r.lobes.iter().all(|g| g.amplitude == glam::Vec3::ZERO));
    let uniform = vec![[2.0f32, 1.0, 0.5, 1.0]; map.texels()];
    let r = gpu_fit(&ctx, &fit, &map, &uniform, FitStart::Cold, 20);
    assert_sane("uniform", &r);
    assert!(
        r.relative_residual() < 0.05,
        "uniform: {}",
        r.relative_residual()
    );
}

#[test]
fn one_tiny_source_a_hundred_thousand_times_brighter() {
    let ctx = common::gpu();
    let (fit, map) = small_fit(&ctx);
    let source = DVec3::new(0.5, 0.2, -0.7).normalize();
    let (x, y) = map.texel_of(source);
    let bright = (y * map.width + x) as usize;
    let sky = &sky_and_sun()[1..];
    let texels = texels_of(&map, sky, |i, t| {
        if i == bright {
            [1e5, 1e5, 1e5, 1.0]
        } else {
            t
        }
    });
    let r = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 30);
    assert_sane("tiny source", &r);
    let cpu = fit_reference(&samples_of(&map, &texels), fit.knobs(), Start::Cold, 30);
    eprintln!(
        "tiny source: GPU {:.4}, CPU {:.4}",
        r.relative_residual(),
        cpu.relative_residual()
    );
    assert!(r.relative_residual() < 0.2, "{}", r.relative_residual());
    // The brightest lobe sits on the source.
    let brightest = r
        .lobes
        .iter()
        .max_by(|a, b| a.amplitude.x.total_cmp(&b.amplitude.x))
        .unwrap();
    let texel_dir = map.direction(x, y);
    assert!(
        brightest.direction.as_dvec3().dot(texel_dir) > 0.99,
        "{brightest:?}"
    );
}

#[test]
fn nan_and_inf_texels_are_ignored_and_counted() {
    let ctx = common::gpu();
    let (fit, map) = small_fit(&ctx);
    let bad = [3usize, 40, 41, 100, 200];
    let values = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, f32::NAN];
    let texels = texels_of(&map, &sky_and_sun(), |i, mut t| {
        if let Some(j) = bad.iter().position(|&b| b == i) {
            t[j % 3] = values[j];
        }
        t
    });
    let r = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 20);
    assert_sane("NaN/Inf texels", &r);
    assert_eq!(r.invalid, bad.len() as u32);
    let cpu = fit_reference(&samples_of(&map, &texels), fit.knobs(), Start::Cold, 20);
    assert_eq!(cpu.invalid, bad.len());
    assert!(r.relative_residual() < 0.05, "{}", r.relative_residual());
}

#[test]
fn warm_starts_from_extreme_lobes_and_after_a_jump() {
    let ctx = common::gpu();
    let (mut fit, map) = small_fit(&ctx);
    let texels = texels_of(&map, &sky_and_sun(), |_, t| t);
    // Lobes at the sharpness limits with huge amplitudes as the "previous
    // frame": the fit must stay finite (and the cold start wins).
    let extreme: Vec<_> = (0..8)
        .map(|k| {
            Sg64 {
                direction: model::fibonacci_axis(k, 8),
                sharpness: if k % 2 == 0 {
                    MAX_SHARPNESS
                } else {
                    MIN_SHARPNESS
                },
                amplitude: DVec3::splat(1e6),
            }
            .to_f32()
        })
        .collect();
    fit.set_lobes(&ctx, &extreme).unwrap();
    let r = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Warm, 10);
    assert_sane("extreme warm start", &r);
    assert!(r.started_cold, "the cold start fits better than 1e6 lobes");
    // A converged fit, then a small move: the warm start is kept.
    let r = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 30);
    let moved = texels_of(&map, &sky_and_sun(), |_, t| {
        [t[0] * 1.05, t[1] * 1.05, t[2] * 1.05, 1.0]
    });
    let warm = gpu_fit(&ctx, &fit, &map, &moved, FitStart::Warm, 4);
    assert_sane("small move", &warm);
    assert!(!warm.started_cold);
    // Where the f64 reference goes from the same lobes, and far better than
    // the same iterations from the cold start.
    let prev: Vec<Sg64> = r.iterate.iter().map(|g| g.to_f64()).collect();
    let moved_samples = samples_of(&map, &moved);
    let cpu = fit_reference(&moved_samples, fit.knobs(), Start::Warm(&prev), 4);
    let cold = fit_reference(&moved_samples, fit.knobs(), Start::Cold, 4);
    assert!(
        warm.relative_residual() < 1.1 * cpu.relative_residual() + 0.002
            && warm.relative_residual() < 0.5 * cold.relative_residual(),
        "warm {} ({:?}), the reference {} ({:?}), cold {}",
        warm.relative_residual(),
        warm.costs,
        cpu.relative_residual(),
        cpu.costs,
        cold.relative_residual()
    );
    // The object jumps: the sun is now below and elsewhere.
    let mut jumped = sky_and_sun();
    jumped[0].direction = DVec3::new(-0.2, -0.9, 0.4).normalize();
    jumped[0].sharpness = 300.0;
    let texels = texels_of(&map, &jumped, |_, t| t);
    let warm = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Warm, 30);
    assert_sane("jump", &warm);
    let cold = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 30);
    eprintln!(
        "jump: warm start {:.4} (cold chosen: {}), cold start {:.4}",
        warm.relative_residual(),
        warm.started_cold,
        cold.relative_residual()
    );
    assert!(warm.relative_residual() <= 1.5 * cold.relative_residual() + 0.02);
}

/// More parameters than the solver's 256 invocations (M = 64: 384) and
/// between (M = 40: 240): the GPU's first iterations take the f64
/// reference's steps (each cost within 0.1 %; a wrong step, or one
/// rejected where the reference accepts it, is off by far more). A
/// left-looking solver that read a row another invocation was still
/// writing passed at M ≤ 32 and failed here.
#[test]
fn many_lobes_take_the_reference_steps() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let map = DirectionMap::new(MapKind::Octahedral, 32);
    let texels = texels_of(&map, &sky_and_sun(), |i, t| {
        let (a, b) = ((i * 7) % 13, (i * 3) % 5);
        [t[0] + 0.1 * a as f32, t[1], t[2] + 0.05 * b as f32, 1.0]
    });
    for m in [40u32, 64] {
        let knobs = FitKnobs {
            lobes: m,
            ..FitKnobs::default()
        };
        let fit = SgFitPass::new(&ctx, &lib, knobs, map).unwrap();
        let gpu = gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 4);
        let cpu = fit_reference(&samples_of(&map, &texels), &knobs, Start::Cold, 4);
        assert!(cpu.costs[4] < 0.1 * cpu.costs[0], "{:?}", cpu.costs);
        for (g, c) in gpu.costs.iter().zip(&cpu.costs) {
            assert!(
                (g / c - 1.0).abs() < 1e-3,
                "M = {m}: {:?} vs {:?}",
                gpu.costs,
                cpu.costs
            );
        }
    }
}

/// A warm update spread over frames (2 iterations, then the fit continued
/// three times) ends on the lobes of the same update run whole: the same
/// iterate and the same shading lobes, up to f32 rounding (measured equal).
#[test]
fn a_fit_spread_over_frames_reaches_the_same_lobes() {
    let ctx = common::gpu();
    let (fit, map) = small_fit(&ctx);
    let texels = texels_of(&map, &sky_and_sun(), |_, t| t);
    let moved = texels_of(&map, &sky_and_sun(), |i, t| {
        [t[0] * 1.1, t[1] * (1.0 + 0.01 * (i % 7) as f32), t[2], 1.0]
    });
    let run = |chunks: &[u32]| {
        gpu_fit(&ctx, &fit, &map, &texels, FitStart::Cold, 12);
        let mut r = gpu_fit(&ctx, &fit, &map, &moved, FitStart::Warm, chunks[0]);
        for &n in &chunks[1..] {
            r = gpu_fit(&ctx, &fit, &map, &moved, FitStart::Continue, n);
        }
        r
    };
    let whole = run(&[8]);
    let spread = run(&[2, 2, 2, 2]);
    assert!(!whole.started_cold && whole.accepted >= 2, "{whole:?}");
    assert_eq!(spread.accepted, whole.accepted);
    assert_eq!(spread.costs.len(), whole.costs.len());
    let close = |a: &[Sg32], b: &[Sg32]| {
        a.iter().zip(b).all(|(x, y)| {
            (x.direction - y.direction).length() < 1e-5
                && (x.sharpness / y.sharpness - 1.0).abs() < 1e-5
                && (x.amplitude - y.amplitude).abs().max_element()
                    <= 1e-5 * y.amplitude.max_element().max(1e-3)
        })
    };
    assert!(
        close(&spread.iterate, &whole.iterate),
        "{spread:?}\n{whole:?}"
    );
    assert!(close(&spread.lobes, &whole.lobes));
    // Continued from where it stopped, not from the shading lobes: the
    // cost never rises across the frames.
    assert!(
        spread.costs.windows(2).all(|w| w[1] <= w[0]),
        "{:?}",
        spread.costs
    );
}

/// A 256 × 256 probe fitted with 64 lobes is more than llvmpipe's 65535
/// loop iterations for one invocation (a lobe's cold start gives each of
/// its 64 invocations 1024 texels against every lobe; measured: the
/// first cost 1.5 % off the reference's), so on such a device the fit is
/// refused, naming the knobs; 128 × 128 fits.
#[test]
fn a_fit_past_the_devices_loop_limit_is_refused() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let knobs = FitKnobs {
        lobes: 64,
        ..FitKnobs::default()
    };
    let map = |n| DirectionMap::new(MapKind::Octahedral, n);
    assert!(SgFitPass::new(&ctx, &lib, knobs, map(128)).is_ok());
    let big = SgFitPass::new(&ctx, &lib, knobs, map(256));
    if ctx.info().loop_iteration_limit.is_none() {
        assert!(big.is_ok());
        return;
    }
    let e = big.err().expect("refused").to_string();
    for needle in ["sg-fit", "probe_resolution` 256", "lobes` 64", "65535"] {
        assert!(e.contains(needle), "`{needle}` missing: {e}");
    }
}
