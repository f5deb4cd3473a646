//! The probe trace on the GPU (lavapipe) against its f64 CPU reference,
//! with and without an environment light; the fit of a traced probe on GPU
//! and CPU; and the incident light re-running only when something changed.

mod common;

use std::sync::Arc;

use glam::DVec3;
use inlay::shaders::embedded_library;
use inlay_engine::shader::{compile, Define, ShaderStage};
use inlay_engine::{Context, HdrImage, ImageDesc, Readback};
use inlay_passes::field::{GpuGridField, GridField};
use inlay_passes::lighting::{environment_lobes, IncidentLight, LightingWork};
use inlay_passes::march::MarchKnobs;
use inlay_passes::probe::{trace_probe, MapKind, ProbeKnobs, ProbePass, PROBE_FORMAT};
use inlay_passes::sg::Sg64;
use inlay_passes::sgfit::{fit_reference, FitKnobs, FitStart, ProbeSamples, Start};

fn march() -> MarchKnobs {
    MarchKnobs {
        samples_per_ray: 256,
        ..MarchKnobs::default()
    }
}

fn gpu_probe(ctx: &Arc<Context>, pass: &ProbePass, field: &GridField, origin: DVec3) -> HdrImage {
    let gpu_field = GpuGridField::upload(ctx, field).unwrap();
    let map = pass.map();
    let rb = Readback::new(
        ctx,
        ImageDesc {
            width: map.width,
            height: map.height,
            format: PROBE_FORMAT,
        },
    )
    .unwrap();
    common::run_frame(ctx, |graph| {
        let probe = pass.add(graph, &gpu_field, origin);
        rb.add_to_graph(graph, probe);
    });
    rb.read().unwrap()
}

/// Tolerance as for the march (tests/field_gpu.rs): f32 along the ray and
/// early termination move Ĉ by ≤ 3e-4 of the brightest value and Ô by
/// 3e-4; the environment term adds the f32 SG evaluation (≤ 1e-5 relative).
fn assert_matches(gpu: &HdrImage, cpu: &[[f64; 4]], what: &str) {
    let max = cpu
        .iter()
        .map(|t| t[0].max(t[1]).max(t[2]))
        .fold(0.0, f64::max);
    assert!(max > 1e-3, "{what}: black probe");
    for (i, (g, c)) in gpu.pixels.iter().zip(cpu).enumerate() {
        for k in 0..4 {
            let tol = if k == 3 { 3e-4 } else { 3e-4 * max };
            assert!(
                g[k].is_finite() && (g[k] as f64 - c[k]).abs() <= tol,
                "{what}: texel {i} channel {k}: GPU {} vs CPU {}",
                g[k],
                c[k]
            );
        }
    }
}

#[test]
fn probe_matches_the_cpu_reference_with_and_without_environment() {
    let ctx = common::gpu();
    let lib = embedded_library();
    for (scene, origin, kind) in [
        ("books.toml", DVec3::new(0.1, 0.3, 0.1), MapKind::Octahedral),
        ("plants.toml", DVec3::new(0.0, 0.4, 0.0), MapKind::Equirect),
    ] {
        let s = common::bundled_scene(scene);
        let field = common::bake_small(&s, 24, 4, 0);
        let env = environment_lobes(&s.environment);
        assert_eq!(env.is_empty(), scene == "plants.toml");
        let knobs = ProbeKnobs {
            map: kind,
            resolution: 12,
            supersampling: 2,
        };
        let pass = ProbePass::new(&ctx, &lib, knobs, march(), &env).unwrap();
        let gpu = gpu_probe(&ctx, &pass, &field, origin);
        let cpu = trace_probe(&field, origin, &knobs, &march(), &env);
        assert_matches(&gpu, &cpu, scene);
        // Some of the sphere sees past the field.
        assert!(
            cpu.iter().any(|t| t[3] < 0.5),
            "{scene}: the probe is enclosed"
        );
    }
}

#[test]
fn without_environment_the_env_term_is_not_compiled() {
    let lib = embedded_library();
    let bindings = |env: bool| -> Vec<u32> {
        let defines = [
            Define::Bool("SKIP_EMPTY", true),
            Define::Bool("OCTAHEDRAL", true),
        ];
        let entry = if env {
            "main_with_environment"
        } else {
            "main_field_only"
        };
        compile(
            &lib,
            "probe/trace.wgsl",
            entry,
            ShaderStage::Compute,
            &defines,
        )
        .unwrap()
        .bindings
        .iter()
        .map(|b| b.binding)
        .collect()
    };
    assert!(bindings(true).contains(&4));
    assert!(!bindings(false).contains(&4), "{:?}", bindings(false));
}

#[test]
fn traced_probe_fits_alike_on_gpu_and_cpu_and_reruns_only_on_change() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let s = common::bundled_scene("books.toml");
    let field = common::bake_small(&s, 24, 4, 0);
    let gpu_field = GpuGridField::upload(&ctx, &field).unwrap();
    let env: Vec<Sg64> = environment_lobes(&s.environment);
    let probe_knobs = ProbeKnobs {
        map: MapKind::Octahedral,
        resolution: 16,
        supersampling: 2,
    };
    let fit_knobs = FitKnobs {
        lobes: 8,
        cold_iterations: 20,
        warm_iterations: 4,
        ..FitKnobs::default()
    };
    let mut light = IncidentLight::new(&ctx, &lib, probe_knobs, fit_knobs, march(), &env).unwrap();
    let centre = DVec3::new(0.1, 0.3, 0.1);
    let frame = |light: &mut IncidentLight, centre: DVec3, version: u64| {
        let work = light.plan(centre, version);
        let report = common::run_frame(&ctx, |graph| {
            light.add(graph, &gpu_field, centre, work).unwrap();
            light.fit.add_readback(graph);
        });
        (work, report.executed)
    };
    let (work, executed) = frame(&mut light, centre, 0);
    assert_eq!(
        work,
        LightingWork::Update {
            start: FitStart::Cold,
            iterations: 20
        }
    );
    assert!(executed.iter().any(|p| p == "probe-trace") && executed.iter().any(|p| p == "sg-fit"));
    let gpu = light.fit.read_report().unwrap();
    // The same probe on the CPU.
    let cpu_probe = trace_probe(&field, centre, &probe_knobs, &march(), &env);
    let cpu = fit_reference(
        &ProbeSamples::new(&light.probe.map(), &cpu_probe),
        &fit_knobs,
        Start::Cold,
        20,
    );
    eprintln!(
        "books probe, 8 lobes, 20 iterations: GPU residual {:.4}, CPU {:.4}",
        gpu.relative_residual(),
        cpu.relative_residual()
    );
    assert!(gpu.relative_residual() <= 1.25 * cpu.relative_residual() + 0.01);
    assert!(cpu.relative_residual() < 0.6);
    // Nothing changed: neither pass runs.
    let (work, executed) = frame(&mut light, centre, 0);
    assert_eq!(work, LightingWork::Reuse);
    assert!(
        !executed.iter().any(|p| p == "probe-trace" || p == "sg-fit"),
        "{executed:?}"
    );
    // The object moves, or the lighting changes: a warm update.
    for (c, v) in [(centre + DVec3::X * 0.05, 0), (centre + DVec3::X * 0.05, 1)] {
        let (work, executed) = frame(&mut light, c, v);
        assert_eq!(
            work,
            LightingWork::Update {
                start: FitStart::Warm,
                iterations: 4
            }
        );
        assert!(executed.iter().any(|p| p == "sg-fit"));
        let r = light.fit.read_report().unwrap();
        assert!(!r.started_cold && r.relative_residual() <= 1.1 * gpu.relative_residual() + 0.01);
    }
}
