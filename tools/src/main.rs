//! `inlay`: inserts virtual objects into HDR radiance fields in real time.
#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use inlay::commands::on_device;
use inlay::demo::{DemoPipelines, DemoScene};
use inlay::headless::run_headless;
use inlay::timings_table::format_table;
use inlay::window_app::{run_window, WindowError, WindowOptions};
use inlay_engine::window::PresentMode;
use inlay_engine::{Context, ContextOptions};

#[derive(Parser)]
#[command(
    name = "inlay",
    version,
    about = "Virtual objects inserted into HDR radiance fields, in real time, on Vulkan"
)]
struct Cli {
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(subcommand)]
    command: Command,
}

#[derive(Args, Clone)]
struct GpuArgs {
    /// Turn on the Vulkan validation layer; its messages go to the log and any error fails the run.
    #[arg(long, global = true)]
    validate: bool,
    /// Use the Vulkan device whose name contains this text (default: discrete > integrated > CPU).
    #[arg(long, global = true, env = "INLAY_DEVICE")]
    device: Option<String>,
}

impl GpuArgs {
    fn options(&self) -> ContextOptions {
        ContextOptions {
            validate: self.validate,
            device: self.device.clone(),
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Open a scene in a window: drag its objects across the field, edit them, switch effects and presets (headless PNG without a display).
    View(inlay::view::ViewArgs),
    /// Run the engine demo (two compute passes feeding a raster pass with depth) in a window, or headless.
    Demo(DemoArgs),
    /// Bake a scene's recipe of analytic primitives into a grid-field file (path traced).
    BakeScene(inlay::commands::bake_scene::BakeSceneArgs),
    /// Bake an object's SSDF field (its visibility from around it, for shadows) on the GPU.
    BakeSsdf(inlay::commands::bake_ssdf::BakeSsdfArgs),
    /// Estimate the distant environment light the field does not show (SG lobes) and write it as an environment file.
    EstimateEnv(inlay::commands::estimate_env::EstimateEnvArgs),
    /// Read a dataset of posed photographs (transforms.json: Blender synthetic, instant-ngp or nerfstudio) and report its frames, cameras, bounds and unusable pixels.
    Dataset(inlay::commands::dataset::DatasetArgs),
    /// Path trace a training set of a recipe scene: EXR views from a cap of cameras and their transforms.json (instant-ngp convention), optionally bracketed sRGB PNGs.
    RenderViews(inlay::commands::render_views::RenderViewsArgs),
    /// Train a grid radiance field on the GPU from posed photographs (transforms.json) and score held-out views.
    Train(inlay::commands::train::TrainArgs),
    /// Render a scene's radiance field headless from one of its cameras.
    Render(inlay::commands::render::RenderArgs),
    /// Run N frames with the objects inserted and print the paper's Table 1 (median/p95 per module); writes JSON and a Chrome trace.
    Profile(inlay::commands::profile::ProfileArgs),
    /// Measure the speed/accuracy trade: time and error against the ground truth over a grid of the quality knobs; writes a table, the Pareto front and a plot.
    Sweep(inlay::commands::sweep::SweepArgs),
    /// Measure the march: rays/s and samples/s per image size, and its error as the step size changes.
    BenchMarch(inlay::commands::bench_march::BenchMarchArgs),
    /// Path trace the ground-truth image of a recipe scene's camera (no field).
    Reference(inlay::commands::reference::ReferenceArgs),
    /// Measure inlay against Blender Cycles renders of the scene (tools/cycles/render_cycles.py): reference, field, insertion, shadow, probe irradiance.
    Fidelity(inlay::commands::fidelity::FidelityArgs),
    /// Trace the incident-light probe at a point and fit SG lighting to it; writes probe | fit | error.
    Probe(inlay::commands::probe::ProbeArgs),
    /// Measure the SG fit: residual against iterations and lobes, time per iteration and per probe trace.
    BenchSg(inlay::commands::bench_sg::BenchSgArgs),
    /// Measure the SG shading's error against brute force as the light's and the NDF's lobe counts change.
    BenchShade(inlay::commands::bench_shade::BenchShadeArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum PresentArg {
    Fifo,
    FifoRelaxed,
    Mailbox,
    Immediate,
}

#[derive(Args)]
struct DemoArgs {
    /// Render offscreen and write images instead of opening a window.
    #[arg(long)]
    headless: bool,
    /// Output images (headless): .exr is linear HDR, .png is tonemapped sRGB. Repeatable.
    #[arg(long, default_values = ["inlay-demo.exr", "inlay-demo.png"])]
    out: Vec<PathBuf>,
    /// Width in pixels (headless image or initial window).
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Height in pixels.
    #[arg(long, default_value_t = 360)]
    height: u32,
    /// Frames to render (headless default 8; window: until closed).
    #[arg(long)]
    frames: Option<u64>,
    /// Animation time of the first frame, in seconds (headless).
    #[arg(long, default_value_t = 0.0)]
    time: f32,
    /// Exposure multiplier applied before tonemapping (PNG and window).
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Consume the heat-map debug image so its pass is not culled.
    #[arg(long)]
    keep_heatmap: bool,
    /// Presentation mode of the window.
    #[arg(long, value_enum, default_value_t = PresentArg::Fifo)]
    present_mode: PresentArg,
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Demo(args) => demo(&cli.gpu, args),
        Command::View(args) => inlay::view::run(&cli.gpu.options(), args),
        Command::BakeScene(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::bake_scene::run(ctx.info(), args)
        }),
        Command::BakeSsdf(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::bake_ssdf::run(ctx, args)
        }),
        Command::EstimateEnv(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::estimate_env::run(ctx, args)
        }),
        Command::Render(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::render::run(ctx, args)
        }),
        Command::Profile(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::profile::run(ctx, args)
        }),
        Command::Reference(args) => inlay::commands::reference::run(args),
        Command::Sweep(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::sweep::run(ctx, args)
        }),
        Command::BenchMarch(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::bench_march::run(ctx, args)
        }),
        Command::Fidelity(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::fidelity::run(ctx, args)
        }),
        Command::Probe(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::probe::run(ctx, args)
        }),
        Command::BenchSg(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::bench_sg::run(ctx, args)
        }),
        Command::BenchShade(args) => inlay::commands::bench_shade::run(args),
        Command::Dataset(args) => inlay::commands::dataset::run(args),
        Command::RenderViews(args) => inlay::commands::render_views::run(args),
        Command::Train(args) => on_device(&cli.gpu.options(), |ctx| {
            inlay::commands::train::run(ctx, args)
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("inlay: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn demo(gpu: &GpuArgs, args: &DemoArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.exposure.is_finite() && args.exposure > 0.0,
        "--exposure must be a positive number, got {}",
        args.exposure
    );
    if args.headless {
        for out in &args.out {
            inlay::outputs::check_image_output("--out", out)?;
        }
    }
    let library = inlay_passes::shaders::library()?;
    if !args.headless {
        let options = WindowOptions {
            context: gpu.options(),
            title: "inlay demo".into(),
            size: (args.width.max(1), args.height.max(1)),
            present_mode: match args.present_mode {
                PresentArg::Fifo => PresentMode::Fifo,
                PresentArg::FifoRelaxed => PresentMode::FifoRelaxed,
                PresentArg::Mailbox => PresentMode::Mailbox,
                PresentArg::Immediate => PresentMode::Immediate,
            },
            frames: args.frames,
            exposure: args.exposure,
        };
        let keep_heatmap = args.keep_heatmap;
        let factory = Box::new(
            move |ctx: &std::sync::Arc<Context>,
                  lib: &inlay_engine::shader::ShaderLibrary|
                  -> anyhow::Result<Box<dyn inlay::window_app::WindowScene>> {
                Ok(Box::new(inlay::window_app::Passive(Box::new(DemoScene {
                    pipelines: DemoPipelines::new(ctx, lib)?,
                    keep_heatmap,
                }))))
            },
        );
        match run_window(options, library.clone(), factory) {
            Ok(timings) => {
                print!("{}", format_table(&timings, "the window's device"));
                return Ok(());
            }
            Err(WindowError::NoDisplay(why)) => {
                eprintln!("inlay: {why}; rendering headless instead")
            }
            Err(WindowError::Other(e)) => return Err(e),
        }
    }
    let ctx = Context::new(&gpu.options(), None)?;
    let mut scene = DemoScene {
        pipelines: DemoPipelines::new(&ctx, &library)?,
        keep_heatmap: args.keep_heatmap,
    };
    let frames = args.frames.unwrap_or(8).clamp(1, 100_000) as u32;
    let run = run_headless(&ctx, &mut scene, args.width, args.height, frames, args.time)?;
    run.report(&ctx, &args.out, args.exposure)
}
