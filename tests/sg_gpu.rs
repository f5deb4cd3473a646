//! `shaders/common/sg.wgsl` on the GPU (lavapipe) against its Rust mirrors:
//! the f32 `Sg32` (same formulas, same precision) and the f64 `Sg64`.

mod common;

use std::sync::Arc;

use glam::{DVec3, Vec3};
use inlay_engine::shader::{compile, ShaderStage};
use inlay_engine::{vk, Buffer, BufferLocation, BufferReadback, ComputePipeline};
use inlay_passes::rng::Pcg32;
use inlay_passes::sg::{Sg32, Sg64};

fn unit(rng: &mut Pcg32) -> DVec3 {
    let [a, b] = rng.next_2d();
    let z = 1.0 - 2.0 * a;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * b;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn log_uniform(rng: &mut Pcg32, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.next_f64() * (hi.ln() - lo.ln())).exp()
}

/// Random cases over λ ∈ [1e-4, 1e4], μ ∈ [1e-6, 1e6], with b and v near a's
/// axis (within a few lobe widths) so results are not all underflow, plus
/// fixed extremes.
fn cases() -> Vec<(Sg32, Sg32, Vec3)> {
    let mut rng = Pcg32::new(11, 4);
    let mut out = Vec::new();
    for _ in 0..512 {
        let lobe = |rng: &mut Pcg32, axis: DVec3| Sg64 {
            direction: axis,
            sharpness: log_uniform(rng, 1e-4, 1e4),
            amplitude: DVec3::new(
                log_uniform(rng, 1e-6, 1e6),
                log_uniform(rng, 1e-6, 1e6),
                log_uniform(rng, 1e-6, 1e6),
            ),
        };
        let axis_a = unit(&mut rng);
        let a = lobe(&mut rng, axis_a);
        let near = |rng: &mut Pcg32, l: f64| {
            let t = unit(rng) * (3.0 * rng.next_f64() / l.max(1e-4).sqrt()).min(2.0);
            (a.direction + t).normalize()
        };
        let axis_b = near(&mut rng, a.sharpness);
        let b = lobe(&mut rng, axis_b);
        let v = near(&mut rng, a.sharpness);
        out.push((a.to_f32(), b.to_f32(), v.as_vec3()));
    }
    let big = Vec3::splat(1e6);
    for (l1, l2, opposite) in [
        (1e4, 1e4, true),
        (1e4, 1e4, false),
        (0.0, 0.0, true),
        (1e-4, 1e4, false),
    ] {
        let a = Sg32 {
            direction: Vec3::Z,
            sharpness: l1,
            amplitude: big,
        };
        let b = Sg32 {
            direction: if opposite { -Vec3::Z } else { Vec3::Z },
            sharpness: l2,
            amplitude: big,
        };
        out.push((a, b, -Vec3::Z));
    }
    out
}

fn run_on_gpu(ctx: &Arc<inlay_engine::Context>, cases: &[(Sg32, Sg32, Vec3)]) -> Vec<f32> {
    let lib = common::test_library();
    let shader = compile(
        &lib,
        "checks/sg_ops.wgsl",
        "main",
        ShaderStage::Compute,
        &[],
    )
    .unwrap();
    let pipeline = Arc::new(ComputePipeline::new(ctx, &shader).unwrap());
    let input: Vec<u8> = cases
        .iter()
        .flat_map(|(a, b, v)| {
            let mut f = Vec::with_capacity(20);
            f.extend(a.packed());
            f.extend(b.packed());
            f.extend([v.x, v.y, v.z, 0.0]);
            f
        })
        .flat_map(f32::to_le_bytes)
        .collect();
    let input = Arc::new(
        Buffer::with_data(
            ctx,
            "sg-cases",
            &input,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap(),
    );
    let result_bytes = (cases.len() * 24 * 4) as u64;
    let results = Arc::new(
        Buffer::new(
            ctx,
            "sg-results",
            result_bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            BufferLocation::Gpu,
        )
        .unwrap(),
    );
    let readback = BufferReadback::new(ctx, "sg-results", result_bytes).unwrap();
    let n = cases.len() as u32;
    common::run_frame(ctx, |graph| {
        let input = graph.import_buffer(&input, None);
        let out = graph.import_buffer(&results, None);
        let mut out = out;
        graph
            .compute("sg-ops", &pipeline)
            .read("cases", input)
            .write("results", &mut out)
            .threads([n, 1, 1]);
        readback.add_to_graph(graph, "read-sg-results", out);
    });
    readback.read_f32().unwrap()
}

/// Relative difference with a floor for values that underflow in f32.
fn rel(got: f32, want: f64) -> f64 {
    let got = got as f64;
    if want.abs() < 1e-30 && got.abs() < 1e-30 {
        return 0.0;
    }
    (got - want).abs() / want.abs().max(1e-30)
}

#[test]
fn wgsl_sg_matches_the_rust_mirrors() {
    let ctx = common::gpu();
    let cases = cases();
    let out = run_on_gpu(&ctx, &cases);
    let mut worst32 = 0.0f64;
    let mut worst64 = 0.0f64;
    for (i, (a, b, v)) in cases.iter().enumerate() {
        let r = &out[i * 24..(i + 1) * 24];
        assert!(
            r.iter().all(|x| x.is_finite()),
            "case {i} {a:?} {b:?}: {r:?}"
        );
        let p32 = a.product(b);
        let (a64, b64) = (a.to_f64(), b.to_f64());
        let p64 = a64.product(&b64);
        let cos = Sg32::clamped_cosine(*v);
        // (GPU value, f32 mirror, f64 reference, how many f32 roundings of
        // an exponent of this size the value can inherit)
        let exponent = |e: f64| 1.0 + e.abs();
        let checks = [
            (
                r[0],
                a.eval(*v).x,
                a64.eval(v.as_dvec3()).x,
                exponent(a64.sharpness * (v.as_dvec3() - a64.direction).length_squared()),
            ),
            (
                r[7],
                p32.sharpness,
                p64.sharpness,
                1.0 + a64.sharpness + b64.sharpness,
            ),
            (
                r[8],
                p32.amplitude.x,
                p64.amplitude.x,
                exponent((p64.amplitude.x / (a64.amplitude.x * b64.amplitude.x)).ln()),
            ),
            (r[12], a.integral().x, a64.integral().x, 1.0),
            (
                r[16],
                a.inner_product(b).x,
                a64.inner_product(&b64).x,
                exponent((p64.amplitude.x / (a64.amplitude.x * b64.amplitude.x)).ln()),
            ),
            (
                r[20],
                cos.eval(a.direction).x,
                cos.to_f64().eval(a64.direction).x,
                10.0,
            ),
        ];
        for (k, (gpu, mirror, reference, scale)) in checks.into_iter().enumerate() {
            // Against the f32 mirror: the same operations, so only the
            // GPU's exp/length/division ulps (a few 1e-7 per operation,
            // amplified by the size of the exponent they feed).
            let e32 = rel(gpu, mirror as f64);
            // Against f64: additionally the f32 rounding of the inputs.
            let e64 = rel(gpu, reference);
            worst32 = worst32.max(e32 / scale);
            worst64 = worst64.max(e64 / scale);
            assert!(
                e32 <= 2e-5 * scale,
                "case {i} check {k}: GPU {gpu:e} vs f32 {mirror:e} ({a:?}, {b:?}, {v})"
            );
            assert!(
                e64 <= 2e-5 * scale,
                "case {i} check {k}: GPU {gpu:e} vs f64 {reference:e} ({a:?}, {b:?}, {v})"
            );
        }
    }
    eprintln!(
        "worst relative error per exponent unit: vs f32 mirror {worst32:e}, vs f64 {worst64:e}"
    );
}
