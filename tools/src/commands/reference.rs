//! `inlay reference SCENE`: the ground-truth image of a recipe's camera,
//! path traced over the analytic primitives (no field) with the scene's
//! objects inserted (triangles in a BVH, the same BRDF as the shading).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use inlay_engine::HdrImage;
use inlay_passes::bake::{render_reference, ReferenceOptions};
use inlay_passes::camera::CameraFrame;
use inlay_passes::scene::load_scene;

use crate::field_source::progress_bar;
use crate::outputs::{check_image_output, Outputs};

/// Options of `reference`.
#[derive(Args, Debug)]
pub struct ReferenceArgs {
    /// The scene file (TOML with a `[recipe]`).
    pub scene: PathBuf,
    /// Camera index or name.
    #[arg(long, default_value = "0")]
    pub camera: String,
    /// Width in pixels.
    #[arg(long, default_value_t = 320)]
    pub width: u32,
    /// Height in pixels.
    #[arg(long, default_value_t = 180)]
    pub height: u32,
    /// Output images: .exr (r, g, b, coverage) linear, or .png tonemapped. Repeatable.
    #[arg(long, default_values = ["inlay-reference.exr"])]
    pub out: Vec<PathBuf>,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    pub samples: u32,
    /// Indirect bounces (default: the scene's `[bake] bounces`, so it matches the field).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Jitter samples across each pixel (default: pixel centres, as the march).
    #[arg(long)]
    pub antialias: bool,
    /// Exposure multiplier for PNG output.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Trace the bare scene, without its objects.
    #[arg(long)]
    pub no_objects: bool,
}

/// Runs `reference`.
pub fn run(args: &ReferenceArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=16384).contains(&args.width) && (1..=16384).contains(&args.height),
        "image size {}x{} is out of range (1..=16384 per side)",
        args.width,
        args.height
    );
    anyhow::ensure!(args.samples >= 1, "--samples must be at least 1");
    for out in &args.out {
        check_image_output("--out", out)?;
    }
    let scene = load_scene(&args.scene)?;
    let recipe = scene.recipe().ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the scene's field is a file, not a [recipe]: there is no ground truth to trace",
            scene.path.display()
        )
    })?;
    let camera = CameraFrame::new(scene.camera(&args.camera)?, args.width, args.height);
    let options = ReferenceOptions {
        samples: args.samples,
        bounces: args.bounces.unwrap_or(scene.bake.bounces),
        seed: args.seed,
        antialias: args.antialias,
        sky_behind: false,
    };
    let started = Instant::now();
    let bar = progress_bar("tracing", args.height as u64);
    let objects = if args.no_objects {
        &[][..]
    } else {
        &scene.objects[..]
    };
    let pixels = render_reference(
        recipe,
        &scene.environment,
        objects,
        &camera,
        &options,
        &|d, _| bar.set_position(d),
    );
    bar.finish_and_clear();
    eprintln!(
        "traced {}x{} at {} samples per pixel in {:.2} s",
        args.width,
        args.height,
        args.samples,
        started.elapsed().as_secs_f64()
    );
    let image = HdrImage {
        width: args.width,
        height: args.height,
        pixels,
    };
    let mut outputs = Outputs::new();
    for out in &args.out {
        outputs.image(out, &image, args.exposure)?;
    }
    outputs.commit(None)?;
    Ok(())
}
