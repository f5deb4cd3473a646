//! `inlay bench-sg SCENE --at x,y,z`: the SG fit's accuracy and speed.
//! For each probe resolution: the relative residual after each number of
//! iterations (M fixed) and for each lobe count M (iterations fixed), and
//! the GPU time of the probe trace and of one LM iteration (the slope of
//! the `sg-fit` pass time between two iteration counts). Prints Markdown
//! tables for `docs/benchmarks.md`.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use glam::DVec3;
use inlay_engine::graph::FrameGraph;
use inlay_engine::{Context, Renderer, SubmitSync};
use inlay_passes::field::GpuGridField;
use inlay_passes::lighting::environment_lobes;
use inlay_passes::probe::{trace_probe, ProbeKnobs, ProbePass};
use inlay_passes::scene::load_scene;
use inlay_passes::sgfit::{
    fit_reference, relative_residual, FitKnobs, FitReport, FitStart, ProbeSamples, SgFitPass, Start,
};

use crate::commands::probe::PlacementArgs;
use crate::field_source::scene_field;
use crate::timings_table::quantile;

/// Options of `bench-sg`.
#[derive(Args, Debug)]
pub struct BenchSgArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Probe position and layout.
    #[command(flatten)]
    pub placement: PlacementArgs,
    /// Probe resolutions to measure.
    #[arg(long, value_delimiter = ',', default_values = ["16", "32"])]
    pub resolutions: Vec<u32>,
    /// Iteration counts of the residual-against-iterations table.
    #[arg(long, value_delimiter = ',', default_values = ["0", "1", "2", "4", "8", "16", "32", "64"])]
    pub iterations: Vec<u32>,
    /// Lobe counts of the residual-against-M table.
    #[arg(long, value_delimiter = ',', default_values = ["4", "8", "16", "32", "64"])]
    pub lobes: Vec<u32>,
    /// Iterations of the residual-against-M table.
    #[arg(long, default_value_t = 40)]
    pub fit_iterations: u32,
    /// Timed frames per measurement (median reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Also fit the probe traced on the CPU with the f64 reference fit, for
    /// the residual-against-M table (slow: the CPU traces every probe).
    #[arg(long)]
    pub reference: bool,
}

/// Traces the probe and fits it `frames` times; returns the last report and
/// the median GPU ms of the probe trace and of the fit.
fn measure(
    ctx: &Arc<Context>,
    probe: &ProbePass,
    fit: &SgFitPass,
    field: &GpuGridField,
    at: DVec3,
    iterations: u32,
    frames: u32,
) -> anyhow::Result<(FitReport, f64, f64)> {
    let mut renderer = Renderer::new(ctx, 1)?;
    let (mut trace_ms, mut fit_ms) = (Vec::new(), Vec::new());
    for _ in 0..frames.max(1) {
        renderer.begin_frame()?;
        let mut graph = FrameGraph::new();
        let image = probe.add(&mut graph, field, at);
        fit.add(&mut graph, image, FitStart::Cold, iterations)?;
        fit.add_readback(&mut graph);
        renderer.submit(graph, &SubmitSync::none())?;
        renderer.finish()?;
        if let Some(t) = renderer.latest_timings() {
            trace_ms.extend(t.gpu_ms(inlay_passes::probe::PROBE_TRACE));
            fit_ms.extend(t.gpu_ms(inlay_passes::sgfit::SG_FIT));
        }
    }
    Ok((
        fit.read_report()?,
        quantile(&trace_ms, 0.5),
        quantile(&fit_ms, 0.5),
    ))
}

/// Runs `bench-sg`.
pub fn run(ctx: &Arc<Context>, args: &BenchSgArgs) -> anyhow::Result<()> {
    let at = args.placement.point()?;
    let scene = load_scene(&args.scene)?;
    let field = scene_field(&scene, args.field.as_deref(), true, Some(ctx.info()))?;
    let gpu_field = GpuGridField::upload(ctx, &field)?;
    let env = environment_lobes(&scene.environment);
    let library = gpu_field.library(&inlay_passes::shaders::library()?);
    let map = args.placement.map_or(scene.lighting.probe.map);
    let max_iterations = args.iterations.iter().copied().max().unwrap_or(0);
    println!(
        "Device: {} ({:?}); scene {}, probe at {at}, {} map, environment {} lobes\n",
        ctx.info().name,
        ctx.info().kind,
        scene.name,
        map.name(),
        env.len()
    );
    let base = scene.lighting.fit;
    let default_lobes = base.lobes;
    let mut timing_rows = Vec::new();
    println!("Relative residual √(cost / Σ w|L|²) against iterations, M = {default_lobes}, cold start:\n");
    let header: Vec<String> = args.iterations.iter().map(|i| i.to_string()).collect();
    println!("| probe | {} |", header.join(" | "));
    println!("| --- |{}", " --- |".repeat(args.iterations.len()));
    for &n in &args.resolutions {
        let knobs = ProbeKnobs {
            map,
            resolution: n,
            ..scene.lighting.probe
        };
        let probe = ProbePass::new(ctx, &library, knobs, scene.march, &env, &[])?;
        let fit = SgFitPass::new(ctx, &library, base, probe.map())?;
        let (report, trace, t_max) = measure(
            ctx,
            &probe,
            &fit,
            &gpu_field,
            at,
            max_iterations,
            args.frames,
        )?;
        let cells: Vec<String> = args
            .iterations
            .iter()
            .map(|&i| {
                let c = report.costs[(i as usize).min(report.costs.len() - 1)];
                format!("{:.4}", relative_residual(c, report.energy))
            })
            .collect();
        let m = probe.map();
        println!("| {}×{} | {} |", m.width, m.height, cells.join(" | "));
        // One LM iteration: the slope of the fit time between 0 and the most iterations.
        let (_, _, t0) = measure(ctx, &probe, &fit, &gpu_field, at, 0, args.frames)?;
        let per_iteration = (t_max - t0) / max_iterations.max(1) as f64;
        timing_rows.push(format!(
            "| {}×{} | {trace:.3} | {t0:.3} | {per_iteration:.3} |",
            m.width, m.height
        ));
    }
    println!(
        "\nRelative residual against M after {} iterations, cold start{}:\n",
        args.fit_iterations,
        if args.reference {
            " (in brackets: the f64 reference fit of the probe traced on the CPU)"
        } else {
            ""
        }
    );
    let header: Vec<String> = args.lobes.iter().map(|m| format!("M={m}")).collect();
    println!("| probe | {} |", header.join(" | "));
    println!("| --- |{}", " --- |".repeat(args.lobes.len()));
    let mut lobe_timing = Vec::new();
    for &n in &args.resolutions {
        let knobs = ProbeKnobs {
            map,
            resolution: n,
            ..scene.lighting.probe
        };
        let probe = ProbePass::new(ctx, &library, knobs, scene.march, &env, &[])?;
        let cpu_probe = args.reference.then(|| {
            let texels = trace_probe(&field, at, &knobs, &scene.march, &env);
            ProbeSamples::new(&probe.map(), &texels)
        });
        let mut cells = Vec::new();
        for &m in &args.lobes {
            let fit_knobs = FitKnobs { lobes: m, ..base };
            let fit = SgFitPass::new(ctx, &library, fit_knobs, probe.map())?;
            let (report, _, t) =
                measure(ctx, &probe, &fit, &gpu_field, at, args.fit_iterations, 1)?;
            let mut cell = format!("{:.4}", report.relative_residual());
            if let Some(samples) = &cpu_probe {
                let cpu = fit_reference(samples, &fit_knobs, Start::Cold, args.fit_iterations);
                cell += &format!(" (f64 {:.4})", cpu.relative_residual());
            }
            cells.push(cell);
            lobe_timing.push((n, m, t));
        }
        let map = probe.map();
        println!("| {}×{} | {} |", map.width, map.height, cells.join(" | "));
    }
    println!(
        "\nGPU time (median of {} frames), M = {default_lobes}:\n",
        args.frames
    );
    println!("| probe | probe trace ms | fit start ms (cold start, no iteration) | ms per LM iteration |");
    println!("| --- | --- | --- | --- |");
    for row in timing_rows {
        println!("{row}");
    }
    println!(
        "\nWhole `sg-fit` pass for {} iterations (one frame) against M:\n",
        args.fit_iterations
    );
    println!("| probe | M | sg-fit ms |");
    println!("| --- | --- | --- |");
    for (n, m, t) in lobe_timing {
        println!("| {n} | {m} | {t:.2} |");
    }
    Ok(())
}
