//! `inlay render SCENE`: renders a scene headless from one of its cameras:
//! the field with the scene's objects inserted (probe, SG fit, G-buffer,
//! clipped march, SG shading, compositing), or the bare field.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use inlay_engine::Context;
use inlay_passes::envest::load_environment_file;
use inlay_passes::scene::{load_scene, ObjectEnvironment};
use inlay_passes::ssdf::OutsideMode;

use crate::headless::{check_frame_size, run_headless};
use crate::outputs::check_image_output;
use crate::scene_view::open_view;

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
    /// Light the objects with this environment file (`inlay estimate-env`) instead of the scene's.
    #[arg(long)]
    pub environment: Option<PathBuf>,
    /// Segments across the field's diagonal (overrides `[march] samples_per_ray`).
    #[arg(long)]
    pub samples_per_ray: Option<u32>,
    /// Early-termination transmittance (overrides `[march] termination`).
    #[arg(long)]
    pub termination: Option<f64>,
    /// Turn off empty-space skipping.
    #[arg(long)]
    pub no_skip: bool,
    /// Frames to render (timings are taken over all of them).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
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
    /// SG lobes for GGX's normal distribution (overrides `[shading] ndf_lobes`).
    #[arg(long)]
    pub ndf_lobes: Option<u32>,
    /// Rays a side per tile for the field's light at the object's surface
    /// (overrides `[shading] field_light`; 0: off).
    #[arg(long)]
    pub field_light: Option<u32>,
    /// Draw no shadows (neither self-shadows nor the cast shadow).
    #[arg(long)]
    pub no_shadows: bool,
    /// Draw no self-shadows on the objects.
    #[arg(long)]
    pub no_self_shadow: bool,
    /// Draw no shadow cast onto the field.
    #[arg(long)]
    pub no_cast_shadow: bool,
    /// Leave the objects' outlines single-sampled (no `object-edge-aa`).
    #[arg(long)]
    pub no_edge_aa: bool,
    /// How the SSDF is read outside its grid: correct, clamp or infinity (overrides `[shadows] outside`).
    #[arg(long, value_parser = parse_outside)]
    pub shadow_outside: Option<OutsideMode>,
    /// SSDF grid nodes per axis for objects baked on first use (overrides `[shadows] grid`).
    #[arg(long)]
    pub ssdf_grid: Option<u32>,
    /// SSDF direction map side for objects baked on first use (overrides `[shadows] directions`).
    #[arg(long)]
    pub ssdf_directions: Option<u32>,
    /// SSDF PCA components for objects baked on first use (overrides `[shadows] components`).
    #[arg(long)]
    pub ssdf_components: Option<u32>,
    /// SSDF coarse angle for objects baked on first use, radians; 0 bakes
    /// every node (overrides `[shadows] coarse_angle`).
    #[arg(long)]
    pub ssdf_coarse_angle: Option<f64>,
}

fn parse_outside(s: &str) -> Result<OutsideMode, String> {
    OutsideMode::ALL
        .into_iter()
        .find(|m| m.name() == s)
        .ok_or_else(|| format!("`{s}` is not one of correct, clamp, infinity"))
}

/// Runs `render` on a context made with `options`.
pub fn run(ctx: &Arc<Context>, args: &RenderArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.exposure.is_finite() && args.exposure > 0.0,
        "--exposure must be a positive number, got {}",
        args.exposure
    );
    for out in &args.out {
        check_image_output("--out", out)?;
    }
    check_frame_size(ctx.info(), args.width, args.height)?;
    let mut scene = load_scene(&args.scene)?;
    if args.no_objects {
        scene.objects.clear();
    }
    if let Some(file) = &args.environment {
        let light = load_environment_file(file)?;
        scene.object_environment = Some(ObjectEnvironment::new(file.clone(), light));
    }
    scene.shading.ndf_lobes = args.ndf_lobes.unwrap_or(scene.shading.ndf_lobes);
    scene.shading.field_light = args.field_light.unwrap_or(scene.shading.field_light);
    scene.shadows.self_shadow &= !(args.no_shadows || args.no_self_shadow);
    scene.shadows.cast &= !(args.no_shadows || args.no_cast_shadow);
    scene.shadows.outside = args.shadow_outside.unwrap_or(scene.shadows.outside);
    let bake = &mut scene.shadows.bake;
    bake.grid = args.ssdf_grid.unwrap_or(bake.grid);
    bake.directions = args.ssdf_directions.unwrap_or(bake.directions);
    bake.components = args
        .ssdf_components
        .unwrap_or(bake.components)
        .min(bake.directions.pow(2))
        .min(bake.grid.pow(3));
    bake.coarse_angle = args.ssdf_coarse_angle.unwrap_or(bake.coarse_angle);
    if let Some((k, m)) = bake.problem() {
        anyhow::bail!("--ssdf-{}: {m}", k.replace('_', "-"));
    }
    let mut knobs = scene.march;
    knobs.samples_per_ray = args.samples_per_ray.unwrap_or(knobs.samples_per_ray);
    knobs.termination = args.termination.unwrap_or(knobs.termination);
    knobs.skip_empty &= !args.no_skip;
    let library = inlay_passes::shaders::library()?;
    let mut view = open_view(
        ctx,
        &library,
        &scene,
        knobs,
        args.field.as_deref(),
        &args.camera,
        !args.no_cache,
    )?;
    if args.no_edge_aa {
        let mut effects = view.effects();
        effects.edge_aa = false;
        view.set_effects(effects);
    }
    let run = run_headless(ctx, &mut view, args.width, args.height, args.frames, 0.0)?;
    let bad = run.image.non_finite_count();
    anyhow::ensure!(bad == 0, "the frame has {bad} non-finite pixels");
    run.report(ctx, &args.out, args.exposure)
}
