//! `inlay train DATASET --out FIELD.inlayfield`: trains a grid radiance
//! field on the GPU from posed photographs (`transforms.json`, see
//! `docs/datasets.md`), coarse to fine, and scores the views it held out.
//! A time budget or Ctrl-C ends the run early with a valid field (a second
//! Ctrl-C kills it); `--resume` continues from a field. The field and the
//! hold-out picture are put in place only when the run completes.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use clap::Args;
use glam::DVec3;
use inlay_engine::{Context, HdrImage};
use inlay_passes::dataset::{load_dataset, LoadOptions};
use inlay_passes::field::seen_lights::{seen_lights_path, seen_lights_text};
use inlay_passes::field::{checked_field_bytes, sky_path};
use inlay_passes::geometry::Aabb;
use inlay_passes::train::completing::{completion_runs, train_completing, CompletedTraining};
use inlay_passes::train::planes::Completion;
use inlay_passes::train::{default_iterations, TrainControl, TrainKnobs};
use inlay_passes::train::{depth_error_colour, PixelDepth};

use crate::commands::auto_value::{parse_auto, Auto};
use crate::commands::dataset::{parse_bounds, parse_rgb};
use crate::field_source::progress_bar;
use crate::outputs::{check_image_output, check_output, Outputs};

/// Arguments of `inlay train`.
#[derive(Args, Debug)]
pub struct TrainArgs {
    /// The dataset: a transforms.json, or a folder holding one.
    pub dataset: PathBuf,
    /// The field file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Nodes along the field's longest axis.
    #[arg(long, default_value_t = TrainKnobs::default().resolution)]
    pub resolution: u32,
    /// Coarse-to-fine stages (the grid doubles between them).
    #[arg(long, default_value_t = TrainKnobs::default().stages)]
    pub stages: u32,
    /// Share of the steps the first, coarsest stage takes (the later
    /// stages split the rest evenly).
    #[arg(long, default_value_t = TrainKnobs::default().first_stage_share)]
    pub first_stage_share: f64,
    /// Each density is multiplied by 2^P when a stage's grid doubles: 0
    /// carries the field unchanged, 1 keeps each node's optical depth per
    /// spacing (surfaces as steep per node as on the coarser grid).
    /// `auto` (the default): 0.5 behind a random background, else 0.
    #[arg(long, value_parser = parse_auto::<f64>, default_value = "auto")]
    pub refine_density_exponent: Auto<f64>,
    /// Optimiser steps of each run. Default: 3000 up to 128 nodes along
    /// the longest axis, 2000 × (nodes / 128)² above where that is more
    /// (256: 8000), for the `--resume` field's resolution when resuming;
    /// two thirds of that for each of two runs (`--planes`).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Rays per step.
    #[arg(long, default_value_t = TrainKnobs::default().batch)]
    pub batch: u32,
    /// March samples along the field's diagonal on the final grid (a
    /// coarser stage takes --coarse-samples × as many per node spacing:
    /// 128 on the 32-node stage of a 128-node run).
    #[arg(long, default_value_t = TrainKnobs::default().samples_per_ray)]
    pub samples_per_ray: u32,
    /// A coarse stage's samples per node spacing, as a multiple of the
    /// final grid's (4 on a three-stage run: every stage at
    /// --samples-per-ray).
    #[arg(long, default_value_t = TrainKnobs::default().coarse_samples)]
    pub coarse_samples: f64,
    /// Colour step size (fraction of the mean radiance; a colour above 8 × the loss's floor steps by this fraction of itself).
    #[arg(long, default_value_t = TrainKnobs::default().rate)]
    pub rate: f64,
    /// Density step size (per field diagonal).
    #[arg(long, default_value_t = TrainKnobs::default().density_rate)]
    pub density_rate: f64,
    /// The relative loss's floor (fraction of the mean radiance): below
    /// it errors count absolutely, above it relatively.
    #[arg(long, default_value_t = TrainKnobs::default().epsilon)]
    pub epsilon: f64,
    /// The radiance `--rate`, `--epsilon` and the starting grey are
    /// fractions of (default: the photographs' mean luminance, pixels that
    /// look past the bounds counted black, a photograph more than 4 times
    /// as bright as the median one left out). For a light that most views
    /// see but the field does not hold, the field's own surfaces' level.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Total variation's weight on neighbouring nodes' colour differences.
    #[arg(long, default_value_t = TrainKnobs::default().tv_colour)]
    pub tv_colour: f64,
    /// The colour difference between neighbouring nodes, as a share of
    /// the radiance scale, from which the colour's total variation pulls
    /// by a bounded amount rather than in proportion: a speckle below it
    /// is smoothed, a lamp above it keeps its radiance (0: squared
    /// differences everywhere).
    #[arg(long, default_value_t = TrainKnobs::default().tv_colour_edge)]
    pub tv_colour_edge: f64,
    /// Total variation's weight on neighbouring nodes' density differences.
    #[arg(long, default_value_t = TrainKnobs::default().tv_density)]
    pub tv_density: f64,
    /// Optical depth per node spacing (σ·h) from which a density step
    /// between neighbouring nodes is smoothed by a bounded pull rather than
    /// in proportion: a surface's rise stays sharp, a haze below it is
    /// smoothed (0: squared differences everywhere).
    #[arg(long, default_value_t = TrainKnobs::default().tv_edge)]
    pub tv_edge: f64,
    /// Weight of the density's sparsity prior, taken with total variation:
    /// pulls a density below its edge (a haze) toward zero and leaves an
    /// opaque surface be (0: none). `auto` (the default): 2e-3 behind a
    /// random background, which clears the haze the steeper refinement
    /// leaves in front of the surfaces, else 1e-3; more clears more haze,
    /// and can put plain surfaces behind where they are and costs foliage
    /// and other faint matter. Stated for 128 nodes: a grid of r > 128
    /// nodes applies it × (128 / r)², as its steps grow by (r / 128)².
    #[arg(long, value_parser = parse_auto::<f64>, default_value = "auto")]
    pub sparsity: Auto<f64>,
    /// The sparsity prior's edge, an optical depth per node spacing (σ·h):
    /// the density it pulls hardest. A haze well below it is pulled toward
    /// zero in proportion; matter well above it (an opaque surface, a
    /// medium such as foliage or glass) hardly at all (0: squared
    /// everywhere). `auto` (the default): 0.03, which spares foliage and
    /// glass (about 0.05–0.1 a spacing at 128 nodes) and leaves a little
    /// more haze in front of plain surfaces; 0.1 behind a random
    /// background, whose steeper refinement leaves more haze there (pass
    /// 0.03 where faint matter matters more than the surfaces' last
    /// spacing).
    #[arg(long, value_parser = parse_auto::<f64>, default_value = "auto")]
    pub sparsity_edge: Auto<f64>,
    /// Weight of the distortion loss (Mip-NeRF 360's): pulls each ray's
    /// weight into one short stretch (0: none). With the other defaults it
    /// can thicken a faint haze in front of the surfaces into them
    /// rather than clear it: measure before relying on it. As a second
    /// step (--resume, with --tv-edge 0.02) it thins plain opaque
    /// surfaces and costs media such as foliage.
    #[arg(long, default_value_t = TrainKnobs::default().distortion)]
    pub distortion: f64,
    /// Weight of the depth maps' loss, for datasets whose frames name one
    /// (`depth_file_path`: z-depths, as phones' LiDAR captures and
    /// `inlay render-views --depth` write them): holds each ray's weight
    /// at the recorded surface, where a photograph of a plain surface
    /// cannot place it (0: ignore the maps). For noisy maps (a phone's)
    /// try 0.3 too, on the held-out views: noise leaves surfaces soft.
    #[arg(long, default_value_t = TrainKnobs::default().depth_weight)]
    pub depth_weight: f64,
    /// The depth loss's tolerance, in node spacings of the final grid:
    /// quadratic within it, linear beyond.
    #[arg(long, default_value_t = TrainKnobs::default().depth_tolerance)]
    pub depth_tolerance: f64,
    /// Each step's rays end on a random colour behind the field instead of
    /// `--background`, so that surfaces train opaque rather than
    /// translucent; photographs with an alpha channel take the same colour
    /// behind their transparent part (refused for transparent exposure
    /// brackets). `auto` (the default): on where the photographs are
    /// linear with some pixel's alpha below 1 (they say where nothing
    /// is) and no sky is asked for, else off; the flag alone: on.
    #[arg(long, value_parser = parse_switch, default_value = "auto", num_args = 0..=1, default_missing_value = "on")]
    pub random_background: Switch,
    /// Learn a sky behind the field instead of `--background`: what the
    /// photographs see past the bounds, as an equirect map of 2N x N
    /// texels (N this; 0: none), written beside the field as
    /// FIELD.sky.exr (and read from beside the `--resume` field). `auto`
    /// (the default): the `--resume` field's sky where it has one, else
    /// N = 8 where at least 1 % of the views' light lies past the
    /// bounds, none otherwise.
    #[arg(long, value_parser = parse_auto::<u32>, default_value = "auto")]
    pub sky: Auto<u32>,
    /// Degree of view-dependent colour (spherical harmonics, 0..=2; 0 is
    /// one colour per node). Degree 1 adds 3 RGB coefficients a node,
    /// degree 2 8, to the file and to the device's memory. Default: the
    /// `--resume` field's degree, else 0.
    #[arg(long)]
    pub sh_degree: Option<u32>,
    /// Share of all the steps, at the start of the first of several
    /// stages, trained at degree 1 where --sh-degree is 0, the
    /// coefficients dropped after it: a wall lit on one face and dark on
    /// the other forms in place rather than in front of its nodes the
    /// views from behind pull dark (0: none; it ends with the first stage at
    /// the latest).
    #[arg(long, default_value_t = TrainKnobs::default().view_dependent_start)]
    pub view_dependent_start: f64,
    /// Learn an RGB exposure gain per frame (the first frame's fixed):
    /// for photographs whose exposure is unknown. Held-out views are
    /// scored at the gain that fits them best.
    #[arg(long)]
    pub learn_exposure: bool,
    /// At the end, the density of every node whose largest rendering
    /// weight in any training ray is below this is set to zero: what no
    /// photograph sees (0 keeps every node).
    #[arg(long, default_value_t = TrainKnobs::default().prune)]
    pub prune: f64,
    /// Train the stages after the first only in the bricks of 8³ nodes
    /// around what the stage before made visible (the default; `--sparse=false`
    /// trains them dense where the grid fits the device's storage binding).
    #[arg(
        long,
        default_value_t = TrainKnobs::default().sparse,
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "true",
        action = clap::ArgAction::Set
    )]
    pub sparse: bool,
    /// Draw each training ray through a random point of its pixel (of its
    /// share of the pixel with --area-rays), as the
    /// photograph gathered the pixel's light over its area, instead of
    /// through its centre (off by default: with one ray a pixel it blurred
    /// the fields of DOG's and PLANTS' Cycles sets by 0.2-2.4 dB).
    #[arg(
        long,
        default_value_t = TrainKnobs::default().jitter,
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "true",
        action = clap::ArgAction::Set
    )]
    pub jitter: bool,
    /// Each training pixel is the mean of N x N rays over its area, and
    /// the loss is taken on that mean (a step keeps --batch rays: 1/N² as
    /// many pixels); 1 is one ray through each pixel's centre. `auto` (the
    /// default): 2 where the photographs' pixels span more than 2 node
    /// spacings at the field's centre and no random background goes
    /// behind them (the Cycles sets' 96 x 96 views at 128 nodes: 0.06-3.05
    /// dB higher held out), else 1 (behind a random background, or with
    /// finer pixels, 2 left a haze in front of the surfaces).
    #[arg(long, value_parser = parse_auto::<u32>, default_value = "auto")]
    pub area_rays: Auto<u32>,
    /// Views never trained on, scored at the end.
    #[arg(long, default_value_t = 2)]
    pub hold_out: u32,
    /// Held-out views are rendered with N x N rays a pixel, averaged, as
    /// their photographs gathered it (1: the ray through each centre).
    #[arg(long, default_value_t = TrainKnobs::default().held_out_samples)]
    pub held_out_samples: u32,
    /// Stop after this many seconds (the field so far is written).
    #[arg(long)]
    pub time_budget: Option<f64>,
    /// Continue from this field (its resolution and bounds, one stage)
    /// instead of a grey grid; trained sparsely, it keeps every brick it
    /// holds a value in.
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Picture of the held-out views: photograph | field | difference.
    #[arg(long)]
    pub picture: Option<PathBuf>,
    /// The field's bounds, min x,y,z then max x,y,z (overrides the dataset's).
    #[arg(long, value_parser = parse_bounds, allow_hyphen_values = true)]
    pub bounds: Option<Aabb>,
    /// Radiance behind the field (linear RGB), and what transparent pixels
    /// of RGBA images are composited over.
    #[arg(long, value_parser = parse_rgb, default_value = "0,0,0")]
    pub background: [f32; 3],
    /// Leave out the frames that cannot be used instead of failing.
    #[arg(long)]
    pub skip_bad_frames: bool,
    /// Read each photograph at 1/N of its width and height (each N x N
    /// block one pixel, its mean; the intrinsics scaled to match): for
    /// photographs too many or too large for memory, which are refused
    /// before any pixel is read, naming the N that fits.
    #[arg(long, default_value_t = 1)]
    pub downscale: u32,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The recipe scene the dataset shows (one `render-views` rendered):
    /// each held-out view's geometry is scored against its surfaces, the
    /// field's expected depth against the first surface at each pixel, in
    /// node spacings (a floor that floats or that the camera sees through
    /// spoils occlusion, probes and shadows at any PSNR).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Picture of each held-out view's depth error against `--scene`'s
    /// surfaces, one view a row: white within a node spacing, bluer the
    /// further the field's surface lies in front (full at 4 spacings),
    /// redder behind; magenta where the camera sees through a surface,
    /// green where the field floats over nothing, black where neither
    /// holds anything.
    #[arg(long, requires = "scene")]
    pub depth_picture: Option<PathBuf>,
    /// Picture of how far each held-out view's surfaces spread along the
    /// ray, one view a row, for any dataset (no recipe needed): white where
    /// the field's weight gathers at a point, orange from 4 node spacings
    /// on, where the photographs left the depth open; black where the field
    /// holds no surface. A view of more than 65 536 pixels is drawn one
    /// pixel of each n × n block.
    #[arg(long)]
    pub spread_picture: Option<PathBuf>,
    /// Lights the training photographs show past the bounds (a bulb above
    /// the box): found where bright spots of several views meet, fitted
    /// as spheres, their pixels left out of training, drawn in the
    /// held-out views and written beside the field as FIELD.lights.toml
    /// (`on`, the default); `off` trains on every pixel as it is.
    #[arg(long, value_parser = parse_on_off, default_value = "on", action = clap::ArgAction::Set)]
    pub seen_lights: bool,
    /// Where the photographs leave surfaces open (a plain floor or wall,
    /// whose depth they cannot place), train twice: the planes through
    /// the surfaces the first run places give the open pixels a depth,
    /// and a second run holds them there as it would a depth map (`on`,
    /// the default, where some training frame has no depth map and not
    /// with --resume: each run takes two thirds of the default steps, the
    /// two 1.4–1.7 times one run's time); `off` trains once.
    #[arg(long, value_parser = parse_on_off, default_value = "on", action = clap::ArgAction::Set)]
    pub planes: bool,
}

/// A knob that is on, off, or chosen from the dataset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    /// Chosen from the dataset.
    Auto,
    /// On.
    On,
    /// Off.
    Off,
}

/// Parses `auto`, `on` or `off`.
pub fn parse_switch(s: &str) -> Result<Switch, String> {
    match s {
        "auto" => Ok(Switch::Auto),
        "on" => Ok(Switch::On),
        "off" => Ok(Switch::Off),
        _ => Err(format!("{s}: expected auto, on or off")),
    }
}

/// Parses `on` or `off`.
pub fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("{s}: expected on or off")),
    }
}

/// Runs `inlay train`.
pub fn run(ctx: &Arc<Context>, args: &TrainArgs) -> Result<()> {
    check_output("--out", &args.out, &["inlayfield"])?;
    if let Some(p) = &args.picture {
        check_image_output("--picture", p)?;
    }
    if let Some(p) = &args.depth_picture {
        check_image_output("--depth-picture", p)?;
    }
    if let Some(p) = &args.spread_picture {
        check_image_output("--spread-picture", p)?;
    }
    for (flag, asked) in [
        ("--picture", args.picture.is_some()),
        ("--depth-picture", args.depth_picture.is_some()),
        ("--spread-picture", args.spread_picture.is_some()),
    ] {
        if asked && args.hold_out == 0 {
            anyhow::bail!("{flag}: draws the held-out views, and --hold-out 0 holds none out");
        }
    }
    let resume = match &args.resume {
        Some(p) => Some(inlay_passes::field::load_field(p)?),
        None => None,
    };
    // The sky learnt with the `--resume` field, where there is one and a
    // sky is asked for (or may be).
    let resume_sky = match &args.resume {
        Some(p) if args.sky != Auto::Value(0) && sky_path(p).exists() => {
            Some(inlay_passes::field::Sky::load(&sky_path(p))?)
        }
        _ => None,
    };
    // The grid trained along its longest axis: a resumed field's own nodes.
    let nodes = resume
        .as_ref()
        .map_or(args.resolution, |f| f.resolution.max_element());
    let mut knobs = TrainKnobs {
        resolution: args.resolution,
        stages: args.stages,
        first_stage_share: args.first_stage_share,
        // Set below from the background where auto.
        refine_density_exponent: args.refine_density_exponent.or(0.0),
        // Set below once the runs are known where not given.
        iterations: args.iterations.unwrap_or_else(|| default_iterations(nodes)),
        batch: args.batch,
        samples_per_ray: args.samples_per_ray,
        coarse_samples: args.coarse_samples,
        rate: args.rate,
        density_rate: args.density_rate,
        epsilon: args.epsilon,
        scale: args.scale,
        tv_colour: args.tv_colour,
        tv_colour_edge: args.tv_colour_edge,
        tv_density: args.tv_density,
        tv_edge: args.tv_edge,
        // Set below from the background where auto.
        sparsity: args.sparsity.or(TrainKnobs::default().sparsity),
        sparsity_edge: args.sparsity_edge.or(TrainKnobs::default().sparsity_edge),
        distortion: args.distortion,
        depth_weight: args.depth_weight,
        depth_tolerance: args.depth_tolerance,
        planes: args.planes,
        // Set below from the photographs' alpha where auto.
        random_background: args.random_background == Switch::On,
        // Set below from the dataset's light past the bounds where auto.
        sky: args.sky.or(0),
        sh_degree: args.sh_degree.unwrap_or(
            resume
                .as_ref()
                .map_or(TrainKnobs::default().sh_degree, |f| f.sh_degree),
        ),
        view_dependent_start: args.view_dependent_start,
        prune: args.prune,
        sparse: args.sparse,
        learn_exposure: args.learn_exposure,
        jitter: args.jitter,
        // Set below from the pixels' width where auto (and checked there).
        area_rays: args.area_rays.or(1),
        held_out_samples: args.held_out_samples,
        seed: args.seed,
        ..TrainKnobs::default()
    };
    if let Err((k, m)) = knobs.check() {
        anyhow::bail!("--{}: {m}", k.replace('_', "-"));
    }
    inlay_passes::train::check_train_rays(
        ctx,
        knobs.samples_per_ray,
        knobs.highest_sh_degree(knobs.stages_run(resume.is_some())),
        knobs.rays_per_pixel(),
    )?;
    let budget = match args.time_budget {
        Some(s) if !(s.is_finite() && s > 0.0) => {
            anyhow::bail!("--time-budget {s}: must be positive seconds")
        }
        Some(s) => Some(Duration::from_secs_f64(s)),
        None => None,
    };
    let options = LoadOptions {
        bounds: args.bounds,
        background: args.background,
        skip_bad_frames: args.skip_bad_frames,
        downscale: args.downscale,
        memory_available: crate::commands::dataset::available_memory(),
        ..LoadOptions::default()
    };
    let mut dataset = load_dataset(&args.dataset, &options)?;
    // Two runs where the planes are to complete what the photographs leave
    // open, each of two thirds of the default steps where not told.
    let runs: u32 = match completion_runs(&dataset, &knobs, args.hold_out, resume.is_some()) {
        Ok(()) => 2,
        Err(_) => 1,
    };
    if args.iterations.is_none() {
        knobs.iterations = inlay_passes::train::knobs::default_run_iterations(nodes, runs);
    }
    let scene = match &args.scene {
        Some(p) => {
            let scene = inlay_passes::scene::load_scene(p)?;
            let Some(recipe) = scene.recipe() else {
                anyhow::bail!(
                    "--scene {}: its field is a file, not a [recipe]: it has no surfaces to score \
                     the geometry against",
                    p.display()
                );
            };
            // A dataset of another scene would be scored against surfaces
            // it does not show: render-views writes the recipe's bounds,
            // and `--bounds` may widen them to hold a surface that reaches
            // past them (the field is then scored against every surface
            // inside its own bounds).
            let (r, d) = (recipe.bounds, dataset.bounds);
            let tolerance = 1e-4 * r.diagonal();
            anyhow::ensure!(
                (d.min - r.min).max_element() <= tolerance
                    && (r.max - d.max).max_element() <= tolerance,
                "--scene {}: its recipe's bounds ({:.3?} to {:.3?}) are not within the dataset's \
                 ({:.3?} to {:.3?}): the geometry is scored on a dataset of that scene \
                 (`inlay render-views` writes the recipe's bounds)",
                p.display(),
                r.min.to_array(),
                r.max.to_array(),
                d.min.to_array(),
                d.max.to_array()
            );
            super::crossing_bounds::warn_crossing_bounds(p, recipe, d, "the dataset's");
            Some(scene)
        }
        None => None,
    };
    let b = dataset.bounds;
    eprintln!(
        "{}: {} frames ({} dialect); bounds {:.3} {:.3} {:.3} to {:.3} {:.3} {:.3} from {}",
        dataset.file.display(),
        dataset.frames.len(),
        dataset.dialect,
        b.min.x,
        b.min.y,
        b.min.z,
        b.max.x,
        b.max.y,
        b.max.z,
        dataset.bounds_source
    );
    if let Some(r) = dataset.skipped_report() {
        eprintln!("{r}");
    }
    let depth = inlay_passes::dataset::depth::DepthCounts::of(&dataset.frames);
    if let Some(line) = depth.line(dataset.frames.len()) {
        if knobs.depth_weight > 0.0 {
            eprintln!(
                "{line}: each of their rays held to it (--depth-weight {}, --depth-tolerance {} \
                 node spacings)",
                knobs.depth_weight, knobs.depth_tolerance
            );
        } else {
            eprintln!("{line}: ignored (--depth-weight 0)");
        }
    }
    if let Some(w) = dataset.blind_frames_warning() {
        eprintln!("warning: {}: {w}", dataset.file.display());
    }
    if let Some(w) = dataset.dark_frames_warning() {
        eprintln!("warning: {}: {w}", dataset.file.display());
    }
    if let Some(w) = dataset.turned_frames_warning() {
        eprintln!("warning: {}: {w}", dataset.file.display());
    }
    if let Some(w) = inlay_passes::train::pixels::saturated_in_every_bracket(&dataset).warning() {
        eprintln!("warning: {}: {w}", dataset.file.display());
    }
    let bounds = resume.as_ref().map_or(dataset.bounds, |f| f.bounds);
    let seen_lights = if args.seen_lights {
        super::seen_lights::find_and_mask(
            &mut dataset,
            args.hold_out,
            &bounds,
            knobs.scale,
            scene.as_ref().and_then(|s| s.recipe()),
        )
    } else {
        Vec::new()
    };
    // What the run chooses from its photographs (the sky, the random
    // background) it reads from its training frames alone.
    let training = inlay_passes::train::pixels::training_frames(&dataset, args.hold_out);
    let past = inlay_passes::train::past_bounds::light_past_bounds(&dataset, &training, &bounds);
    if let Some(w) = past.warning() {
        eprintln!("warning: {}: {w}", dataset.file.display());
    }
    if args.random_background == Switch::Auto {
        let alpha = inlay_passes::train::transparent_pixels(&dataset, &training);
        let sky_asked = resume_sky.is_some() || args.sky.or(0) > 0;
        knobs.random_background = alpha.takes_random_background() && !sky_asked;
        if knobs.random_background {
            eprintln!(
                "a random colour behind the field each step: {} pixels of the photographs have \
                 alpha below 1, so they say where nothing is (--random-background off keeps \
                 --background)",
                alpha.linear
            );
        }
    }
    if args.area_rays.is_auto() {
        let footprint =
            inlay_passes::train::pixels::pixel_footprint(&dataset, &training, &bounds, nodes);
        let n = knobs.auto_area_rays(footprint);
        let fits = inlay_passes::train::check_train_rays(
            ctx,
            knobs.samples_per_ray,
            knobs.highest_sh_degree(knobs.stages_run(resume.is_some())),
            n * n,
        );
        match (n > 1, fits) {
            (true, Ok(())) => {
                knobs.area_rays = n;
                eprintln!(
                    "{n}x{n} rays a training pixel, the loss on their mean: its pixels span \
                     {footprint:.2} node spacings at the field's centre (--area-rays 1 takes one \
                     through each pixel's centre)"
                );
            }
            (true, Err(e)) => eprintln!(
                "one ray a training pixel, though its pixels span {footprint:.2} node spacings at \
                 the field's centre: {n}x{n} would not fit the device ({e:#})"
            ),
            (false, _) => {}
        }
    }
    if args.refine_density_exponent.is_auto() {
        knobs.refine_density_exponent = knobs.auto_refine_exponent();
        if knobs.refine_density_exponent > 0.0 && knobs.stages > 1 {
            eprintln!(
                "each density × 2^{} as the grid doubles, behind the random background \
                 (--refine-density-exponent 0 carries it unchanged)",
                knobs.refine_density_exponent
            );
        }
    }
    if args.sparsity.is_auto() {
        knobs.sparsity = knobs.auto_sparsity();
        if knobs.sparsity != TrainKnobs::default().sparsity {
            eprintln!(
                "sparsity prior {:e} behind the random background (--sparsity {:e} is the fixed \
                 background's)",
                knobs.sparsity,
                TrainKnobs::default().sparsity
            );
        }
    }
    if args.sparsity_edge.is_auto() {
        knobs.sparsity_edge = knobs.auto_sparsity_edge();
        if knobs.sparsity_edge != TrainKnobs::default().sparsity_edge {
            eprintln!(
                "sparsity prior's edge {} behind the random background (--sparsity-edge {} is \
                 the fixed background's)",
                knobs.sparsity_edge,
                TrainKnobs::default().sparsity_edge
            );
        }
    }
    if args.sky.is_auto() {
        knobs.sky = match &resume_sky {
            Some(sky) => sky.height,
            None => past.auto_sky(knobs.random_background),
        };
        if knobs.sky > 0 {
            eprintln!(
                "learning a sky of {}x{} texels behind the field: {}",
                2 * knobs.sky,
                knobs.sky,
                match &resume_sky {
                    Some(_) => "the --resume field's".to_string(),
                    None => format!(
                        "{:.1} % of the views' light lies past the bounds (--sky 0 leaves it out)",
                        100.0 * past.share
                    ),
                }
            );
        }
    }
    let sky_out = sky_path(&args.out);
    if knobs.sky > 0 {
        check_image_output("--out's sky", &sky_out)?;
    }
    if let Some((sky, file)) = resume_sky
        .as_ref()
        .zip(args.resume.as_deref().map(sky_path))
    {
        if knobs.sky > 0 && sky.height != knobs.sky {
            eprintln!(
                "{}: a sky of {}x{} texels, not --sky {}'s: a new sky starts",
                file.display(),
                sky.width,
                sky.height,
                knobs.sky
            );
        }
    }
    if knobs.sparsity_at(nodes) != knobs.sparsity {
        eprintln!(
            "sparsity prior {:.3e} at {nodes} nodes (--sparsity {:e} is stated for 128 nodes)",
            knobs.sparsity_at(nodes),
            knobs.sparsity
        );
    }
    if let Some(end) = knobs.view_dependent_end(knobs.stages_run(resume.is_some())) {
        eprintln!(
            "the first {end} steps at degree 1, then degree {} (--view-dependent-start 0 trains \
             at {0} throughout)",
            knobs.sh_degree
        );
    }
    let poses = inlay_passes::train::pixels::poses(&dataset).len() as u32;
    let held_poses = inlay_passes::train::held_out_frames(poses, args.hold_out).len() as u32;
    if held_poses < args.hold_out {
        eprintln!(
            "--hold-out {}: the dataset has {poses} poses and one must train, so {held_poses} are held out",
            args.hold_out
        );
    }
    let started = Instant::now();
    let background = DVec3::from_array(args.background.map(|v| v as f64));
    // Ctrl-C ends the run with the field so far (a second one kills it).
    inlay_engine::interrupt::catch_interrupts()?;
    let control = TrainControl {
        resume: resume.as_ref(),
        resume_sky: resume_sky.as_ref(),
        budget,
        stop: &inlay_engine::interrupt::interrupted,
        seen_lights: &seen_lights,
        ..TrainControl::default()
    };
    if runs == 2 {
        eprintln!(
            "two runs{}: the first on the photographs alone; then the planes through the \
             surfaces it places give the pixels whose depth it leaves open a depth, which the \
             second holds as a depth map (--planes off trains once)",
            if args.iterations.is_none() {
                format!(" of {} steps", knobs.iterations)
            } else {
                String::new()
            }
        );
    }
    let bar = progress_bar("training", (runs * knobs.iterations) as u64);
    let CompletedTraining {
        trained, single, ..
    } = train_completing(
        ctx,
        &inlay_passes::shaders::library()?,
        &dataset,
        &knobs,
        args.hold_out,
        background,
        &control,
        &|r| {
            let p = &r.progress;
            bar.set_position((r.run * knobs.iterations + p.step) as u64);
            bar.set_message(format!(
                "{}loss {:.3e}, PSNR {:.1} dB, {:.0} rays/s, {}x{}x{}",
                if r.runs > 1 {
                    format!("run {} of {}: ", r.run + 1, r.runs)
                } else {
                    String::new()
                },
                p.loss,
                p.psnr,
                p.rays_per_second,
                p.resolution.x,
                p.resolution.y,
                p.resolution.z
            ));
        },
        &|c| bar.suspend(|| print_completion(c)),
    )?;
    bar.finish_and_clear();
    if let (2, Some(why)) = (runs, single) {
        eprintln!("one run, not two: {why}");
    }
    let f = &trained.field;
    if trained.steps < knobs.iterations {
        eprintln!(
            "stopped at step {} ({}): the field so far is written",
            trained.steps,
            if inlay_engine::interrupt::interrupted() {
                "Ctrl-C"
            } else {
                "time budget"
            }
        );
    }
    eprintln!(
        "trained {} of {} steps in {:.1} s: a {}x{}x{} field; last loss {:.4e}",
        trained.steps,
        knobs.iterations,
        started.elapsed().as_secs_f64(),
        f.resolution.x,
        f.resolution.y,
        f.resolution.z,
        trained.history.last().map_or(f64::NAN, |h| h.1)
    );
    eprintln!(
        "knobs' scale: radiance {:.4} ({})",
        trained.scale,
        if args.scale.is_some() {
            "--scale".to_string()
        } else {
            format!(
                "the photographs' mean luminance, pixels past the bounds black and photographs \
                 over {} times the median one's left out; --scale sets it",
                inlay_passes::train::trainer::SCALE_OUTLIER
            )
        }
    );
    print_step_times(&trained.step_times);
    if knobs.learn_exposure {
        let (low, high) = luminance_range(&trained.gains);
        eprintln!("learnt exposure gains (luminance, frame 0 = 1): {low:.3} to {high:.3}");
    }
    if let Some((emptied, again)) = trained.emptied {
        eprintln!(
            "the first stage's field held no density after step {emptied} (Adam's first steps took \
             every density below zero): its densities below zero took the gradient that asks for \
             more {}",
            match again {
                Some(step) => format!("until step {step}, when it held some again"),
                None => "to the stage's end, and it held none again".into(),
            }
        );
    }
    if let Some((kept, all)) = trained.bricks {
        eprintln!("the last stage trained {kept} of {all} bricks of 8³ nodes (sparse)");
    }
    if knobs.prune > 0.0 {
        eprintln!(
            "pruned the density of {} of {} nodes (largest weight in any training ray below {})",
            trained.pruned,
            f.nodes.len(),
            knobs.prune
        );
    }
    for v in &trained.held_out {
        let inside = v.in_bounds.map_or(String::new(), |(psnr, share)| {
            format!(
                " ({psnr:.2} dB over the {:.0} % of its pixels that look into the bounds)",
                100.0 * share
            )
        });
        let merged = match v.brackets {
            1 => String::new(),
            n => format!(" (its pose's {n} brackets merged: linear radiance)"),
        };
        println!(
            "held-out frame {}{merged}: PSNR {:.2} dB{inside}, relative error {:.3}, brightness field / photograph {:.3}",
            v.frame, v.psnr, v.relative_error, v.brightness
        );
    }
    print_spread(&trained.held_out, trained.field.spacing().min_element());
    let depths = match &scene {
        Some(scene) => print_geometry(scene, &dataset, &trained, &knobs),
        None => Vec::new(),
    };
    let mut outputs = Outputs::new();
    outputs.bytes(&args.out, &checked_field_bytes(&args.out, f)?)?;
    if let Some(sky) = &trained.sky {
        let (low, high) = luminance_range(&sky.texels);
        eprintln!(
            "learnt a sky of {}x{} texels ({} seen past the field, the others filled from \
             the nearest of those), luminance {low:.3e} to {high:.3e}: {}",
            sky.width,
            sky.height,
            trained.sky_seen,
            sky_out.display()
        );
        outputs.image(&sky_out, &sky.to_image(), 1.0)?;
    }
    // A field's lights file is its own: one beside an earlier field at
    // `--out` would be drawn with this one, so it is emptied.
    let lights_out = seen_lights_path(&args.out);
    if !seen_lights.is_empty() || lights_out.exists() {
        eprintln!(
            "{} seen past the bounds, drawn wherever the field is: {}",
            match seen_lights.len() {
                0 => "no light".to_string(),
                1 => "1 light".to_string(),
                n => format!("{n} lights"),
            },
            lights_out.display()
        );
        outputs.bytes(&lights_out, seen_lights_text(&seen_lights).as_bytes())?;
    }
    if let (Some(path), false) = (&args.picture, trained.held_out.is_empty()) {
        outputs.image(path, &held_out_picture(&trained.held_out), 1.0)?;
    }
    if let (Some(path), false) = (&args.depth_picture, depths.is_empty()) {
        outputs.image(path, &depth_picture(&depths), 1.0)?;
    }
    if let (Some(path), false) = (&args.spread_picture, trained.held_out.is_empty()) {
        outputs.image(path, &spread_picture(&trained.held_out), 1.0)?;
    }
    outputs.commit(Some(ctx))?;
    Ok(())
}

/// Prints how far each held-out view's surfaces spread along its rays
/// ([`inlay_passes::train::spread`]), and warns where the share spread
/// wide says the photographs left the depth open.
fn print_spread(views: &[inlay_passes::train::HeldOutView], spacing: f64) {
    use inlay_passes::train::spread::{WIDE_SHARE_WARNING, WIDE_SPREAD};
    for v in views {
        let s = &v.spread;
        let read = match s.stride {
            1 => String::new(),
            n => format!(" (one pixel of each {n} × {n} block read)"),
        };
        println!(
            "held-out frame {}: the field's surfaces spread over {WIDE_SPREAD} node spacings ({:.3} units) or more \
             along the ray at {} of its {} surface pixels{read}",
            v.frame,
            WIDE_SPREAD * spacing,
            percent_of(s.wide_share()),
            s.surfaces()
        );
    }
    let wide: Vec<String> = views
        .iter()
        .filter(|v| v.spread.wide_share() >= WIDE_SHARE_WARNING)
        .map(|v| format!("frame {}: {}", v.frame, percent_of(v.spread.wide_share())))
        .collect();
    if !wide.is_empty() {
        eprintln!(
            "warning: the field's depth is uncertain where a surface's weight spreads along the ray \
             (held-out {}): photographs cannot place a plain, untextured surface, whose colour a \
             translucent sheet in front of it renders from every side. Occlusion, probes and shadows \
             read that depth; photographs with alpha, or depth maps (`depth_file_path`), place it, \
             and `--planes` (on by default) only where the surface lies on a plane through surfaces \
             the photographs place. A medium such as foliage spreads by nature",
            wide.join(", ")
        );
    }
}

/// The smallest and largest luminance of `colours`.
fn luminance_range(colours: &[DVec3]) -> (f64, f64) {
    colours
        .iter()
        .map(|c| inlay_passes::sgfit::model::luminance(*c))
        .fold((f64::INFINITY, 0.0), |(lo, hi), l| (lo.min(l), hi.max(l)))
}

/// One held-out view's pixels' geometry: its size and each pixel's
/// ([`inlay_passes::train::depth_pixels`]).
type ViewDepths = ((u32, u32), Vec<Option<PixelDepth>>);

/// Prints each held-out view's geometry against `scene`'s recipe, its
/// media included ([`inlay_passes::train::geometry_score`]), and returns
/// each view's pixels.
fn print_geometry(
    scene: &inlay_passes::scene::Scene,
    dataset: &inlay_passes::dataset::Dataset,
    trained: &inlay_passes::train::Trained,
    knobs: &TrainKnobs,
) -> Vec<ViewDepths> {
    let Some(recipe) = scene.recipe() else {
        return Vec::new();
    };
    let mut views = Vec::new();
    // Its nearest_surface alone is used: no bounces.
    let tracer = inlay_passes::bake::PathTracer::new(recipe, &scene.environment, 0);
    let content = |ray: &inlay_passes::geometry::Ray, t0: f64, t1: f64| {
        inlay_passes::train::recipe_along(recipe, &tracer, ray, t0, t1)
    };
    let march = inlay_passes::train::view_march(knobs);
    for v in &trained.held_out {
        let frame = &dataset.frames[v.frame as usize];
        let pixels = inlay_passes::train::depth_pixels(frame, &trained.field, &march, &content);
        let g = inlay_passes::train::score_pixels(&pixels);
        views.push((v.size, pixels));
        let depth = if g.compared == 0 {
            "no pixel's depth compared (none both on a surface and opaque)".to_string()
        } else {
            format!(
                "median |depth error| {:.2} node spacings over {} pixels (signed {:+.2}: in front when negative; \
                 {:.2} along the surfaces' normals)",
                g.median_error, g.compared, g.median_signed_error, g.median_normal_offset
            )
        };
        println!(
            "held-out frame {}: geometry against {}: {depth}; seen through at {} of the surfaces' pixels, \
             floating at {} of the others; haze hides {} of the surfaces' light (the field's mean opacity \
             up to {} node spacings in front of them)",
            v.frame,
            scene.path.display(),
            percent_of(g.see_through),
            percent_of(g.floating),
            percent_of(g.haze),
            inlay_passes::train::HAZE_MARGIN
        );
    }
    views
}

/// The held-out views' depth errors ([`depth_error_colour`]), one view a
/// row.
fn depth_picture(views: &[ViewDepths]) -> HdrImage {
    let sizes: Vec<(u32, u32)> = views.iter().map(|v| v.0).collect();
    stacked_views(&sizes, 1, |v, i, _| {
        depth_error_colour(views[v].1[i].as_ref())
    })
}

/// The held-out views' surfaces' spread ([`inlay_passes::train::spread::spread_colour`]),
/// one view a row.
fn spread_picture(views: &[inlay_passes::train::HeldOutView]) -> HdrImage {
    let sizes: Vec<(u32, u32)> = views.iter().map(|v| v.spread.size).collect();
    stacked_views(&sizes, 1, |v, i, _| {
        inlay_passes::train::spread::spread_colour(views[v].spread.spreads[i])
    })
}

/// A share as a percentage, or "— (no such pixel)" where there was nothing
/// to share among (the score's NaN: no pixel of that kind in the view).
fn percent_of(share: f64) -> String {
    if share.is_nan() {
        "— (no such pixel)".to_string()
    } else {
        format!("{:.1} %", 100.0 * share)
    }
}

/// What the planes made of the first run's field: the planes, and the
/// open pixels they completed.
fn print_completion(c: &Completion) {
    eprintln!(
        "the first run's field places {} training pixels' surfaces (their weight within {} node \
         spacings); {} plane(s) hold {} % of them",
        c.placed,
        inlay_passes::train::planes::PLACED_SPREAD,
        c.planes.len(),
        if c.placed == 0 {
            0.0
        } else {
            (100.0 * c.planes.iter().map(|(_, n)| *n).sum::<usize>() as f64 / c.placed as f64)
                .round()
        }
    );
    for (p, n) in &c.planes {
        eprintln!(
            "  plane n = ({:.3}, {:.3}, {:.3}), n·x = {:.4}: {n} points",
            p.normal.x, p.normal.y, p.normal.z, -p.offset
        );
    }
    eprintln!(
        "of {} training pixels{} whose weight spreads over {} spacings or more, {} were given the \
         depth of a plane within their spread{}{} ({:.1} s)",
        c.open,
        match c.stride {
            1 => String::new(),
            s => format!(" read (one pixel of each {s} × {s} block)"),
        },
        inlay_passes::train::planes::OPEN_SPREAD,
        c.completed,
        match c.media {
            0 => String::new(),
            n => format!(
                " and {n} left alone: the weight in front of the plane is not of its colour (a \
                 medium)"
            ),
        },
        match c.stride {
            1 => String::new(),
            _ => format!(
                "; {} pixels in all hold a plane's depth, those between taking the plane the \
                 pixels read around them agree on",
                c.depths
            ),
        },
        c.elapsed.as_secs_f64()
    );
}

/// Where a step's time went: its wall-clock mean and each pass's GPU
/// mean, largest first.
fn print_step_times(times: &inlay_passes::train::StepTimes) {
    if times.steps == 0 {
        return;
    }
    let passes: Vec<String> = times
        .per_step()
        .iter()
        .map(|(p, ms)| format!("{p} {ms:.1}"))
        .collect();
    eprintln!(
        "a step took {:.1} ms; GPU ms per step: {}",
        times.wall_ms_per_step(),
        passes.join(", ")
    );
}

/// The held-out views one under another: photograph | field | |difference|.
fn held_out_picture(views: &[inlay_passes::train::HeldOutView]) -> HdrImage {
    let sizes: Vec<(u32, u32)> = views.iter().map(|v| v.size).collect();
    stacked_views(&sizes, 3, |v, i, panel| {
        let (a, b) = (views[v].truth[i], views[v].rendered[i]);
        match panel {
            0 => a,
            1 => b,
            _ => [0, 1, 2].map(|k| (a[k] - b[k]).abs()),
        }
    })
}

/// Views of `sizes` one under another, each row `panels` panels across
/// as wide as the widest view: `colour(view, pixel, panel)` colours each
/// pixel (row by row within its view); black where a view is narrower.
fn stacked_views(
    sizes: &[(u32, u32)],
    panels: u32,
    colour: impl Fn(usize, usize, u32) -> [f32; 3],
) -> HdrImage {
    let w = sizes.iter().map(|s| s.0).max().unwrap_or(1);
    let h: u32 = sizes.iter().map(|s| s.1).sum();
    let mut pixels = vec![[0.0f32, 0.0, 0.0, 1.0]; (panels * w * h) as usize];
    let mut y0 = 0;
    for (v, &(vw, vh)) in sizes.iter().enumerate() {
        for i in 0..(vw * vh) as usize {
            let (x, y) = (i as u32 % vw, i as u32 / vw);
            for panel in 0..panels {
                let c = colour(v, i, panel);
                let o = ((y0 + y) * panels * w + panel * w + x) as usize;
                pixels[o] = [c[0], c[1], c[2], 1.0];
            }
        }
        y0 += vh;
    }
    HdrImage {
        width: panels * w,
        height: h,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::percent_of;

    /// A view whose every pixel holds a surface has no "others" to float
    /// among: that is said, not printed as NaN.
    #[test]
    fn a_share_of_nothing_is_said_not_printed_as_nan() {
        assert_eq!(percent_of(0.0123), "1.2 %");
        assert_eq!(percent_of(f64::NAN), "— (no such pixel)");
    }
}
