//! The whole estimate: render random views of the field on the GPU, reject
//! poor ones, draw surface points, trace their near-field light on the GPU,
//! then fit the albedo MLP and the environment's lobes on the CPU.

use std::sync::Arc;
use std::time::Instant;

use inlay_engine::graph::FrameGraph;
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{Context, ImageDesc, Readback, Renderer, SubmitSync};

use super::fit::{fit_environment, FitData, FitResult};
use super::knobs::EnvEstimateKnobs;
use super::known_lights::known_irradiance;
use super::near_field::{NearField, NearFieldTracer};
use super::near_lights::PointLight;
use super::outside_light::{keep_if_needed, OutsideLightTest};
use super::quality::{view_quality, QualityScore, ViewImage};
use super::surface::{
    covered_median, draw_points, emitter_limit, keep_seen, view_candidates, SurfacePoint,
};
use super::views::ViewSource;
use super::witnesses::{Witnesses, PHOTO_SPREAD_FLOOR};
use crate::camera::CameraFrame;
use crate::field::{GpuGridField, GridField};
use crate::march::{MarchKnobs, MarchPass, MARCH_COLOUR_FORMAT, MARCH_DEPTH_FORMAT};
use crate::rng::Pcg32;
use crate::sgfit::model::luminance;

/// Which stage an estimate is in, for progress reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Rendering and scoring views (done = views kept).
    Views,
    /// Tracing the near-field light (done = points traced).
    NearField,
    /// Fitting (done = steps; the loss comes along).
    Fit,
}

/// Receives progress: stage, done, total and (in the fit) the batch loss.
pub type Progress<'a> = &'a (dyn Fn(Stage, usize, usize, Option<f64>) + Sync);

/// The surface points and how the views went.
#[derive(Debug, Clone)]
pub struct SurfaceSample {
    /// Every point drawn.
    pub points: Vec<SurfacePoint>,
    /// Views rendered.
    pub views_tried: u32,
    /// Views kept.
    pub views_kept: u32,
    /// The score of every view tried, in order, and whether it was kept.
    pub scores: Vec<(QualityScore, bool)>,
    /// Pixels whose ray passes through the field, over all kept views.
    pub covered: usize,
    /// Covered pixels left out as not on a surface, over all kept views.
    pub not_surface: usize,
    /// Covered pixels left out as light sources, over all kept views.
    pub emitters: usize,
    /// Covered pixels left out as mixed, over all kept views.
    pub mixed: usize,
    /// Covered pixels left out as on a crease, over all kept views.
    pub creased: usize,
    /// Reading radiance from the photographs: the median, over the points
    /// read, of the reading's luminance over the field's pixel's (how far
    /// the field's colour is from its photographs').
    pub photo_ratio: Option<f64>,
    /// Candidates tried and left out as seen by no photograph (reading
    /// radiance from the photographs: or read by none, its pixels
    /// saturated or masked), over all views rendered.
    pub unseen: usize,
    /// Candidates tried and left out because the photographs that saw
    /// them disagree there, or only one or two did
    /// ([`EnvEstimateKnobs::max_photo_spread`]), over all views rendered.
    pub inconsistent: usize,
}

/// A finished estimate.
#[derive(Debug, Clone)]
pub struct EnvEstimate {
    /// The surface points and view statistics.
    pub surface: SurfaceSample,
    /// Their near-field light.
    pub near: NearField,
    /// The irradiance each point gets from the lights known beside the
    /// field (empty when none were given).
    pub known: Vec<glam::DVec3>,
    /// The fit and its lobes (black when the points need no light from
    /// outside the field: `outside`).
    pub fit: FitResult,
    /// Whether the points needed the light the fit found.
    pub outside: OutsideLightTest,
    /// Seconds spent on views, near-field light and the fit.
    pub seconds: [f64; 3],
}

/// Renders `frame` with the march and reads it back.
fn render_view(
    ctx: &Arc<Context>,
    renderer: &mut Renderer,
    march: &MarchPass,
    gpu: &GpuGridField,
    frame: &CameraFrame,
) -> anyhow::Result<ViewImage> {
    let desc = |format| ImageDesc {
        width: frame.width,
        height: frame.height,
        format,
    };
    let colour = Readback::new(ctx, desc(MARCH_COLOUR_FORMAT))?;
    let depth = Readback::new(ctx, desc(MARCH_DEPTH_FORMAT))?;
    renderer.begin_frame()?;
    let mut graph = FrameGraph::new();
    let out = march.add(&mut graph, gpu, frame, None);
    colour.add_to_graph(&mut graph, out.colour_opacity);
    depth.add_to_graph(&mut graph, out.depth);
    renderer.submit(graph, &SubmitSync::none())?;
    renderer.finish()?;
    Ok(ViewImage {
        width: frame.width,
        height: frame.height,
        colour_opacity: colour.read()?.pixels,
        depth: depth.read()?.pixels.iter().map(|p| p[0]).collect(),
    })
}

/// Views from `source`, scored, until `knobs.views` are kept (or the tries
/// run out), and their surface points.
#[allow(clippy::too_many_arguments)]
pub fn sample_surface(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    field: &GridField,
    gpu: &GpuGridField,
    march: MarchKnobs,
    knobs: &EnvEstimateKnobs,
    source: &ViewSource,
    seen_from: Option<&Witnesses>,
    progress: Progress,
) -> anyhow::Result<SurfaceSample> {
    let lib = &gpu.library(lib);
    let pass = MarchPass::new(ctx, lib, march)?;
    let mut renderer = Renderer::new(ctx, 1)?;
    let distance = 0.5 * field.bounds.size().max_element();
    let mut views: Vec<(u32, super::surface::ViewPoints)> = Vec::new();
    let max_tries = knobs.views * knobs.max_tries_per_view;
    let mut out = SurfaceSample {
        points: Vec::new(),
        views_tried: 0,
        views_kept: 0,
        scores: Vec::new(),
        covered: 0,
        not_surface: 0,
        emitters: 0,
        mixed: 0,
        creased: 0,
        unseen: 0,
        inconsistent: 0,
        photo_ratio: None,
    };
    let mut photo_ratios = Vec::new();
    // Whether points take their radiance from the photographs, and
    // whether the photographs judge them.
    let have_photos = seen_from.is_some_and(Witnesses::have_photos);
    let photos = have_photos && knobs.radiance_from_photos;
    let photo_check = have_photos && knobs.max_photo_spread > 0.0;
    let mut rejected = Vec::new();
    // Views that passed the quality score but had no surface point.
    let mut surfaceless = 0u32;
    while out.views_kept < knobs.views && out.views_tried < max_tries {
        let spec = source.view(&field.bounds, knobs.seed, out.views_tried as u64);
        out.views_tried += 1;
        // A camera's view is the same each time: one rejected is not retried.
        if rejected.contains(&spec) {
            continue;
        }
        let frame = CameraFrame::new(&spec, knobs.view_size, knobs.view_size);
        let image = render_view(ctx, &mut renderer, &pass, gpu, &frame)?;
        let score = view_quality(&image, distance);
        // A photograph's camera saw what it saw: it is not rejected for
        // covering little of its view (DOG's training cameras, 4.4 m away,
        // cover 15-22 % of theirs), only for blur or near clutter.
        let judged = match source {
            ViewSource::Sphere => score.score,
            ViewSource::Cameras(_) => score.flat.max(score.near),
        };
        let mut keep = judged <= knobs.quality_threshold;
        if keep {
            let mut candidates =
                view_candidates(field, &frame, &image, out.views_tried - 1, &march, knobs);
            if let Some(w) = seen_from {
                // Twice the points drawn, for those left out as lights.
                let mut rng = Pcg32::new(knobs.seed, 0x5EE4_0000_0000 | out.views_tried as u64);
                let count = 2 * knobs.pixels_per_view as usize;
                let mut inconsistent = 0;
                let floor = PHOTO_SPREAD_FLOOR * covered_median([&candidates]);
                candidates = keep_seen(candidates, count, &mut rng, |p| {
                    if photo_check {
                        match w.photo_spread(field, &march, p.position, p.normal) {
                            // Three photographs saw it: no need to ask again.
                            Some(s) if s.relative(floor) <= knobs.max_photo_spread => {
                                if !photos {
                                    return true;
                                }
                            }
                            None if !w.saw(field, &march, p.position, p.normal) => return false,
                            _ => {
                                inconsistent += 1;
                                return false;
                            }
                        }
                    }
                    if !photos {
                        return w.saw(field, &march, p.position, p.normal);
                    }
                    match w.photographed_radiance(field, &march, p.position, p.normal) {
                        Some(r) => {
                            photo_ratios.push(luminance(r) / luminance(p.radiance).max(1e-12));
                            p.radiance = r;
                            true
                        }
                        None => false,
                    }
                });
                candidates.unseen -= inconsistent;
                out.inconsistent += inconsistent;
                out.unseen += candidates.unseen;
            }
            // A view with no surface to draw from is as poor as an empty one.
            keep = !candidates.points.is_empty();
            if !keep {
                surfaceless += 1;
            }
            if keep {
                views.push((out.views_tried, candidates));
            }
        }
        out.scores.push((score, keep));
        if !keep && source.distinct().is_some() {
            rejected.push(spec);
        }
        if keep {
            out.views_kept += 1;
            progress(
                Stage::Views,
                out.views_kept as usize,
                knobs.views as usize,
                None,
            );
        }
    }
    // Light sources are judged against all the views' median at once.
    let limit = emitter_limit(views.iter().map(|(_, v)| v), knobs.emitter_ratio);
    for (tried, candidates) in views {
        let mut rng = Pcg32::new(knobs.seed, 0x5E1E_C700_0000 | tried as u64);
        let drawn = draw_points(candidates, limit, knobs.pixels_per_view as usize, &mut rng);
        out.covered += drawn.covered_luminance.len();
        out.not_surface += drawn.not_surface;
        out.emitters += drawn.emitters;
        out.mixed += drawn.mixed;
        out.creased += drawn.creased;
        out.points.extend(drawn.points);
    }
    if !photo_ratios.is_empty() {
        let mid = photo_ratios.len() / 2;
        out.photo_ratio = Some(*photo_ratios.select_nth_unstable_by(mid, f64::total_cmp).1);
    }
    anyhow::ensure!(
        !out.points.is_empty() || surfaceless == 0 || !photos,
        "{surfaceless} of {} views passed the quality check but no photograph gave a reading within 2× of the field's colour at any of their surface points: \
         were the photographs' exposures learnt in training (`inlay train --learn-exposure`), or are they scaled unlike the field?",
        out.views_tried
    );
    anyhow::ensure!(
        !out.points.is_empty() || surfaceless == 0 || out.inconsistent == 0,
        "{surfaceless} of {} views passed the quality check but at none of their {} surface points did three or more photographs see it and agree \
         (within --max-photo-spread {} of their median and its floor; {} points seen by none): the field's surfaces are not where its photographs put them, \
         as where a trainer left haze",
        out.views_tried,
        out.inconsistent,
        knobs.max_photo_spread,
        out.unseen
    );
    anyhow::ensure!(
        !out.points.is_empty() || surfaceless == 0,
        "{surfaceless} of {} views passed the quality check but held no surface point (surface test {:?}): \
         a field trained from photographs has surfaces a hundred times less steep than a bake's; \
         try the surface test `weight`",
        out.views_tried,
        knobs.surface_test
    );
    anyhow::ensure!(
        !out.points.is_empty(),
        "no view of the field passed the quality check ({} tried, threshold {}): is the field empty?",
        out.views_tried,
        knobs.quality_threshold
    );
    Ok(out)
}

/// Runs the whole estimate on `field`, its views from `source`, its
/// surface points those `seen_from` saw (all without), the `known` lights
/// beside it given ([`super::known_lights`]).
#[allow(clippy::too_many_arguments)]
pub fn estimate_environment(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    field: &GridField,
    march: MarchKnobs,
    knobs: &EnvEstimateKnobs,
    source: &ViewSource,
    seen_from: Option<&Witnesses>,
    known: &[PointLight],
    progress: Progress,
) -> anyhow::Result<EnvEstimate> {
    if let Some((k, m)) = knobs.problem() {
        anyhow::bail!("estimate knob `{k}`: {m}");
    }
    let gpu = GpuGridField::upload(ctx, field)?;
    let lib = &gpu.library(lib);
    let t0 = Instant::now();
    let surface = sample_surface(
        ctx, lib, field, &gpu, march, knobs, source, seen_from, progress,
    )?;
    let t1 = Instant::now();
    let tracer = NearFieldTracer::new(ctx, lib, march)?;
    let near = tracer.trace(
        ctx,
        field,
        &gpu,
        &surface.points,
        knobs.surface_test,
        knobs.rays_per_point,
        knobs.opacity_map,
        knobs.seed,
        &|done, total| progress(Stage::NearField, done, total, None),
    )?;
    ctx.check_validation()?;
    let t2 = Instant::now();
    let known = known_irradiance(&surface.points, &near, known);
    let data = FitData {
        points: &surface.points,
        near: &near,
        known: &known,
        bounds: field.bounds,
    };
    let fit = fit_environment(&data, knobs, &|step, steps, loss| {
        progress(Stage::Fit, step as usize, steps as usize, Some(loss))
    });
    let (outside, fit) = keep_if_needed(&data, knobs, fit);
    let t3 = Instant::now();
    Ok(EnvEstimate {
        surface,
        near,
        known,
        fit,
        outside,
        seconds: [
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
        ],
    })
}
