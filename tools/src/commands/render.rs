//! `inlay render SCENE`: renders a scene headless from one of its cameras:
//! the field with the scene's objects inserted (probe, SG fit, G-buffer,
//! clipped march, SG shading, compositing), or the bare field.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use inlay_engine::Context;
use inlay_passes::field::GpuGridField;
use inlay_passes::march::MarchPass;
use inlay_passes::scene::load_scene;

use crate::field_source::scene_field;
use crate::headless::run_headless;
use crate::insertion_view::InsertionView;

/// Options of `render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Camera index or name.
    #[arg(long, default_value = "0")]
    pub camera: String,
    /// Width in pixels.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Height in pixels.
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// Output images: .exr holds linear (colour, coverage); .png is tonemapped over black. Repeatable.
    #[arg(long, default_values = ["inlay-render.png"])]
    pub out: Vec<PathBuf>,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Segments across the field's diagonal (overrides [march] samples_per_ray).
    #[arg(long)]
    pub samples_per_ray: Option<u32>,
    /// Early-termination transmittance (overrides [march] termination).
    #[arg(long)]
    pub termination: Option<f64>,
    /// Turn off empty-space skipping.
    #[arg(long)]
    pub no_skip: bool,
    /// Frames to render (timings are taken over all of them).
    #[arg(long, default_value_t = 4)]
    pub frames: u32,
    /// Exposure multiplier for PNG output.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Bake the recipe again even if a cached field exists.
    #[arg(long)]
    pub no_cache: bool,
    /// Render the bare field, without the scene's objects.
    #[arg(long)]
    pub no_objects: bool,
    /// SG lobes for GGX's normal distribution (overrides [shading] ndf_lobes).
    #[arg(long)]
    pub ndf_lobes: Option<u32>,
}

/// Runs `render` on a context made with `options`.
pub fn run(ctx: &Arc<Context>, args: &RenderArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.exposure.is_finite() && args.exposure > 0.0,
        "--exposure must be a positive number, got {}",
        args.exposure
    );
    let mut scene = load_scene(&args.scene)?;
    if args.no_objects {
        scene.objects.clear();
    }
    scene.shading.ndf_lobes = args.ndf_lobes.unwrap_or(scene.shading.ndf_lobes);
    let camera = scene.camera(&args.camera)?.clone();
    let mut knobs = scene.march;
    knobs.samples_per_ray = args.samples_per_ray.unwrap_or(knobs.samples_per_ray);
    knobs.termination = args.termination.unwrap_or(knobs.termination);
    knobs.skip_empty &= !args.no_skip;
    knobs
        .check()
        .map_err(|(k, m)| anyhow::anyhow!("march knob `{k}`: {m}"))?;
    let field = scene_field(&scene, args.field.as_deref(), !args.no_cache)?;
    let library = crate::shaders::library()?;
    let view = InsertionView::new(
        ctx,
        &library,
        &scene,
        MarchPass::new(ctx, &library, knobs)?,
        GpuGridField::upload(ctx, &field)?,
        camera,
    )?;
    let run = run_headless(ctx, &view, args.width, args.height, args.frames.max(1), 0.0)?;
    let bad = run.image.non_finite_count();
    anyhow::ensure!(bad == 0, "the frame has {bad} non-finite pixels");
    run.report(ctx, &args.out, args.exposure)
}
