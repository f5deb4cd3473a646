//! `inlay sweep SCENE`: the measured speed/accuracy trade. Runs the costly
//! knobs (render size, samples per ray, probe size, lobes M, LM
//! iterations, SSDF grid and PCA components) over a grid; for each
//! configuration it times every Table 1 module over dragged frames (probe
//! and fit every frame) and measures the error of a still frame (cold fit)
//! against the path-traced ground truth with the object. Writes a
//! Markdown table, JSON, and an SVG plot of error against frame time with
//! the Pareto front.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use inlay_engine::{Context, HdrImage};
use inlay_passes::bake::{render_reference, ReferenceOptions};
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::GpuGridField;
use inlay_passes::scene::{load_scene, Scene};
use inlay_passes::shadow::GpuSsdf;
use serde_json::json;

use super::profile::{profile_view, Motion};
use crate::field_source::scene_field;
use crate::headless::run_headless;
use crate::measure::{parse_size, relative_error};
use crate::outputs::{check_output, Outputs};
use crate::scene_view::view_over_gpu_field;
use crate::sweep::grid::{configurations, GridMode, KnobValues, Knobs};
use crate::sweep::pareto::pareto_front;
use crate::sweep::plot::{svg, PlotPoint};
use crate::table1::{modules, summarise};
use crate::timings_table::quantile;

/// Options of `sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    /// The scene file (a recipe scene with objects: the ground truth is
    /// path traced from the recipe).
    pub scene: PathBuf,
    /// Camera index or name.
    #[arg(long, default_value = "0")]
    pub camera: String,
    /// Use this field file instead of the scene's (baked) recipe field;
    /// the ground truth is still traced from the recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Render sizes, WxH (the first is the base).
    #[arg(long, value_delimiter = ',', default_values = ["160x90", "320x180"])]
    pub sizes: Vec<String>,
    /// Samples per ray (segments across the field's diagonal).
    #[arg(long, value_delimiter = ',', default_values_t = [64, 128, 256, 512])]
    pub samples_per_ray: Vec<u32>,
    /// Probe sides n (n × n texels).
    #[arg(long, value_delimiter = ',', default_values_t = [8, 16, 32])]
    pub probe: Vec<u32>,
    /// SG lobe counts M.
    #[arg(long, value_delimiter = ',', default_values_t = [4, 8, 16, 32])]
    pub lobes: Vec<u32>,
    /// LM iterations of the cold fit (warm fits run a fifth of them).
    #[arg(long, value_delimiter = ',', default_values_t = [10, 20, 40])]
    pub iterations: Vec<u32>,
    /// SSDF grid nodes per axis (each new grid is baked once and cached).
    #[arg(long, value_delimiter = ',', default_values_t = [8, 16])]
    pub ssdf_grid: Vec<u32>,
    /// SSDF PCA components (one bake per grid, at the most components,
    /// truncated for the fewer).
    #[arg(long, value_delimiter = ',', default_values_t = [4, 8, 16])]
    pub components: Vec<u32>,
    /// How the values combine: each knob around the base (the scene's
    /// knobs at the first size), or every combination.
    #[arg(long, value_enum, default_value_t = GridMode::Axes)]
    pub grid: GridMode,
    /// Frames timed per configuration: the first (cold fit) apart, the
    /// rest with the object dragged.
    #[arg(long, default_value_t = 5)]
    pub frames: u32,
    /// Path-traced samples per pixel of the ground truth.
    #[arg(long, default_value_t = 64)]
    pub reference_samples: u32,
    /// Folder for sweep.md, sweep.json and sweep.svg.
    #[arg(long, default_value = "inlay-sweep")]
    pub out_dir: PathBuf,
    /// Bake again even where a cached field or SSDF exists.
    #[arg(long)]
    pub no_cache: bool,
}

/// What one configuration measured.
#[derive(Debug, Clone)]
pub struct SweepRow {
    /// The configuration.
    pub knobs: Knobs,
    /// Median GPU frame time over the dragged frames, ms.
    pub frame_ms: f64,
    /// Median per Table 1 module over the dragged frames (None: skipped).
    pub module_ms: Vec<(String, Option<f64>)>,
    /// The first frame's SG update (cold fit), ms.
    pub first_fit_ms: Option<f64>,
    /// Relative error of the still frame against the ground truth.
    pub error: f64,
}

/// The base configuration: `scene`'s knobs at `size`.
pub fn base_knobs(scene: &Scene, size: (u32, u32)) -> Knobs {
    Knobs {
        width: size.0,
        height: size.1,
        samples_per_ray: scene.march.samples_per_ray,
        probe: scene.lighting.probe.resolution,
        lobes: scene.lighting.fit.lobes,
        iterations: scene.lighting.fit.cold_iterations,
        ssdf_grid: scene.shadows.bake.grid,
        components: scene.shadows.bake.components,
    }
}

/// `scene` with `knobs` applied; SSDF bakes at `bake_components`.
pub fn scene_with(scene: &Scene, knobs: &Knobs, bake_components: u32) -> Scene {
    let mut s = scene.clone();
    s.march.samples_per_ray = knobs.samples_per_ray;
    s.lighting.probe.resolution = knobs.probe;
    s.lighting.fit.lobes = knobs.lobes;
    s.lighting.fit.cold_iterations = knobs.iterations;
    s.lighting.fit.warm_iterations = knobs.warm_iterations();
    s.shadows.bake.grid = knobs.ssdf_grid;
    s.shadows.bake.components = bake_components;
    s
}

/// Runs `sweep`.
pub fn run(ctx: &Arc<Context>, args: &SweepArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out_dir)
        .map_err(|e| anyhow::anyhow!("--out-dir: {}: {e}", args.out_dir.display()))?;
    for name in ["sweep.md", "sweep.json", "sweep.svg"] {
        check_output("--out-dir", &args.out_dir.join(name), &[])?;
    }
    let scene = load_scene(&args.scene)?;
    let recipe = scene.recipe().ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the scene's field is a file, not a [recipe]: there is no ground truth to measure the error against",
            scene.path.display()
        )
    })?;
    anyhow::ensure!(
        !scene.objects.is_empty(),
        "{}: the scene has no [[objects]]: there is nothing to insert",
        scene.path.display()
    );
    anyhow::ensure!(
        args.frames >= 2,
        "--frames must be at least 2 (the first is timed apart)"
    );
    anyhow::ensure!(
        args.reference_samples >= 1,
        "--reference-samples must be at least 1"
    );
    let sizes = args
        .sizes
        .iter()
        .map(|s| parse_size(s))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let values = KnobValues {
        sizes: sizes.clone(),
        samples_per_ray: args.samples_per_ray.clone(),
        probe: args.probe.clone(),
        lobes: args.lobes.clone(),
        iterations: args.iterations.clone(),
        ssdf_grid: args.ssdf_grid.clone(),
        components: args.components.clone(),
    };
    let base = base_knobs(
        &scene,
        *sizes
            .first()
            .ok_or_else(|| anyhow::anyhow!("--sizes is empty"))?,
    );
    let configs = configurations(&values, base, args.grid);
    let most_components = configs
        .iter()
        .map(|k| k.components)
        .max()
        .unwrap_or(base.components);
    let spec = scene.camera(&args.camera)?.clone();
    let field = scene_field(
        &scene,
        args.field.as_deref(),
        !args.no_cache,
        Some(ctx.info()),
    )?;
    // One upload serves every configuration.
    let gpu_field = GpuGridField::upload(ctx, &field)?;
    let library = gpu_field.library(&inlay_passes::shaders::library()?);
    eprintln!(
        "sweep: {} configurations ({:?} grid) of {} on {}",
        configs.len(),
        args.grid,
        scene.path.display(),
        ctx.info().name
    );

    // The ground truth per render size, traced once.
    let mut references: std::collections::HashMap<(u32, u32), Vec<[f32; 4]>> =
        std::collections::HashMap::new();
    let mut rows = Vec::with_capacity(configs.len());
    for (i, knobs) in configs.iter().enumerate() {
        let (w, h) = (knobs.width, knobs.height);
        let reference = references.entry((w, h)).or_insert_with(|| {
            let options = ReferenceOptions {
                samples: args.reference_samples,
                bounces: scene.bake.bounces,
                seed: 1,
                antialias: false,
                sky_behind: false,
            };
            render_reference(
                recipe,
                &scene.environment,
                &scene.objects,
                &CameraFrame::new(&spec, w, h),
                &options,
                &|_, _| {},
            )
        });
        let configured = scene_with(&scene, knobs, most_components);
        let mut view = view_over_gpu_field(
            ctx,
            &library,
            &configured,
            configured.march,
            gpu_field.clone(),
            spec.clone(),
            !args.no_cache,
        )
        .map_err(|e| e.context(format!("configuration {}", knobs.label())))?;
        let meshes: Vec<_> = (0..view.objects().len())
            .filter_map(|i| view.placed(i).map(|p| p.mesh))
            .collect();
        for (o, mesh) in view.objects_mut().iter_mut().zip(meshes) {
            if let Some(s) = &o.ssdf {
                if s.field.components > knobs.components {
                    o.ssdf = Some(GpuSsdf::upload(
                        ctx,
                        Arc::new(s.field.truncated(knobs.components)),
                        &mesh,
                    )?);
                }
            }
        }
        let run = profile_view(ctx, &mut view, w, h, args.frames, Motion::Drag)?;
        // SG updating over frames 2.. (the dragged ones; the first, cold,
        // apart), the other modules over the dragged frames too.
        let whole = summarise(&run.frames, &[]);
        let dragged = &run.frames[1.min(run.frames.len())..];
        let table = summarise(dragged, &[]);
        let sg = whole.modules.iter().find(|m| m.module == "SG updating");
        let first_fit_ms = sg.and_then(|m| m.first_frame_ms);
        let totals: Vec<f64> = dragged.iter().map(|f| f.gpu_total_ms).collect();
        // The error of a still frame: the object where the scene puts it,
        // lit by a cold fit with this configuration's iterations.
        for o in view.objects_mut() {
            o.light.reset();
        }
        let still: HdrImage = run_headless(ctx, &mut view, w, h, 1, 0.0)?.image;
        let error = relative_error(&still, reference);
        let row = SweepRow {
            knobs: *knobs,
            frame_ms: quantile(&totals, 0.5),
            module_ms: table
                .modules
                .iter()
                .map(|m| match sg {
                    Some(sg) if m.module == sg.module => (m.module.clone(), sg.median_ms),
                    _ => (m.module.clone(), m.median_ms),
                })
                .collect(),
            first_fit_ms,
            error,
        };
        eprintln!(
            "[{}/{}] {}: {:.2} ms per dragged frame, error {:.4}",
            i + 1,
            configs.len(),
            knobs.label(),
            row.frame_ms,
            row.error
        );
        rows.push(row);
    }
    ctx.check_validation()?;

    let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.frame_ms, r.error)).collect();
    let front = pareto_front(&points);
    let device = format!("{} ({:?})", ctx.info().name, ctx.info().kind);
    let markdown = format_markdown(&rows, &front, &scene, &device, args);
    print!("{markdown}");
    let mut outputs = Outputs::new();
    let mut write =
        |name: &str, text: &str| outputs.bytes(&args.out_dir.join(name), text.as_bytes());
    write("sweep.md", &markdown)?;
    let report = json!({
        "scene": scene.path.display().to_string(),
        "device": device,
        "grid": format!("{:?}", args.grid).to_lowercase(),
        "frames": args.frames,
        "reference_samples": args.reference_samples,
        "base": base,
        "configurations": rows.iter().enumerate().map(|(i, r)| json!({
            "knobs": r.knobs,
            "frame_ms": r.frame_ms,
            "modules_ms": r.module_ms.iter().map(|(m, t)| (m.clone(), json!(t))).collect::<serde_json::Map<_, _>>(),
            "first_fit_ms": r.first_fit_ms,
            "error": if r.error.is_finite() { json!(r.error) } else { json!(null) },
            "pareto": front.contains(&i),
        })).collect::<Vec<_>>(),
        "pareto_front": front,
    });
    write("sweep.json", &serde_json::to_string_pretty(&report)?)?;
    let plot_points: Vec<PlotPoint> = rows
        .iter()
        .map(|r| PlotPoint {
            ms: r.frame_ms,
            error: r.error,
            label: r.knobs.label(),
        })
        .collect();
    write(
        "sweep.svg",
        &svg(
            &format!(
                "{}: error against frame time on {}",
                scene.name,
                ctx.info().name
            ),
            "GPU ms per frame, object dragged (log)",
            "relative error against the path-traced ground truth (log)",
            &plot_points,
            &front,
        ),
    )?;
    outputs.commit(Some(ctx))?;
    Ok(())
}

/// The table of every configuration and the Pareto front, in Markdown.
fn format_markdown(
    rows: &[SweepRow],
    front: &[usize],
    scene: &Scene,
    device: &str,
    args: &SweepArgs,
) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Sweep of {} on {device}: {} configurations ({:?} grid), {} frames each (the first, a cold fit, apart; the rest with the object dragged); error = mean |image − truth| / mean truth over rgb, against the path tracer at {} samples per pixel, of a still frame after a cold fit.\n",
        scene.path.display(),
        rows.len(),
        args.grid,
        args.frames,
        args.reference_samples
    );
    let _ = write!(s, "| configuration | frame ms |");
    for (m, _) in modules() {
        let _ = write!(s, " {m} |");
    }
    let _ = writeln!(s, " first fit ms | error | Pareto |");
    let _ = write!(s, "| --- | --- |");
    for _ in modules() {
        let _ = write!(s, " --- |");
    }
    let _ = writeln!(s, " --- | --- | --- |");
    let ms = |t: Option<f64>| t.map_or("skipped".to_string(), |t| format!("{t:.2}"));
    for (i, r) in rows.iter().enumerate() {
        let _ = write!(s, "| {} | {:.2} |", r.knobs.label(), r.frame_ms);
        for (_, t) in &r.module_ms {
            let _ = write!(s, " {} |", ms(*t));
        }
        let _ = writeln!(
            s,
            " {} | {:.4} | {} |",
            ms(r.first_fit_ms),
            r.error,
            if front.contains(&i) { "yes" } else { "" }
        );
    }
    let _ = writeln!(s, "\nPareto front (cheapest first):\n");
    for &i in front {
        let r = &rows[i];
        let _ = writeln!(
            s,
            "- {}: {:.2} ms, error {:.4}",
            r.knobs.label(),
            r.frame_ms,
            r.error
        );
    }
    s
}
