//! The training loop: a grid trained coarse to fine on the GPU
//! (`train-rays`, `train-adam`; a stage too large for one binding only in
//! the bricks around what the stage before made visible,
//! [`super::sparse_stage`]), step sizes decaying exponentially, then the
//! held-out views rendered with the march and scored.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec3, UVec3};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{Context, Renderer};
use rayon::prelude::*;

use super::adam::AdamKnobs;
use super::behind::Behind;
use super::gpu::{GpuTrainer, TrainRay};
use super::knobs::TrainKnobs;
use super::past_bounds::{frame_sees_bounds, pose_light};
use super::pixels::{bracket_sets, is_bracket, merged_brackets, training_frames, PixelPool};
use super::seen_lights::SeenLight;
use super::spread::{surface_spread, SurfaceSpread};
use super::view_pixel::{view_pixel, PixelSplit};
use super::visibility::pool_visibility_gpu;
use crate::dataset::pixels::srgb_encode as encoded;
use crate::dataset::{Dataset, Frame, PixelState};
use crate::field::FieldLayout::Auto;
use crate::field::Sky;
use crate::field::{GridField, DEFAULT_OCCUPANCY_BLOCK};
use crate::geometry::Aabb;
use crate::march::MarchKnobs;
use crate::rng::Pcg32;
use crate::sgfit::model::luminance;

/// Where a run is, for progress reports.
#[derive(Debug, Clone, Copy)]
pub struct TrainProgress {
    /// Steps done.
    pub step: u32,
    /// Steps in the run.
    pub steps: u32,
    /// The last batch's mean loss.
    pub loss: f64,
    /// The last batch's PSNR in dB, as the held-out views are scored
    /// ([`batch_psnr`]).
    pub psnr: f64,
    /// Rays per second so far.
    pub rays_per_second: f64,
    /// The grid's nodes per axis now.
    pub resolution: UVec3,
}

/// A held-out view rendered from the trained field and scored.
#[derive(Debug, Clone)]
pub struct HeldOutView {
    /// Its index in the dataset's frames (a bracketed pose's longest
    /// exposure).
    pub frame: u32,
    /// The frames it stands for: a bracketed pose's brackets, merged into
    /// one view of radiance and scored as one ([`merged_brackets`]); 1
    /// for any other frame.
    pub brackets: usize,
    /// PSNR in dB of the rendered view against the photograph, on
    /// sRGB-encoded values clipped at 1 (brackets at their exposure).
    pub psnr: f64,
    /// Σ|L_field − L_photo| / Σ L_photo in luminance over the usable
    /// pixels (linear radiance; brackets at their exposure, clipped).
    pub relative_error: f64,
    /// Σ L_field / Σ L_photo over the same pixels: whether the field is
    /// brighter or darker than its photographs as a whole, which the
    /// relative error cannot tell.
    pub brightness: f64,
    /// Where some of the view's pixels look past the field's bounds (a
    /// sky, a far wall) and some into them: the PSNR over those that look
    /// into the bounds alone, and their share of the usable pixels. The
    /// field is judged by these; the rest show only what lies behind it.
    pub in_bounds: Option<(f64, f64)>,
    /// The photograph (linear, brackets at their exposure and clipped).
    pub truth: Vec<[f32; 3]>,
    /// The field's rendering of it, the same way.
    pub rendered: Vec<[f32; 3]>,
    /// Width and height.
    pub size: (u32, u32),
    /// How far the field's surfaces spread along the rays through the
    /// view's pixels: where wide, the photographs left their depth open.
    pub spread: SurfaceSpread,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct Trained {
    /// The trained field.
    pub field: GridField,
    /// (step, mean batch loss) every few steps.
    pub history: Vec<(u32, f64)>,
    /// The held-out views.
    pub held_out: Vec<HeldOutView>,
    /// Steps taken (fewer than asked when the time budget ran out).
    pub steps: u32,
    /// The radiance the knobs' rates, the loss's floor and the starting
    /// grey were fractions of ([`TrainKnobs::scale`], else [`radiance_scale`]).
    pub scale: f64,
    /// Nodes whose density pruning took ([`TrainKnobs::prune`]).
    pub pruned: usize,
    /// Each frame's exposure gain (all 1 unless
    /// [`TrainKnobs::learn_exposure`]; held-out frames' stay 1).
    pub gains: Vec<DVec3>,
    /// Bricks trained and bricks in the grid, where the last stage was
    /// trained sparsely ([`TrainKnobs::sparse`]).
    pub bricks: Option<(u32, u32)>,
    /// The sky learnt behind the field ([`TrainKnobs::sky`]; None behind
    /// the fixed background).
    pub sky: Option<Sky>,
    /// The sky's texels the last stage's rays reached (the others, where
    /// no photograph looks past the field, are filled from the nearest
    /// of these: [`Sky::fill_unseen`]).
    pub sky_seen: usize,
    /// Where the steps' time went, pass by pass.
    pub step_times: super::StepTimes,
    /// The steps of the first stage after which its field first held no
    /// density (every node below zero) and after which it held some again:
    /// in between its densities below zero took the gradient that asks for
    /// more ([`super::DensityGate::Revive`]; the second None where it
    /// never did). None where it never emptied.
    pub emptied: Option<(u32, Option<u32>)>,
}

/// The first stage's steps after each of which the trainer asks whether
/// its field still holds any density ([`Trained::emptied`]). Adam's
/// first steps are about the full step size whatever the gradient, five
/// times the grey start's density: on a coarse first stage behind a random
/// background (8 or 16 nodes across) every node's first gradient asked for
/// less, and one step took every density below zero (DOG, CUPS and BOOKS
/// of 8 views at `--resolution 32`, CUPS of 24 at 64).
/// Revived until the field held density again (one to three steps), the
/// 14 held-out views of those runs and others like them read 0.6–7.6 dB
/// higher than revived to the stage's end, which lets haze grow where a
/// surface's neighbours would have brought it back.
pub const EMPTIED_CHECK_STEPS: u32 = 10;

/// Nodes per axis for `nodes` along the bounds' longest axis.
pub fn grid_size(size: DVec3, nodes: u32) -> UVec3 {
    let m = size.max_element();
    UVec3::new(
        ((nodes as f64 * size.x / m).round() as u32).max(2),
        ((nodes as f64 * size.y / m).round() as u32).max(2),
        ((nodes as f64 * size.z / m).round() as u32).max(2),
    )
}

/// `field` at the nodes of a `resolution` grid over the same bounds, its
/// view-dependent colour included (trilinear: a finer grid holds the same
/// field).
pub fn resample(field: &GridField, resolution: UVec3) -> GridField {
    let b = field.bounds;
    let cells = (resolution - UVec3::ONE).as_dvec3();
    let count = (resolution.x * resolution.y * resolution.z) as usize;
    let mut nodes = Vec::with_capacity(count);
    let mut sh = Vec::with_capacity(count * field.sh_count());
    for k in 0..resolution.z {
        for j in 0..resolution.y {
            for i in 0..resolution.x {
                let f = DVec3::new(i as f64, j as f64, k as f64) / cells;
                let x = (b.min + f * b.size()).clamp(b.min, b.max);
                nodes.push(field.interpolate(x).map(|v| v as f32));
                sh.extend(
                    field
                        .interpolate_sh(x)
                        .iter()
                        .map(|c| c.as_vec3().to_array()),
                );
            }
        }
    }
    GridField::new(resolution, b, nodes, DEFAULT_OCCUPANCY_BLOCK).with_sh(field.sh_degree, sh)
}

/// `field` on the finer `resolution` grid of the next stage ([`resample`]),
/// each node's density multiplied by r^`exponent`, r the node spacing
/// before over after: 0 keeps the field as it was; 1 keeps each node's
/// optical depth per spacing, so a surface rises as steeply per node as
/// it did on the coarser grid ([`TrainKnobs::refine_density_exponent`]).
/// A density's sign is kept, so the surfaces, where the interpolated
/// density crosses zero, stay where they were.
pub fn refine(field: &GridField, resolution: UVec3, exponent: f64) -> GridField {
    let before = field.spacing().min_element();
    let mut fine = resample(field, resolution);
    let gain = (before / fine.spacing().min_element()).powf(exponent) as f32;
    if gain != 1.0 {
        // A positive factor keeps which nodes are above zero, so the
        // occupancy built from them stays as it is.
        for n in &mut fine.nodes {
            n[3] *= gain;
        }
    }
    fine
}

/// `field` with view-dependent colour of `degree`: the coefficients it has
/// up to that degree (the bands are nested), zeros beyond.
pub fn with_sh_degree(field: GridField, degree: u32) -> GridField {
    let (from, to) = (
        field.sh_count(),
        crate::field::sh_extra_coefficients(degree),
    );
    if from == to {
        return field;
    }
    let sh = (0..field.nodes.len())
        .flat_map(|n| (0..to).map(move |k| (n, k)))
        .map(|(n, k)| {
            if k < from {
                field.sh[n * from + k]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    field.with_sh(degree, sh)
}

/// How many times the median training pose's mean luminance a pose's
/// may be and still count in [`radiance_scale`]. On the bundled sets the
/// brightest pose's mean is 1.1–1.5 times the median's; on ROOM's Cycles
/// set, whose highest views see the bulb in front of the box, 18.7.
pub const SCALE_OUTLIER: f64 = 4.0;

/// The loss's and the colours' scale: the mean, over the training poses,
/// of each pose's mean luminance (a median over pixels would be zero
/// where most pixels see empty space), in the scene's radiance: the
/// brackets of a pose are merged at each pixel ([`super::pixels::merged_luminance`]),
/// so that bracketed photographs give the scale their linear
/// counterparts would. Read as recorded, PLANTS' brackets at 1/64, 1/8
/// and 1 gave a fraction of it, and the field they trained had its
/// surfaces 10–13 node spacings in front of the recipe's
/// (`docs/benchmarks.md`, issue 25's fifteenth pass). A pixel whose ray
/// misses `bounds` counts as black: its light is not the field's to hold
/// ([`super::past_bounds`]), and a `render-views` set, black past the
/// bounds, reads the same scale either way. A pose whose mean is more
/// than [`SCALE_OUTLIER`] times the median pose's is left out: a light
/// that a few views see and the field does not hold sets no scale
/// (ROOM's Cycles set sees its bulb, in front of the box, from its
/// highest views, and the mean over every pose was 3 times the room's:
/// `docs/benchmarks.md`, issue 25's twenty-second pass). A light inside
/// the field, which most views see (PLANTS' lamp), stays in it.
pub fn radiance_scale(dataset: &Dataset, training: &[u32], bounds: &Aabb) -> f64 {
    let sets = bracket_sets(dataset, training);
    // Each pose once, at its longest exposure's frame.
    let mut means: Vec<f64> = training
        .par_iter()
        .filter(|&&f| sets[f as usize][0] == f)
        .map(|&f| pose_light(dataset, &sets[f as usize], bounds))
        .filter(|pose| pose.pixels > 0)
        .map(|pose| pose.inside / pose.pixels as f64)
        .collect();
    if means.is_empty() {
        return 1e-6;
    }
    means.sort_by(f64::total_cmp);
    let k = means.len();
    let median = if k % 2 == 1 {
        means[k / 2]
    } else {
        0.5 * (means[k / 2 - 1] + means[k / 2])
    };
    let kept: Vec<f64> = means
        .into_iter()
        .filter(|m| *m <= SCALE_OUTLIER * median)
        .collect();
    (kept.iter().sum::<f64>() / kept.len().max(1) as f64).max(1e-6)
}

/// The radiance behind the field for step `step`'s rays: `background`, or
/// under [`TrainKnobs::random_background`] a colour drawn for the step,
/// each channel uniform over [0, 2·`scale`) (`scale` the photographs' mean
/// radiance).
pub fn step_background(knobs: &TrainKnobs, background: DVec3, scale: f64, step: u32) -> DVec3 {
    if !knobs.random_background {
        return background;
    }
    let mut rng = Pcg32::new(knobs.seed, RANDOM_BACKGROUND_STREAM ^ step as u64);
    DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * (2.0 * scale)
}

/// The random stream [`step_background`] draws from (apart from the
/// batches' pixels').
const RANDOM_BACKGROUND_STREAM: u64 = 0xB6_0000_0000;

/// The photographs' pixels whose alpha is below 1.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TransparentPixels {
    /// In frames of linear radiance (EXR, or PNG/JPEG without an exposure
    /// time): a random background goes behind them.
    pub linear: usize,
    /// In exposure brackets, whose recorded codes take no other background.
    pub brackets: usize,
}

impl TransparentPixels {
    /// Whether a random background suits the photographs by default: they
    /// say where nothing is (some pixel's alpha below 1) and every such
    /// pixel can take it.
    pub fn takes_random_background(&self) -> bool {
        self.linear > 0 && self.brackets == 0
    }
}

/// Counts the transparent pixels of `dataset`'s frames `frames` (`inlay
/// train` chooses the random background from its training frames', and
/// refuses one behind any bracket's).
pub fn transparent_pixels(dataset: &Dataset, frames: &[u32]) -> TransparentPixels {
    let mut out = TransparentPixels::default();
    for f in frames.iter().map(|&f| &dataset.frames[f as usize]) {
        let n = f.image.alpha.iter().filter(|a| **a < 1.0).count();
        if super::pixels::is_bracket(f) {
            out.brackets += n;
        } else {
            out.linear += n;
        }
    }
    out
}

/// Why `dataset` cannot be trained with `knobs`, before any work: every
/// usable pixel black, or a random background behind exposure brackets
/// with transparent pixels (a
/// bracket's code was recorded over the fixed background, and another
/// cannot be put behind it). Transparent linear frames take it: their
/// alpha composites each step's background.
pub fn check_dataset(knobs: &TrainKnobs, dataset: &Dataset) -> anyhow::Result<()> {
    // Photographs that record no light teach an empty field, which the
    // run would refuse only at its end.
    anyhow::ensure!(
        dataset.frames.is_empty() || dataset.records_light(),
        "{}: every usable pixel of its {} frames is black (radiance 0): there is nothing to \
         train on (images written in other units, or an exposure_time that reads them as none?)",
        dataset.file.display(),
        dataset.frames.len()
    );
    let every: Vec<u32> = (0..dataset.frames.len() as u32).collect();
    let transparent = transparent_pixels(dataset, &every).brackets;
    anyhow::ensure!(
        !knobs.random_background || transparent == 0,
        "random background: {} has {transparent} pixels with alpha below 1 in its exposure \
         brackets, whose codes were recorded over the fixed background; train them over it (no \
         random background)",
        dataset.file.display()
    );
    Ok(())
}

/// How a run begins and when it stops early.
pub struct TrainControl<'a> {
    /// A field to continue from (its nodes, resolution and bounds; one
    /// stage at its resolution; its view-dependent colour brought to the
    /// knobs' degree) instead of a grey grid.
    pub resume: Option<&'a GridField>,
    /// A learnt sky to continue from ([`TrainKnobs::sky`]; one of another
    /// size starts afresh).
    pub resume_sky: Option<&'a Sky>,
    /// Stop once this much time has passed.
    pub budget: Option<Duration>,
    /// Stop when this says so (Ctrl-C).
    pub stop: &'a dyn Fn() -> bool,
    /// Lights the photographs show past the bounds
    /// ([`super::seen_lights`]), drawn in the held-out views. Their
    /// training pixels are the caller's to leave out
    /// ([`super::seen_lights::mask_seen_lights`]).
    pub seen_lights: &'a [SeenLight],
    /// Depth maps that stand in for the frames' own, frame by frame (each
    /// pixel's z-depth, 0 where none; an empty map leaves the frame's
    /// own): the planes' completion of the open surfaces
    /// ([`super::planes`]).
    pub depth: Option<&'a [Vec<f32>]>,
    /// Whether the held-out views are rendered and scored at the end
    /// ([`Trained::held_out`] empty where not: a first run whose field
    /// only leads to the next).
    pub score_held_out: bool,
}

impl Default for TrainControl<'_> {
    fn default() -> Self {
        Self {
            resume: None,
            resume_sky: None,
            budget: None,
            stop: &|| false,
            seen_lights: &[],
            depth: None,
            score_held_out: true,
        }
    }
}

/// Trains a grid on `dataset` (holding out `hold_out` frames), over
/// `background`; `control` says where to start and when to stop early (the
/// field so far is the result then).
#[allow(clippy::too_many_arguments)]
pub fn train(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    dataset: &Dataset,
    knobs: &TrainKnobs,
    hold_out: u32,
    background: DVec3,
    control: &TrainControl,
    progress: &dyn Fn(&TrainProgress),
) -> anyhow::Result<Trained> {
    if let Err((k, m)) = knobs.check() {
        anyhow::bail!("train knob {k}: {m}");
    }
    check_dataset(knobs, dataset)?;
    let started = Instant::now();
    let pool = PixelPool::new(dataset, hold_out);
    anyhow::ensure!(!pool.pixels.is_empty(), "no usable pixel to train on");
    let bounds = control.resume.map_or(dataset.bounds, |f| f.bounds);
    let scale = knobs
        .scale
        .unwrap_or_else(|| radiance_scale(dataset, &training_frames(dataset, hold_out), &bounds));
    let diag = bounds.diagonal();
    let march = MarchKnobs {
        skip_empty: false,
        ..view_march(knobs)
    };
    let final_res = control
        .resume
        .map_or(grid_size(bounds.size(), knobs.resolution), |f| f.resolution);
    let stages = knobs.stages_run(control.resume.is_some());
    let stage_res = |s: u32| {
        let shift = stages - 1 - s;
        (final_res.as_dvec3() / (1u32 << shift) as f64)
            .ceil()
            .as_uvec3()
            .max(UVec3::splat(2))
    };
    // The final grid at the knobs' degree, the first at the start's.
    for (res, degree) in [
        (final_res, knobs.sh_degree),
        (stage_res(0), knobs.highest_sh_degree(stages)),
    ] {
        crate::field::check_field_may_fit(
            ctx.info(),
            res,
            degree,
            crate::field::NodeStorage::Training,
        )?;
    }
    // Start grey at the mean radiance, half transparent across the box.
    let first = stage_res(0);
    let grey = scale as f32;
    let start = match control.resume {
        Some(f) => f.clone(),
        None => GridField::new(
            first,
            bounds,
            vec![[grey, grey, grey, (1.0 / diag) as f32]; (first.x * first.y * first.z) as usize],
            DEFAULT_OCCUPANCY_BLOCK,
        ),
    };
    // The first stage's view-dependent start, where there is one, trains
    // at degree 1 until its end step, then the stage goes on at the
    // knobs' degree: each is a phase, as is every later stage.
    let dependent_end = knobs.view_dependent_end(stages);
    let mut field = with_sh_degree(start, knobs.highest_sh_degree(stages));
    let phases: Vec<(u32, u32)> = dependent_end
        .map(|end| (0, end))
        .into_iter()
        .chain((0..stages).map(|s| (s, knobs.stage_end(stages, s))))
        .collect();
    let mut gains = vec![DVec3::ONE; dataset.frames.len().max(1)];
    // A resumed sky of the knobs' size goes on as it was saved: every
    // texel holds what its own run learnt or filled in.
    let resumed_sky = control.resume_sky.filter(|s| s.height == knobs.sky);
    let mut sky = (knobs.sky > 0).then(|| match resumed_sky {
        Some(s) => s.clone(),
        None => Sky::uniform(knobs.sky, background),
    });
    let mut sky_seen = Vec::new();
    let mut renderer = Renderer::new(ctx, 1)?;
    let mut history = Vec::new();
    let mut rays_done = 0u64;
    let mut step = 0u32;
    let mut bricks = None;
    let mut step_times = super::StepTimes::default();
    let mut emptied: Option<(u32, Option<u32>)> = None;
    let mut gate = super::DensityGate::Clamp;
    let view_march = view_march(knobs);
    // The largest weight each node takes in any training ray (sparse
    // stages, pruning).
    let visibility_of = |renderer: &mut Renderer, field: &GridField| {
        pool_visibility_gpu(renderer, lib, field, dataset, &pool, &view_march, Auto)
    };
    'stages: for (phase, &(s, end)) in phases.iter().enumerate() {
        // A phase that ends where the one before it did has no step.
        if phase > 0 && end <= phases[phase - 1].1 {
            continue;
        }
        let target = stage_res(s);
        // A resumed field trains sparsely from its first stage where its
        // dense grid would not fit one binding (a 256-node field).
        let sparse = (s > 0 || control.resume.is_some())
            && (knobs.sparse || !GpuTrainer::dense_fits(ctx.info(), target, knobs.sh_degree));
        // The bricks around what the stage before (or the resumed field)
        // made visible, and those a resumed field holds.
        let layout = if sparse {
            let visibility = visibility_of(&mut renderer, &field)?;
            Some(super::sparse_stage::stage_layout(
                &field,
                &visibility,
                knobs.prune,
                target,
            ))
        } else {
            None
        };
        if target != field.resolution {
            field = refine(&field, target, knobs.refine_density_exponent);
        }
        // The view-dependent start's coefficients dropped after it (the
        // moments of Adam start afresh, as at each stage).
        let start_phase = phase == 0 && dependent_end.is_some();
        if !start_phase && field.sh_degree != knobs.sh_degree {
            log::info!(
                "step {step}: the first stage goes on at degree {}",
                knobs.sh_degree
            );
            field = with_sh_degree(field, knobs.sh_degree);
        }
        let res = field.resolution;
        bricks = layout.as_ref().map(|l| (l.slots, l.table.len() as u32));
        if let Some(l) = &layout {
            log::info!(
                "stage {} at {res}: {} of {} bricks of 8³ nodes trained",
                s + 1,
                l.slots,
                l.table.len()
            );
        }
        let stage_march = MarchKnobs {
            samples_per_ray: knobs.stage_samples(res.max_element(), final_res.max_element()),
            ..march
        };
        let mut gpu = GpuTrainer::with_layout(ctx, lib, &field, stage_march, layout)?
            .with_rays_per_pixel(ctx, knobs.rays_per_pixel())?;
        // The sparsity prior's weight follows the grid trained: a resumed
        // field's own nodes, not `knobs.resolution`.
        gpu.tv_weights = knobs.tv_weights(
            field.spacing().min_element(),
            final_res.max_element(),
            scale,
        );
        gpu.distortion = knobs.distortion;
        // The depth maps' loss, its tolerance in the final grid's spacings.
        let final_spacing = (bounds.size() / (final_res - UVec3::ONE).as_dvec3()).min_element();
        gpu.depth = (knobs.depth_weight > 0.0)
            .then_some((knobs.depth_weight, knobs.depth_tolerance * final_spacing));
        gpu.set_gains(ctx, &gains)?;
        gpu.set_sky(ctx, sky.as_ref())?;
        if s == 0 {
            gpu.gate = gate;
        }
        while step < end {
            if control.budget.is_some_and(|b| started.elapsed() >= b) || (control.stop)() {
                field = gpu.field(&mut renderer)?;
                gains = gpu.gains(&mut renderer)?;
                sky = gpu.sky(&mut renderer)?;
                sky_seen = gpu.sky_seen(&mut renderer)?;
                break 'stages;
            }
            let step_started = Instant::now();
            // The photographs' transparent pixels are read over
            // `background`; the step's own goes behind them instead.
            let behind = step_background(knobs, background, scale, step);
            let batch = pool.batch(
                dataset,
                control.depth.unwrap_or(&[]),
                knobs.pixels_per_step() as usize,
                knobs.seed,
                step as u64,
                behind - background,
                knobs.pixel_rays(),
            );
            let records: Vec<TrainRay> = batch
                .iter()
                .flat_map(|(rays, t, f, depths)| {
                    rays.iter().zip(depths).map(|(r, d)| {
                        TrainRay::new(r.origin, r.dir, *t, 1.0)
                            .in_frame(*f)
                            .with_depth(*d)
                    })
                })
                .collect();
            let decay = knobs.rate_decay.powf(step as f64 / knobs.iterations as f64);
            gpu.gain_rate = knobs.learn_exposure.then_some((GAIN_RATE * decay) as f32);
            let adam = AdamKnobs {
                rate: knobs.rate * scale * decay,
                relative_rate: knobs.rate * decay,
                relative_floor: RELATIVE_STEP_FLOOR * knobs.epsilon * scale,
                density_rate: knobs.density_rate / diag * decay,
                beta1: 0.9,
                beta2: 0.99,
            };
            let out = gpu.run_batch(
                &mut renderer,
                &records,
                behind,
                knobs.epsilon * scale,
                Some((&adam, 1.0 / batch.len() as f32)),
            )?;
            step_times.add(
                renderer.latest_timings(),
                step_started.elapsed().as_secs_f64(),
            );
            rays_done += records.len() as u64;
            step += 1;
            // A first stage emptied by its first steps comes back only
            // where densities below zero take some gradient, until it
            // holds density again.
            if s == 0 && (step <= EMPTIED_CHECK_STEPS || gate == super::DensityGate::Revive) {
                let holds = gpu.holds_density(&mut renderer)?;
                if !holds && gate == super::DensityGate::Clamp {
                    log::info!("step {step}: the field holds no density; reviving it");
                    emptied.get_or_insert((step, None));
                    gate = super::DensityGate::Revive;
                } else if holds && gate == super::DensityGate::Revive {
                    log::info!("step {step}: the field holds density again");
                    if let Some((_, again)) = &mut emptied {
                        *again = Some(step);
                    }
                    gate = super::DensityGate::Clamp;
                }
                gpu.gate = gate;
            }
            let loss = out.iter().map(|o| o[3] as f64).sum::<f64>() / out.len() as f64;
            // A loss that is no longer a number trains nothing further:
            // stop before the field is written.
            if !loss.is_finite() {
                anyhow::bail!(
                    "training diverged: the batch's loss is {loss} at step {step} of {}; \
                     the knobs left f32's range (radiance scale {scale:.3e}, step sizes \
                     --rate {} and --density-rate {}, --epsilon {})",
                    knobs.iterations,
                    knobs.rate,
                    knobs.density_rate,
                    knobs.epsilon
                );
            }
            if step % 10 == 0 || step == knobs.iterations {
                history.push((step, loss));
                progress(&TrainProgress {
                    step,
                    steps: knobs.iterations,
                    loss,
                    psnr: batch_psnr(&batch, &out),
                    rays_per_second: rays_done as f64 / started.elapsed().as_secs_f64().max(1e-9),
                    resolution: res,
                });
            }
        }
        field = gpu.field(&mut renderer)?;
        gains = gpu.gains(&mut renderer)?;
        sky = gpu.sky(&mut renderer)?;
        sky_seen = gpu.sky_seen(&mut renderer)?;
    }
    // A run stopped in the view-dependent start still ends at the knobs'
    // degree.
    if field.sh_degree != knobs.sh_degree {
        field = with_sh_degree(field, knobs.sh_degree);
    }
    // Only a new sky is filled: a resumed one's texels that this run's
    // rays missed keep their values (filled from this run's few texels,
    // a short resume smoothed away what the first run learnt).
    if let (Some(s), None) = (&mut sky, resumed_sky) {
        s.fill_unseen(&sky_seen);
    }
    // A field with no density shows nothing an object could be put into:
    // never written as if trained.
    anyhow::ensure!(
        field.holds_density(),
        "training left the field empty: after {step} steps no node's density is above zero, \
         every ray's light given to what lies behind the field; check that the bounds hold what \
         the photographs show (`inlay dataset` prints them) and the knobs that pull density \
         down (--sparsity {}, --density-rate {})",
        knobs.sparsity,
        knobs.density_rate
    );
    // Pruned unless Ctrl-C ended the run (the field so far, at once), and
    // not where pruning would leave nothing (a run stopped by its time
    // budget in its first steps: no training ray yet weighs the grey
    // start's nodes as much as the threshold).
    let mut pruned = 0;
    if knobs.prune > 0.0 && !(control.stop)() {
        let visibility = visibility_of(&mut renderer, &field)?;
        let (kept, n) = super::prune::prune(&field, &visibility, knobs.prune);
        if kept.holds_density() {
            (field, pruned) = (kept, n);
        } else {
            log::info!("pruning would leave no density: the field is kept unpruned");
        }
    }
    // Empty space below zero costs a sparse file its bricks; zeroing it
    // changes no density.
    (field, _) = super::prune::clear_inert_negatives(&field);
    let behind = sky.as_ref().map_or(Behind::Colour(background), Behind::Sky);
    let held_out = if control.score_held_out {
        score_held_out(
            dataset,
            &pool.held_out,
            &field,
            knobs,
            behind,
            control.seen_lights,
        )
    } else {
        Vec::new()
    };
    Ok(Trained {
        field,
        history,
        held_out,
        steps: step,
        scale,
        pruned,
        gains,
        bricks,
        sky,
        sky_seen: sky_seen.iter().filter(|s| **s).count(),
        step_times,
        emptied,
    })
}

/// `dataset`'s frames `held` (held out of training) rendered from `field`
/// over `behind` with `seen_lights` beside it, and scored: each pose once,
/// a bracketed one as its brackets merged ([`merged_brackets`]).
pub fn score_held_out(
    dataset: &Dataset,
    held: &[u32],
    field: &GridField,
    knobs: &TrainKnobs,
    behind: Behind,
    seen_lights: &[SeenLight],
) -> Vec<HeldOutView> {
    let sets = bracket_sets(dataset, held);
    held.iter()
        .filter(|&&f| sets[f as usize][0] == f)
        .map(|&f| {
            let set = &sets[f as usize];
            let merged =
                is_bracket(&dataset.frames[f as usize]).then(|| merged_brackets(dataset, set));
            let frame = merged.as_ref().unwrap_or(&dataset.frames[f as usize]);
            HeldOutView {
                brackets: set.len(),
                ..score_view(
                    frame,
                    f,
                    field,
                    &view_march(knobs),
                    behind,
                    seen_lights,
                    knobs.learn_exposure,
                    knobs.held_out_samples,
                )
            }
        })
        .collect()
}

/// Colours more than this many × the loss's floor ε step by the colour
/// rate's share of themselves (a tenth at the defaults;
/// [`AdamKnobs::relative_floor`]): a lamp's, not a surface's.
/// Every colour above 1 × ε stepping by ε's share of itself cost DOG's
/// held-out views 0.3-0.6 dB and brightened them 3 %; a tenth of every
/// colour, 4-5 dB on DOG and 2.5-6.5 dB on PLANTS (`docs/benchmarks.md`).
pub const RELATIVE_STEP_FLOOR: f64 = 8.0;

/// The exposure gains' Adam step size (the gains are near 1: a step of
/// 1 % at most, decaying with the grid's).
pub const GAIN_RATE: f64 = 0.03;

/// The PSNR of a batch's pixels `out` (r, g, b, loss per ray) against what
/// its photographs say, on sRGB values clipped at 1 as the held-out views
/// are scored: a bracket at its exposure, a lower bound only where the
/// pixel falls below it.
pub fn batch_psnr(batch: &[super::pixels::BatchPixel], out: &[[f32; 4]]) -> f64 {
    use super::PixelTarget;
    let mut se = 0.0;
    let mut n = 0usize;
    for ((_, target, ..), o) in batch.iter().zip(out) {
        let c = DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64);
        for k in 0..3 {
            let (a, b) = match *target {
                PixelTarget::Value(y) => (encoded(c[k]), encoded(y[k])),
                PixelTarget::AtLeast(y) => (encoded(c[k].min(y[k])), encoded(y[k])),
                PixelTarget::Bracket {
                    encoded: y,
                    exposure,
                } => (encoded(exposure * c[k]), y[k]),
            };
            se += (a - b).powi(2);
            n += 1;
        }
    }
    -10.0 * (se / n.max(1) as f64).max(1e-12).log10()
}

/// The RGB gain g minimising Σ (g·recorded − photograph)² over `frame`'s
/// usable pixels (a bracket's saturated ones left out), per channel.
fn fitted_gain(frame: &crate::dataset::Frame, recorded: &[DVec3]) -> DVec3 {
    let (mut rt, mut rr) = (DVec3::ZERO, DVec3::ZERO);
    for (i, r) in recorded.iter().enumerate() {
        let t = DVec3::from_array(frame.image.radiance[i].map(|v| v as f64));
        if frame.image.state[i] != PixelState::Value
            || (is_bracket(frame) && t.max_element() >= 1.0)
        {
            continue;
        }
        rt += *r * t;
        rr += *r * *r;
    }
    DVec3::select(rr.cmpgt(DVec3::ZERO), rt / rr, DVec3::ONE)
}

/// A rendered view's scores against its photograph ([`HeldOutView`]'s
/// figures) over the pixels not masked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewScores {
    /// PSNR in dB on sRGB-encoded values clipped at 1.
    pub psnr: f64,
    /// Σ|L_rendered − L_photo| / Σ L_photo in luminance.
    pub relative_error: f64,
    /// Σ L_rendered / Σ L_photo.
    pub brightness: f64,
}

/// [`ViewScores`] of `rendered` against `truth` (linear rgb), leaving out
/// the pixels `state` masks; with no light in the photograph the relative
/// figures are infinite. A lower bound (saturated in every exposure) is
/// scored against the nearest radiance it allows, each channel the larger
/// of the bound and the rendered value: a field brighter than the bound
/// is not wrong there, one darker is wrong by what it lacks.
pub fn view_scores(rendered: &[[f32; 3]], truth: &[[f32; 3]], state: &[PixelState]) -> ViewScores {
    let (mut se, mut n, mut diff, mut total, mut ours) = (0.0, 0usize, 0.0, 0.0, 0.0);
    for (i, (a, b)) in rendered.iter().zip(truth).enumerate() {
        let bound;
        let b = match state[i] {
            PixelState::Masked => continue,
            PixelState::LowerBound => {
                bound = [0, 1, 2].map(|k| b[k].max(a[k]));
                &bound
            }
            PixelState::Value => b,
        };
        let (la, lb) = (
            luminance(DVec3::from_array(a.map(|v| v as f64))),
            luminance(DVec3::from_array(b.map(|v| v as f64))),
        );
        diff += (la - lb).abs();
        total += lb;
        ours += la;
        for k in 0..3 {
            se += (encoded(a[k] as f64) - encoded(b[k] as f64)).powi(2);
        }
        n += 3;
    }
    let mse = se / n.max(1) as f64;
    let relative = |x: f64| {
        if total > 0.0 {
            x / total
        } else {
            f64::INFINITY
        }
    };
    ViewScores {
        psnr: -10.0 * mse.max(1e-12).log10(),
        relative_error: relative(diff),
        brightness: relative(ours),
    }
}

/// The march a trained field's views are rendered and scored with: the
/// training's samples along the diagonal, empty space skipped.
pub fn view_march(knobs: &TrainKnobs) -> MarchKnobs {
    MarchKnobs {
        samples_per_ray: knobs.samples_per_ray,
        termination: 1e-4,
        skip_empty: true,
    }
}

/// Renders `frame` (frame `f` of its dataset, or a pose's brackets
/// merged: [`merged_brackets`]) from `field` over `background` (a
/// colour or a learnt sky), with `lights` beside it, and scores it; with
/// `fit_exposure`, at the RGB gain that fits the photograph best (least
/// squares over its usable pixels: a frame of unknown exposure). Each
/// pixel is the mean of `samples` × `samples` rays spread evenly over it
/// (1: the ray through its centre), a light's share of it read over finer
/// rays, as its photograph gathered it ([`view_pixel`]).
#[allow(clippy::too_many_arguments)]
pub fn score_view<'a>(
    frame: &Frame,
    f: u32,
    field: &GridField,
    march: &MarchKnobs,
    background: impl Into<Behind<'a>>,
    lights: &[SeenLight],
    fit_exposure: bool,
    samples: u32,
) -> HeldOutView {
    let behind = background.into();
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    let exposure = if is_bracket(frame) {
        frame.exposure_time
    } else {
        None
    };
    // What the sensor records of radiance c, before clipping.
    let recorded = |c: DVec3| c * exposure.unwrap_or(1.0);
    let split = PixelSplit::new(samples, lights);
    let radiance: Vec<DVec3> = (0..w * h)
        .into_par_iter()
        .map(|p| recorded(view_pixel(frame, p, field, march, &behind, lights, &split)))
        .collect();
    let gain = if fit_exposure {
        fitted_gain(frame, &radiance)
    } else {
        DVec3::ONE
    };
    let rendered: Vec<[f32; 3]> = radiance
        .iter()
        .map(|c| {
            let c = gain * *c;
            match exposure {
                Some(_) => c.clamp(DVec3::ZERO, DVec3::ONE),
                None => c,
            }
            .as_vec3()
            .to_array()
        })
        .collect();
    let truth: Vec<[f32; 3]> = frame.image.radiance.clone();
    let s = view_scores(&rendered, &truth, &frame.image.state);
    // The same scores over the pixels that look into the bounds.
    let inside: Vec<PixelState> = (0..w * h)
        .map(|p| match frame.image.state[p as usize] {
            PixelState::Masked => PixelState::Masked,
            _ if !frame_sees_bounds(frame, p, &field.bounds) => PixelState::Masked,
            state => state,
        })
        .collect();
    let usable =
        |states: &[PixelState]| states.iter().filter(|s| **s != PixelState::Masked).count();
    let (all, seen) = (usable(&frame.image.state), usable(&inside));
    let in_bounds = (seen > 0 && seen < all).then(|| {
        (
            view_scores(&rendered, &truth, &inside).psnr,
            seen as f64 / all as f64,
        )
    });
    HeldOutView {
        frame: f,
        brackets: 1,
        psnr: s.psnr,
        relative_error: s.relative_error,
        brightness: s.brightness,
        in_bounds,
        truth,
        rendered,
        size: (w, h),
        spread: surface_spread(frame, field, march),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train::pixels::{area_offsets, pixel_ray_at, PixelRays};
    use crate::train::seen_lights::fit::COVERAGE_RAYS;
    use crate::train::seen_lights::with_seen_lights;

    /// One ray through each pixel's centre.
    const CENTRE: PixelRays = PixelRays {
        area: 1,
        jitter: false,
    };

    /// Refining a surface to the next stage's grid leaves it where it was
    /// (the interpolated density crosses zero at the same place) and, at
    /// exponent 1, as steep per node: each node's optical depth per
    /// spacing is the coarse grid's at the same point; at 0 the field is
    /// the plain resampling.
    #[test]
    fn refining_keeps_the_surfaces_and_steepens_them() {
        // Along x, density −4 + 16·x over [0, 1] (a surface at x = 0.25,
        // density below zero in front of it), 5 nodes a side.
        let res = UVec3::splat(5);
        let bounds = crate::geometry::Aabb::new(DVec3::ZERO, DVec3::ONE);
        let h = 0.25;
        let nodes: Vec<[f32; 4]> = (0..125)
            .map(|n| [0.5, 0.5, 0.5, (-4.0 + 16.0 * (n % 5) as f64 * h) as f32])
            .collect();
        let coarse = GridField::new(res, bounds, nodes, DEFAULT_OCCUPANCY_BLOCK);
        let fine_res = UVec3::splat(9);
        let plain = refine(&coarse, fine_res, 0.0);
        let resampled = resample(&coarse, fine_res);
        assert_eq!(plain.nodes, resampled.nodes);
        let steep = refine(&coarse, fine_res, 1.0);
        let at = |f: &GridField, x: f64| f.interpolate(DVec3::new(x, 0.5, 0.5))[3];
        for f in [&plain, &steep] {
            assert!(
                at(f, 0.25).abs() < 1e-6,
                "the surface moved: {}",
                at(f, 0.25)
            );
        }
        // The node spacing halves, so each density doubles.
        for x in [0.0, 0.125, 0.5, 0.875, 1.0] {
            let (p, s) = (at(&plain, x), at(&steep, x));
            assert!((s - 2.0 * p).abs() < 1e-5, "at {x}: {s} against 2 × {p}");
            // Optical depth per spacing: the coarse grid's at the same point.
            assert!((s * 0.125 - at(&coarse, x) * h).abs() < 1e-5);
        }
        let half = refine(&coarse, fine_res, 0.5);
        let gain = at(&half, 1.0) / at(&plain, 1.0);
        assert!((gain - 2f64.sqrt()).abs() < 1e-6, "gain {gain}");
        assert_eq!(half.occupancy.cells, plain.occupancy.cells);
    }

    /// A dataset of no frames whose pixels counted `transparent` with
    /// alpha below 1.
    fn dataset_with(transparent: usize) -> Dataset {
        Dataset {
            file: "shots/transforms.json".into(),
            dialect: crate::dataset::Dialect::InstantNgp,
            frames: Vec::new(),
            bounds: crate::geometry::Aabb::new(DVec3::ZERO, DVec3::ONE),
            bounds_source: crate::dataset::BoundsSource::AabbKey,
            counts: crate::dataset::pixels::PixelCounts {
                transparent,
                ..Default::default()
            },
            skipped: Vec::new(),
        }
    }

    /// One view of radiance `radiance` (linear), as an EXR frame or, with
    /// `exposure`, as an 8-bit sRGB bracket taken at that exposure (its
    /// saturated pixels lower bounds, as the loader marks them).
    fn frame_of(radiance: &[f32], exposure: Option<f32>) -> crate::dataset::Frame {
        let recorded: Vec<(f32, PixelState)> = radiance
            .iter()
            .map(|&v| match exposure {
                None => (v, PixelState::Value),
                Some(e) => match crate::dataset::capture::bracket_reading(v, e) {
                    (r, true) => (r, PixelState::LowerBound),
                    (r, false) => (r, PixelState::Value),
                },
            })
            .collect();
        let n = radiance.len() as u32;
        crate::dataset::Frame {
            index: 0,
            image_path: if exposure.is_some() { "v.png" } else { "v.exr" }.into(),
            pose: crate::dataset::Pose::looking_at(DVec3::Z, DVec3::ZERO, DVec3::Y),
            intrinsics: crate::dataset::Intrinsics::centred(n, 1, 40.0),
            exposure_time: exposure.map(f64::from),
            exif_exposure: None,
            image: crate::dataset::FrameImage {
                width: n,
                height: 1,
                radiance: recorded.iter().map(|(v, _)| [*v; 3]).collect(),
                state: recorded.iter().map(|(_, s)| *s).collect(),
                alpha: Vec::new(),
                counts: Default::default(),
            },
            depth: Vec::new(),
        }
    }

    /// A bracketed pose is held out whole (its brackets would otherwise
    /// train the pose its held-out bracket is scored on), and its
    /// brackets merge into the radiance each pixel's longest unsaturated
    /// bracket records over its exposure; linear frames are held out as
    /// before, one frame a pose.
    #[test]
    fn a_bracketed_pose_is_held_out_whole_and_merged_into_radiance() {
        use crate::train::pixels::{held_out_frames, merged_brackets, poses};
        let radiance: Vec<f32> = (0..50)
            .map(|i| if i == 7 { 40.0 } else { 0.02 + 0.01 * i as f32 })
            .collect();
        let mut d = dataset_with(0);
        for k in 0..4 {
            for e in [1.0, 1.0 / 8.0, 1.0 / 64.0] {
                let mut f = frame_of(&radiance, Some(e));
                let eye = DVec3::new(k as f64, 0.0, 1.0);
                f.pose = crate::dataset::Pose::looking_at(eye, DVec3::ZERO, DVec3::Y);
                d.frames.push(f);
            }
        }
        assert_eq!(poses(&d).len(), 4);
        let held = PixelPool::new(&d, 1).held_out;
        assert_eq!(held, vec![6, 7, 8]);
        let merged = merged_brackets(&d, &[6, 7, 8]);
        assert_eq!(merged.exposure_time, None);
        for (i, &v) in radiance.iter().enumerate() {
            let m = merged.image.radiance[i][0];
            assert_eq!(merged.image.state[i], PixelState::Value, "pixel {i}");
            assert!((m / v - 1.0).abs() < 0.03, "pixel {i}: {m} against {v}");
        }
        // Pixel 7 saturates the longest exposures; the shortest holds it.
        assert_eq!(d.frames[6].image.state[7], PixelState::LowerBound);
        let mut linear = dataset_with(0);
        linear.frames = (0..5).map(|_| frame_of(&radiance, None)).collect();
        assert_eq!(PixelPool::new(&linear, 2).held_out, held_out_frames(5, 2));
    }

    /// The loss's and the colours' scale is the scene's mean radiance
    /// whether the photographs are linear or brackets of one pose, merged
    /// at each pixel. Read as they were recorded, brackets at 1/64, 1/8
    /// and 1 of a view whose mean is 0.44 (a lamp of 40 that only the
    /// darkest holds is 45 % of it) read 0.097; with each bracket's value
    /// over its exposure and its saturated pixels left out, 0.31.
    #[test]
    fn brackets_give_the_scale_of_the_radiance_they_record() {
        let radiance: Vec<f32> = (0..200)
            .map(|i| {
                if i == 7 {
                    40.0
                } else {
                    0.02 + 0.5 * (i % 10) as f32 / 10.0
                }
            })
            .collect();
        let dataset = |frames: Vec<crate::dataset::Frame>| Dataset {
            frames,
            ..dataset_with(0)
        };
        let linear = dataset(vec![frame_of(&radiance, None)]);
        let brackets = dataset(
            [1.0 / 64.0, 1.0 / 8.0, 1.0]
                .map(|e| frame_of(&radiance, Some(e)))
                .to_vec(),
        );
        let of = |d: &Dataset| radiance_scale(d, &training_frames(d, 0), &d.bounds);
        let truth = of(&linear);
        let read = of(&brackets);
        assert!(
            (read / truth - 1.0).abs() < 0.05,
            "brackets {read}, linear {truth}"
        );
    }

    /// A light that one view of three sees sets no scale: the view is
    /// left out (its mean is 101 times the others'; over every pixel of
    /// the three the mean would be 34 times their grey), and the scale
    /// is the others' grey.
    #[test]
    fn a_light_few_views_see_sets_no_scale() {
        let grey = vec![0.2f32; 50];
        let mut lamp = grey.clone();
        lamp[25] = 1000.0;
        let dataset = Dataset {
            frames: vec![
                frame_of(&grey, None),
                frame_of(&lamp, None),
                frame_of(&grey, None),
            ],
            // Bounds round the cameras: every pixel looks into them.
            bounds: crate::geometry::Aabb::new(DVec3::splat(-10.0), DVec3::splat(10.0)),
            ..dataset_with(0)
        };
        let scale = radiance_scale(&dataset, &training_frames(&dataset, 0), &dataset.bounds);
        assert!((scale - 0.2).abs() < 1e-6, "{scale}");
        // Two views of three with the lamp: the median view has it, and
        // the grey view is no outlier, so the scale is the views' mean.
        let dataset = Dataset {
            frames: vec![
                frame_of(&grey, None),
                frame_of(&lamp, None),
                frame_of(&lamp, None),
            ],
            ..dataset
        };
        let scale = radiance_scale(&dataset, &training_frames(&dataset, 0), &dataset.bounds);
        let with_lamp = (49.0 * 0.2 + 1000.0) / 50.0;
        let mean = (0.2 + 2.0 * with_lamp) / 3.0;
        assert!((scale - mean).abs() < 1e-4, "{scale} {mean}");
    }

    /// A batch comes in the order of its frames and pixels (the device
    /// marches neighbouring rays of a view side by side), and holds the
    /// pixels the seed and step draw, whatever their order.
    #[test]
    fn a_batch_is_drawn_at_random_and_ordered_by_frame_and_pixel() {
        let radiance: Vec<f32> = (0..200).map(|i| i as f32 / 200.0).collect();
        let dataset = Dataset {
            frames: (0..3).map(|_| frame_of(&radiance, None)).collect(),
            ..dataset_with(0)
        };
        let pool = PixelPool::new(&dataset, 0);
        let batch = pool.batch(&dataset, &[], 64, 1, 5, DVec3::ZERO, CENTRE);
        assert_eq!(batch.len(), 64);
        let keys: Vec<(u32, f64)> = batch.iter().map(|(r, _, f, _)| (*f, r[0].dir.x)).collect();
        assert!(keys.windows(2).all(|w| w[0].0 <= w[1].0), "{keys:?}");
        assert!(keys.iter().any(|k| k.0 == 0) && keys.iter().any(|k| k.0 == 2));
        // The same draw for the same seed and step, another for the next step.
        assert_eq!(
            pool.batch(&dataset, &[], 64, 1, 5, DVec3::ZERO, CENTRE),
            batch
        );
        assert_ne!(
            pool.batch(&dataset, &[], 64, 1, 6, DVec3::ZERO, CENTRE),
            batch
        );
    }

    /// Depth maps given beside the dataset stand in for its frames' own
    /// frame by frame: a frame given a map reads its pixels' depths from
    /// it (z over the ray's cosine to the camera's axis; none where it
    /// records 0), a frame given an empty one keeps its own, and a frame
    /// with neither has none.
    #[test]
    fn depth_maps_given_beside_the_frames_stand_in_for_theirs() {
        let radiance: Vec<f32> = (0..200).map(|i| i as f32 / 200.0).collect();
        let mut own = frame_of(&radiance, None);
        own.depth = vec![3.0; 200];
        let dataset = Dataset {
            frames: vec![frame_of(&radiance, None), own, frame_of(&radiance, None)],
            ..dataset_with(0)
        };
        let given: Vec<f32> = (0..200)
            .map(|p| if p % 2 == 0 { 2.0 } else { 0.0 })
            .collect();
        let depth = vec![given, Vec::new(), Vec::new()];
        let pool = PixelPool::new(&dataset, 0);
        let batch = pool.batch(&dataset, &depth, 256, 1, 5, DVec3::ZERO, CENTRE);
        let mut seen = [0; 3];
        for (rays, _, f, depths) in &batch {
            let frame = &dataset.frames[*f as usize];
            let cos = rays[0].dir.normalize().dot(frame.pose.forward());
            let (u, _) = frame
                .intrinsics
                .project(frame.pose.matrix.inverse().transform_vector3(rays[0].dir))
                .unwrap();
            let p = u.floor() as usize;
            let want = match f {
                0 => (p % 2 == 0).then(|| 2.0 / cos),
                1 => Some(3.0 / cos),
                _ => None,
            };
            let got = depths[0];
            assert!(
                got.zip(want)
                    .map_or(got == want, |(g, w)| (g - w).abs() < 1e-9),
                "frame {f} pixel {p}: {got:?} against {want:?}"
            );
            seen[*f as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
    }

    /// A pixel's n × n rays pass through its own area (each through its
    /// part of an even split: at its centre, or jittered over it) and carry
    /// the pixel's value.
    #[test]
    fn a_pixels_rays_stay_inside_the_pixel_they_are_scored_on() {
        let radiance: Vec<f32> = (0..200).map(|i| i as f32 / 200.0).collect();
        let dataset = Dataset {
            frames: vec![frame_of(&radiance, None)],
            ..dataset_with(0)
        };
        let frame = &dataset.frames[0];
        let to_camera = frame.pose.matrix.inverse();
        let pool = PixelPool::new(&dataset, 0);
        for area in [1u32, 2, 3] {
            for jitter in [false, true] {
                let rays = PixelRays { area, jitter };
                let batch = pool.batch(&dataset, &[], 256, 1, 5, DVec3::ZERO, rays);
                let mut offsets = Vec::new();
                for (pixel_rays, target, ..) in &batch {
                    assert_eq!(pixel_rays.len() as u32, area * area);
                    for (k, ray) in pixel_rays.iter().enumerate() {
                        let (u, v) = frame
                            .intrinsics
                            .project(to_camera.transform_vector3(ray.dir))
                            .unwrap();
                        let pixel = u.floor() as usize;
                        assert!((0.0..=1.0).contains(&v), "{v}");
                        assert_eq!(
                            *target,
                            crate::train::PixelTarget::Value(DVec3::splat(radiance[pixel] as f64)),
                            "u {u}"
                        );
                        // Ray k lies in column k mod n of the split.
                        let part = (k as u32 % area) as f64 / area as f64;
                        let o = u - u.floor();
                        assert!(
                            o >= part - 1e-9 && o <= part + 1.0 / area as f64 + 1e-9,
                            "area {area}: ray {k} at {o}"
                        );
                        offsets.push(o);
                    }
                }
                let (lo, hi) = offsets
                    .iter()
                    .fold((1.0f64, 0.0f64), |(lo, hi), o| (lo.min(*o), hi.max(*o)));
                if jitter {
                    assert!(lo < 0.05 && hi > 0.95, "{lo} {hi}");
                } else {
                    let first = 0.5 / area as f64;
                    assert!(
                        (lo - first).abs() < 1e-6 && (hi - (1.0 - first)).abs() < 1e-6,
                        "{lo} {hi}"
                    );
                }
            }
        }
    }

    /// A held-out pixel is the mean of its rays: where a sharp edge of the
    /// sky crosses a pixel a quarter of the way in, as its photograph
    /// averaged it, 4 × 4 rays read the blend and the centre ray one side.
    #[test]
    fn a_held_out_pixel_is_the_mean_over_its_area() {
        // 8 × 1 pixels looking along −z, 0.087 rad a pixel; the direction
        // x = 0 (where the sky turns from 0 to 1) through u = 3.25.
        let truth = [0.0, 0.0, 0.0, 0.75, 1.0, 1.0, 1.0, 1.0];
        let mut frame = frame_of(&truth, None);
        frame.intrinsics = crate::dataset::Intrinsics::centred(8, 1, 5.0);
        frame.intrinsics.cx = 3.25;
        let dataset = Dataset {
            frames: vec![frame],
            ..dataset_with(0)
        };
        // 2048 × 1024 texels, a texel 0.035 pixels: x < 0 reads 0, x > 0
        // reads 1 (φ = atan2(z, x)), blended over a texel at the edge.
        let (w, h) = (2048u32, 1024u32);
        let texels = (0..w * h)
            .map(|i| {
                let phi = ((i % w) as f64 + 0.5) / w as f64 * std::f64::consts::TAU;
                DVec3::splat(if phi.cos() < 0.0 { 0.0 } else { 1.0 })
            })
            .collect();
        let sky = Sky::new(w, h, texels).unwrap();
        let empty = GridField::new(UVec3::splat(2), dataset.bounds, vec![[0.0; 4]; 8], 8);
        let knobs = MarchKnobs::default();
        let view = |n| score_view(&dataset.frames[0], 0, &empty, &knobs, &sky, &[], false, n);
        let (centre, area) = (view(1), view(4));
        let read = |v: &HeldOutView| v.rendered.iter().map(|c| c[0]).collect::<Vec<f32>>();
        for (p, t) in truth.iter().enumerate() {
            assert!((read(&area)[p] - t).abs() < 1e-3, "{:?}", read(&area));
            let side = if p < 3 { 0.0 } else { 1.0 };
            assert!(
                (read(&centre)[p] - side).abs() < 1e-3,
                "{:?}",
                read(&centre)
            );
        }
        assert!(
            area.psnr > centre.psnr + 20.0,
            "{} {}",
            area.psnr,
            centre.psnr
        );
    }

    /// A bright light that covers a small part of a held-out pixel,
    /// between its 4 × 4 rays, is drawn at the share it covers (the share
    /// the lights' fit reads, and near the disc's area over the pixel's):
    /// the centre rays alone read it black. Pixels it does not touch read
    /// as they would with no light at all.
    #[test]
    fn a_light_between_a_pixels_rays_is_drawn_at_the_share_it_covers() {
        let mut frame = frame_of(&[0.0; 8], None);
        frame.intrinsics = crate::dataset::Intrinsics::centred(8, 1, 5.0);
        // A disc of 0.15 pixels' radius centred at (3.25, 0.25): 0.177
        // pixels from each of the four nearest of pixel 3's 4 × 4 rays.
        let to_world = |u: f64| {
            let d = frame.intrinsics.direction(u, 0.25).unwrap();
            frame.pose.to_world(d).normalize()
        };
        let (origin, distance) = (frame.pose.origin(), 20.0);
        let pixel_angle = to_world(3.25).angle_between(to_world(4.25));
        let light = SeenLight {
            centre: origin + distance * to_world(3.25),
            radius: 0.15 * pixel_angle * distance,
            radiance: DVec3::splat(1000.0),
            views: 3,
            residual: 0.0,
        };
        let dataset = Dataset {
            frames: vec![frame],
            ..dataset_with(0)
        };
        let empty = GridField::new(UVec3::splat(2), dataset.bounds, vec![[0.0; 4]; 8], 8);
        let (knobs, back) = (MarchKnobs::default(), DVec3::splat(0.2));
        let frame = &dataset.frames[0];
        let read = |lights: &[SeenLight], n| {
            score_view(frame, 0, &empty, &knobs, back, lights, false, n).rendered
        };
        // What the fit reads of the pixel: its 16 × 16 rays that meet it.
        let rays = area_offsets(COVERAGE_RAYS);
        let hits = rays
            .iter()
            .filter(|&&o| light.hit(&pixel_ray_at(frame, 3, o).unwrap()).is_some())
            .count();
        let share = hits as f64 / rays.len() as f64;
        let disc = std::f64::consts::PI * 0.15 * 0.15;
        assert!((share - disc).abs() < 0.2 * disc, "{share} {disc}");
        let expected = share * 1000.0 + (1.0 - share) * 0.2;
        let (with, without) = (read(&[light], 4), read(&[], 4));
        assert!(
            (with[3][0] as f64 - expected).abs() < 1e-3 * expected,
            "{} {expected}",
            with[3][0]
        );
        let centre_rays_only = (with_seen_lights_mean(frame, &light, &empty, back), 0.2);
        assert!((centre_rays_only.0 - centre_rays_only.1).abs() < 1e-9);
        for p in (0..8).filter(|&p| p != 3) {
            assert_eq!(with[p], without[p], "pixel {p}");
        }
    }

    /// Pixel 3 of `frame` as the mean of its 4 × 4 centre rays alone, each
    /// drawn with `light`: what held-out views read before a light's
    /// share was read over finer rays.
    fn with_seen_lights_mean(
        frame: &crate::dataset::Frame,
        light: &SeenLight,
        field: &GridField,
        back: DVec3,
    ) -> f64 {
        let offsets = area_offsets(4);
        let sum: f64 = offsets
            .iter()
            .map(|&o| {
                let ray = pixel_ray_at(frame, 3, o).unwrap();
                let r = crate::march::march_ray(field, &ray, f64::INFINITY, &MarchKnobs::default());
                with_seen_lights(&[*light], &ray, &field.bounds, r.colour, r.opacity, back).x
            })
            .sum();
        sum / offsets.len() as f64
    }

    /// A lamp past the shortest bracket's white is counted once for its
    /// pose; one the shortest records is not; linear frames have no
    /// brackets to count.
    #[test]
    fn a_light_every_bracket_saturates_is_counted() {
        let lamp = |v: f32| -> Vec<f32> { (0..50).map(|i| if i == 7 { v } else { 0.3 }).collect() };
        let brackets = |v: f32| Dataset {
            frames: [1.0 / 64.0, 1.0 / 8.0, 1.0]
                .map(|e| frame_of(&lamp(v), Some(e)))
                .to_vec(),
            ..dataset_with(0)
        };
        let s = super::super::pixels::saturated_in_every_bracket(&brackets(160.0));
        assert_eq!((s.pixels, s.poses, s.bracketed_poses), (1, 1, 1));
        assert_eq!(s.shortest, 1.0 / 64.0);
        let w = s.warning().expect("a pixel to warn of");
        assert!(
            w.contains("1 pixels of 1 of its 1") && w.contains("at least 64.0"),
            "{w}"
        );
        let s = super::super::pixels::saturated_in_every_bracket(&brackets(40.0));
        assert_eq!((s.pixels, s.poses, s.bracketed_poses), (0, 0, 1));
        assert_eq!(s.warning(), None);
        let linear = Dataset {
            frames: vec![frame_of(&lamp(160.0), None)],
            ..dataset_with(0)
        };
        let s = super::super::pixels::saturated_in_every_bracket(&linear);
        assert_eq!((s.pixels, s.bracketed_poses), (0, 0));
    }

    /// A random background is refused, naming the file, behind exposure
    /// brackets with transparent pixels, and taken behind transparent
    /// linear frames (their alpha composites it) and opaque brackets; a
    /// fixed one either way.
    #[test]
    fn a_random_background_is_refused_only_behind_transparent_brackets() {
        let random = TrainKnobs {
            random_background: true,
            ..TrainKnobs::default()
        };
        let transparent = |exposure| {
            let mut f = frame_of(&[0.2, 0.4, 0.6], exposure);
            f.image.alpha = vec![1.0, 0.5, 0.0];
            f
        };
        let with = |frames| Dataset {
            frames,
            ..dataset_with(0)
        };
        let e = check_dataset(&random, &with(vec![transparent(Some(1.0))]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("shots/transforms.json") && e.contains("2 pixels"),
            "{e}"
        );
        assert!(check_dataset(&random, &with(vec![transparent(None)])).is_ok());
        let opaque = frame_of(&[0.2; 3], Some(1.0));
        assert!(check_dataset(&random, &with(vec![opaque])).is_ok());
        let fixed = TrainKnobs::default();
        assert!(check_dataset(&fixed, &with(vec![transparent(Some(1.0))])).is_ok());
    }

    /// Photographs that record no light are refused before any work,
    /// naming the file (training would end in an empty field); one lit
    /// pixel is enough, a masked one is not.
    #[test]
    fn photographs_that_record_no_light_are_refused() {
        let fixed = TrainKnobs::default();
        let with = |frames| Dataset {
            frames,
            ..dataset_with(0)
        };
        let black = frame_of(&[0.0; 3], None);
        let e = check_dataset(&fixed, &with(vec![black.clone(), black.clone()]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("shots/transforms.json: every usable pixel of its 2 frames is black"),
            "{e}"
        );
        let mut masked = frame_of(&[0.0, 0.3, 0.0], None);
        masked.image.state[1] = PixelState::Masked;
        assert!(check_dataset(&fixed, &with(vec![black.clone(), masked])).is_err());
        let lit = frame_of(&[0.0, 0.3, 0.0], None);
        assert!(check_dataset(&fixed, &with(vec![black, lit])).is_ok());
    }

    /// A transparent pixel trained over another background says its
    /// radiance plus its uncovered share of the difference; an opaque one
    /// and a bracket say what they recorded.
    #[test]
    fn a_transparent_pixel_takes_the_steps_background_behind_it() {
        use super::super::pixels::pixel_target;
        use super::super::PixelTarget;
        let shift = DVec3::new(1.0, 2.0, 3.0);
        let mut linear = frame_of(&[0.2, 0.4, 0.6], None);
        linear.image.alpha = vec![1.0, 0.25, 0.0];
        let value = |f: &crate::dataset::Frame, p| match pixel_target(f, p, shift) {
            Some(PixelTarget::Value(v)) => v,
            t => panic!("{t:?}"),
        };
        let close = |a: DVec3, b: DVec3| (a - b).abs().max_element() < 1e-6;
        assert!(close(value(&linear, 0), DVec3::splat(0.2)));
        assert!(close(value(&linear, 1), DVec3::splat(0.4) + 0.75 * shift));
        assert!(close(value(&linear, 2), DVec3::splat(0.6) + shift));
        let mut bracket = frame_of(&[0.2, 0.4, 0.6], Some(1.0));
        bracket.image.alpha = vec![1.0, 0.25, 0.0];
        assert_eq!(
            pixel_target(&bracket, 1, shift),
            pixel_target(&bracket, 1, DVec3::ZERO)
        );
    }

    /// The fixed background is every step's; a random one differs from
    /// step to step, stays in [0, 2·scale) per channel, and averages the
    /// scale.
    #[test]
    fn each_step_draws_its_own_background() {
        let bg = DVec3::new(0.1, 0.2, 0.3);
        assert_eq!(step_background(&TrainKnobs::default(), bg, 0.5, 7), bg);
        let random = TrainKnobs {
            random_background: true,
            ..TrainKnobs::default()
        };
        let draws: Vec<DVec3> = (0..2000)
            .map(|s| step_background(&random, bg, 0.5, s))
            .collect();
        assert_ne!(draws[0], draws[1]);
        assert!(draws
            .iter()
            .all(|d| d.min_element() >= 0.0 && d.max_element() < 1.0));
        let mean = draws.iter().sum::<DVec3>() / draws.len() as f64;
        assert!(
            (mean - DVec3::splat(0.5)).abs().max_element() < 0.03,
            "{mean}"
        );
    }

    /// A view 10 % too bright everywhere scores brightness 1.1 and
    /// relative error 0.1; a darker one the other way; masked pixels and
    /// a black photograph are handled.
    #[test]
    fn view_scores_tell_a_bright_field_from_a_dark_one() {
        let truth = vec![[0.2f32, 0.2, 0.2], [0.4, 0.4, 0.4], [9.0, 0.0, 0.0]];
        let state = [PixelState::Value, PixelState::Value, PixelState::Masked];
        let scaled = |k: f32| -> Vec<[f32; 3]> { truth.iter().map(|p| p.map(|v| v * k)).collect() };
        let bright = view_scores(&scaled(1.1), &truth, &state);
        assert!((bright.brightness - 1.1).abs() < 1e-6, "{bright:?}");
        assert!((bright.relative_error - 0.1).abs() < 1e-6, "{bright:?}");
        let dark = view_scores(&scaled(0.9), &truth, &state);
        assert!((dark.brightness - 0.9).abs() < 1e-6 && (dark.relative_error - 0.1).abs() < 1e-6);
        let same = view_scores(&truth, &truth, &state);
        assert!(same.brightness == 1.0 && same.relative_error == 0.0 && same.psnr >= 119.0);
        let black = vec![[0.0f32; 3]; 3];
        let none = view_scores(&scaled(1.0), &black, &state);
        assert!(none.brightness.is_infinite() && none.relative_error.is_infinite());
    }

    /// A lower bound scores a field above it as right and one below it
    /// wrong by what it lacks; read as a value, the field above it was
    /// scored wrong.
    #[test]
    fn a_lower_bound_is_scored_as_what_it_allows() {
        let truth = vec![[0.5f32; 3], [4.0; 3]];
        let (bounded, valued) = (
            [PixelState::Value, PixelState::LowerBound],
            [PixelState::Value, PixelState::Value],
        );
        let above = vec![[0.5f32; 3], [9.0; 3]];
        let s = view_scores(&above, &truth, &bounded);
        assert!(
            s.psnr >= 119.0 && s.relative_error == 0.0 && s.brightness == 1.0,
            "{s:?}"
        );
        let as_value = view_scores(&above, &truth, &valued);
        assert!(as_value.relative_error > 1.0, "{as_value:?}");
        let below = vec![[0.5f32; 3], [3.0; 3]];
        let s = view_scores(&below, &truth, &bounded);
        assert!((s.relative_error - 1.0 / 4.5).abs() < 1e-6, "{s:?}");
        assert!((s.brightness - 3.5 / 4.5).abs() < 1e-6, "{s:?}");
    }
}
