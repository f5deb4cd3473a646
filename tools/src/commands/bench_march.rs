//! `inlay bench-march SCENE`: the march's speed (rays/s and samples/s from
//! its GPU timestamps) at several image sizes, and its error as the step
//! size changes — against a very fine march of the same field (quadrature
//! error) and against the path-traced reference (everything the field
//! loses). Prints Markdown tables for `docs/benchmarks.md`.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use inlay_engine::Context;
use inlay_passes::bake::{render_reference, ReferenceOptions};
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::GpuGridField;
use inlay_passes::march::{march_image, MarchKnobs, MarchPass};
use inlay_passes::scene::load_scene;

use crate::field_source::scene_field;
use crate::headless::run_headless;
use crate::insertion_view::InsertionView;
use crate::measure::{parse_size, relative_error};
use crate::timings_table::quantile;

/// Options of `bench-march`.
#[derive(Args, Debug)]
pub struct BenchMarchArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Camera index or name.
    #[arg(long, default_value = "0")]
    pub camera: String,
    /// Image sizes to time, WxH.
    #[arg(long, value_delimiter = ',', default_values = ["320x180", "1280x720"])]
    pub sizes: Vec<String>,
    /// Frames per timing (the first is dropped).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// samples_per_ray values for the error table.
    #[arg(long, value_delimiter = ',', default_values = ["32", "64", "128", "256", "512", "1024", "2048"])]
    pub steps: Vec<u32>,
    /// Size of the error-table images, WxH.
    #[arg(long, default_value = "160x90")]
    pub error_size: String,
    /// Path-traced samples per pixel of the reference (recipe scenes only).
    #[arg(long, default_value_t = 64)]
    pub reference_samples: u32,
}

/// Runs `bench-march`.
pub fn run(ctx: &Arc<Context>, args: &BenchMarchArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let spec = scene.camera(&args.camera)?.clone();
    let field = scene_field(&scene, args.field.as_deref(), true, Some(ctx.info()))?;
    let gpu_field = GpuGridField::upload(ctx, &field)?;
    let library = gpu_field.library(&inlay_passes::shaders::library()?);
    let knobs = scene.march;
    println!(
        "Device: {} ({:?}); field {}x{}x{}; samples_per_ray {}, termination {:e}, skip_empty {}\n",
        ctx.info().name,
        ctx.info().kind,
        field.resolution.x,
        field.resolution.y,
        field.resolution.z,
        knobs.samples_per_ray,
        knobs.termination,
        knobs.skip_empty
    );
    println!("| image | march ms p50 | p95 | Mrays/s | samples/ray | Msamples/s |");
    println!("| --- | --- | --- | --- | --- | --- |");
    // The frame every command renders, without the scene's objects: the
    // march alone.
    let mut bare = scene.clone();
    bare.objects.clear();
    bare.object_sources.clear();
    let mut view = InsertionView::new(
        ctx,
        &library,
        &bare,
        MarchPass::new(ctx, &library, knobs)?,
        gpu_field,
        spec.clone(),
        true,
    )?;
    for size in &args.sizes {
        let (w, h) = parse_size(size)?;
        let run = run_headless(ctx, &mut view, w, h, args.frames.max(2), 0.0)?;
        let mut ms: Vec<f64> = run
            .timings
            .iter()
            .skip(1)
            .flat_map(|t| {
                t.passes
                    .iter()
                    .filter(|p| p.name == inlay_passes::march::NERF_MARCH)
                    .map(|p| p.gpu_ms)
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        let (p50, p95) = (quantile(&ms, 0.5), quantile(&ms, 0.95));
        // The CPU mirror takes the same steps: count the samples it evaluates.
        let frame = CameraFrame::new(&spec, w, h);
        let samples: u64 = march_image(&field, &frame, &knobs, &|_, _| f64::INFINITY)
            .iter()
            .map(|r| r.samples as u64)
            .sum();
        let rays = (w * h) as f64;
        println!(
            "| {w}×{h} | {p50:.2} | {p95:.2} | {:.2} | {:.1} | {:.1} |",
            rays / p50 / 1e3,
            samples as f64 / rays,
            samples as f64 / p50 / 1e3
        );
    }
    let (w, h) = parse_size(&args.error_size)?;
    let fine_knobs = MarchKnobs {
        samples_per_ray: 8192,
        termination: 0.0,
        ..knobs
    };
    view.frame.march = MarchPass::new(ctx, &library, fine_knobs)?;
    let fine = run_headless(ctx, &mut view, w, h, 1, 0.0)?.image;
    let reference = scene.recipe().map(|recipe| {
        render_reference(
            recipe,
            &scene.environment,
            &[],
            &CameraFrame::new(&spec, w, h),
            &ReferenceOptions {
                samples: args.reference_samples,
                bounces: scene.bake.bounces,
                seed: 1,
                antialias: false,
                sky_behind: false,
            },
            &|_, _| {},
        )
    });
    println!(
        "\nError at {w}×{h} (mean |Δ| / mean radiance) against a march with 8192 samples per ray \
         and no early termination, and against the path-traced reference ({} spp):\n",
        args.reference_samples
    );
    println!("| samples_per_ray | step (scene units) | vs fine march | vs path-traced reference |");
    println!("| --- | --- | --- | --- |");
    for &n in &args.steps {
        let k = MarchKnobs {
            samples_per_ray: n,
            ..knobs
        };
        view.frame.march = MarchPass::new(ctx, &library, k)?;
        let img = run_headless(ctx, &mut view, w, h, 1, 0.0)?.image;
        println!(
            "| {n} | {:.4} | {:.4} | {} |",
            k.step(field.bounds.diagonal()),
            relative_error(&img, &fine.pixels),
            reference
                .as_ref()
                .map(|r| format!("{:.4}", relative_error(&img, r)))
                .unwrap_or_else(|| "–".into())
        );
    }
    Ok(())
}
