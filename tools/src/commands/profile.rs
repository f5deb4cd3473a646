//! `inlay profile SCENE`: runs N frames of a scene with its objects
//! inserted and prints the paper's Table 1 (per-module median and p95 GPU
//! time from timestamps, the first frame's SG update apart, frame total and
//! frame rate), writing the same as JSON and as a Chrome/Perfetto trace.
//! By default the first object is dragged along a small circle so the
//! probe and the fit run every frame, as they do while a user moves it;
//! `--motion still` shows what adaptive skipping saves.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use clap::{Args, ValueEnum};
use glam::DVec3;
use inlay_engine::graph::FrameGraph;
use inlay_engine::timing::FrameTimings;
use inlay_engine::{Context, Renderer, SubmitSync, DEFAULT_FRAMES_IN_FLIGHT};
use inlay_passes::envest::load_environment_file;
use inlay_passes::scene::{load_scene, ObjectEnvironment};
use serde_json::json;

use crate::chrome_trace::chrome_trace;
use crate::headless::{check_frame_size, Scene as _};
use crate::insertion_view::InsertionView;
use crate::outputs::{check_output, Outputs};
use crate::scene_view::open_view;
use crate::table1::summarise;

/// How the first object moves during the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Motion {
    /// Dragged along a circle of a quarter of its radius, a full turn per
    /// 60 frames: the incident light is updated every frame.
    Drag,
    /// Left where the scene puts it: after the first frame the probe and
    /// the fit are skipped.
    Still,
    /// Dragged for the first half of the frames, then left still: how many
    /// frames the lighting takes to settle once the object stops (a warm
    /// update spread over frames, `[lighting] frame_iterations`).
    Stop,
}

/// The first frame an object moving with `motion` over `frames` frames is
/// still in (None: it moves throughout, or never).
pub fn stop_frame(motion: Motion, frames: u32) -> Option<u32> {
    (motion == Motion::Stop).then_some(frames / 2)
}

/// How many frames from `stop` on ran the SG fit: the frames the lighting
/// took to settle after the object stopped.
pub fn settling_frames(frames: &[FrameTimings], stop: u32) -> usize {
    frames
        .iter()
        .skip(stop as usize)
        .filter(|f| {
            f.passes
                .iter()
                .any(|p| p.name == inlay_passes::sgfit::SG_FIT)
        })
        .count()
}

/// Options of `profile`.
#[derive(Args, Debug)]
pub struct ProfileArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Camera index or name.
    #[arg(long, default_value = "0")]
    pub camera: String,
    /// Width in pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Height in pixels.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Frames to run (the first is reported apart for the SG update).
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// How the first object moves.
    #[arg(long, value_enum, default_value_t = Motion::Drag)]
    pub motion: Motion,
    /// Where to write the table and every frame's timings as JSON.
    #[arg(long, default_value = "inlay-profile.json")]
    pub json: PathBuf,
    /// Where to write the Chrome/Perfetto trace.
    #[arg(long, default_value = "inlay-profile.trace.json")]
    pub trace: PathBuf,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Light the objects with this environment file (`inlay estimate-env`).
    #[arg(long)]
    pub environment: Option<PathBuf>,
    /// Segments across the field's diagonal (overrides `[march] samples_per_ray`).
    #[arg(long)]
    pub samples_per_ray: Option<u32>,
    /// Bake again even where a cached field or SSDF exists.
    #[arg(long)]
    pub no_cache: bool,
    /// Draw no shadows (no SSDF is loaded or baked; Shadow shows as skipped).
    #[arg(long)]
    pub no_shadows: bool,
    /// Pace the frames as the viewer does: the field's march kept while
    /// the camera holds still (NeRF rendering then times a copy and the
    /// objects' rectangle) and a moving object's lighting interleaved (a
    /// frame traces its probe share or runs the fit, in turn). The frame
    /// rate is the viewer's; the ratios are not Table 1's.
    #[arg(long)]
    pub viewer: bool,
}

/// What a profile run measured.
pub struct ProfileRun {
    /// Every frame's timings, oldest first.
    pub frames: Vec<FrameTimings>,
    /// When each frame was submitted, ms after the run began.
    pub submitted_ms: Vec<f64>,
}

/// Runs `frames` frames of `view` at `width`×`height` with `motion`,
/// keeping every frame's timings.
pub fn profile_view(
    ctx: &Arc<Context>,
    view: &mut InsertionView,
    width: u32,
    height: u32,
    frames: u32,
    motion: Motion,
) -> anyhow::Result<ProfileRun> {
    check_frame_size(ctx.info(), width, height)?;
    let start_pose = view.placed(0);
    let mut renderer = Renderer::new(ctx, DEFAULT_FRAMES_IN_FLIGHT)?;
    let began = Instant::now();
    let mut run = ProfileRun {
        frames: Vec::new(),
        submitted_ms: Vec::new(),
    };
    let collect = |renderer: &Renderer, run: &mut ProfileRun| {
        let seen = run.frames.last().map(|f| f.frame as i64).unwrap_or(-1);
        run.frames.extend(
            renderer
                .timings()
                .iter()
                .filter(|f| f.frame as i64 > seen)
                .cloned(),
        );
    };
    for i in 0..frames.max(1) {
        let moving = match motion {
            Motion::Drag => true,
            Motion::Still => false,
            Motion::Stop => Some(i) < stop_frame(motion, frames),
        };
        if let (true, Some(p0)) = (moving, &start_pose) {
            let (_, radius) = p0.sphere();
            let a = std::f64::consts::TAU * i as f64 / 60.0;
            let mut p = p0.clone();
            p.pose.position += 0.25 * radius * DVec3::new(a.cos() - 1.0, 0.0, a.sin());
            view.set_placed(0, p);
        }
        renderer.begin_frame()?;
        collect(&renderer, &mut run);
        let mut graph = FrameGraph::new();
        let hdr = view.build(&mut graph, width, height, 0.0)?;
        graph.mark_output_image(hdr);
        run.submitted_ms.push(began.elapsed().as_secs_f64() * 1e3);
        renderer.submit(graph, &SubmitSync::none())?;
    }
    renderer.finish()?;
    collect(&renderer, &mut run);
    if let Some(p0) = start_pose {
        view.set_placed(0, p0);
    }
    ctx.check_validation()?;
    Ok(run)
}

/// The wall-clock frame times of a run whose frames were submitted at
/// `submitted_ms` with `in_flight` frames in flight: the intervals between
/// consecutive submissions from the first that had to wait for an
/// earlier frame to finish on. Before that the renderer's slots are free,
/// so an interval is only the time to build a frame (a 2-frame run once
/// read 986 fps where the frame took 80 ms); a run too short to fill them
/// has none.
pub fn paced_intervals(submitted_ms: &[f64], in_flight: usize) -> Vec<f64> {
    submitted_ms
        .windows(2)
        .enumerate()
        .filter(|(i, _)| i + 1 >= in_flight)
        .map(|(_, w)| w[1] - w[0])
        .collect()
}

/// Runs `profile`.
pub fn run(ctx: &Arc<Context>, args: &ProfileArgs) -> anyhow::Result<()> {
    check_output("--json", &args.json, &["json"])?;
    check_output("--trace", &args.trace, &["json"])?;
    check_frame_size(ctx.info(), args.width, args.height)?;
    let mut scene = load_scene(&args.scene)?;
    if let Some(file) = &args.environment {
        let light = load_environment_file(file)?;
        scene.object_environment = Some(ObjectEnvironment::new(file.clone(), light));
    }
    if args.no_shadows {
        scene.shadows.self_shadow = false;
        scene.shadows.cast = false;
    }
    let mut knobs = scene.march;
    knobs.samples_per_ray = args.samples_per_ray.unwrap_or(knobs.samples_per_ray);
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
    view.frame.set_viewer_pacing(ctx, args.viewer);
    let run = profile_view(
        ctx,
        &mut view,
        args.width,
        args.height,
        args.frames,
        args.motion,
    )?;
    if let Some(stop) = stop_frame(args.motion, args.frames) {
        println!(
            "the object stopped at frame {stop}; the SG fit ran in {} frames after that",
            settling_frames(&run.frames, stop)
        );
    }
    let wall = paced_intervals(&run.submitted_ms, DEFAULT_FRAMES_IN_FLIGHT);
    let table = summarise(&run.frames, &wall);
    let device = format!("{} ({:?})", ctx.info().name, ctx.info().kind);
    print!(
        "{}",
        table.format(&format!(
            "Table 1: {} at {}x{}, {} frames ({:?} object), on {device}",
            args.scene.display(),
            args.width,
            args.height,
            run.frames.len(),
            args.motion
        ))
    );
    let per_frame: Vec<_> = run
        .frames
        .iter()
        .map(|f| {
            json!({
                "frame": f.frame,
                "gpu_total_ms": f.gpu_total_ms,
                "passes": f.passes.iter().map(|p| json!({
                    "name": p.name, "start_ms": p.start_ms, "gpu_ms": p.gpu_ms, "cpu_ms": p.cpu_ms,
                })).collect::<Vec<_>>(),
                "skipped": f.skipped.iter().map(|s| json!({"name": s.name, "reason": s.reason})).collect::<Vec<_>>(),
                "culled": f.culled,
            })
        })
        .collect();
    let report = json!({
        "scene": args.scene.display().to_string(),
        "device": device,
        "width": args.width,
        "height": args.height,
        "motion": format!("{:?}", args.motion).to_lowercase(),
        "table": table,
        "frames": per_frame,
    });
    let mut outputs = Outputs::new();
    outputs.json(&args.json, &report)?;
    let trace = chrome_trace(&run.frames, &run.submitted_ms, &device);
    outputs.json(&args.trace, &trace)?;
    outputs.commit(Some(ctx))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use inlay_engine::timing::PassTiming;

    /// With two frames in flight, the third submission is the first that
    /// waits: the interval before it and those after count, the first
    /// does not; a two-frame run has no paced interval.
    #[test]
    fn wall_time_counts_only_paced_submissions() {
        let submitted = [0.0, 1.0, 81.0, 161.0, 242.0];
        assert_eq!(paced_intervals(&submitted, 2), vec![80.0, 80.0, 81.0]);
        assert_eq!(paced_intervals(&submitted, 1), vec![1.0, 80.0, 80.0, 81.0]);
        assert!(paced_intervals(&submitted[..2], 2).is_empty());
        assert!(paced_intervals(&[], 2).is_empty());
    }

    /// `stop` moves for half the frames; the frames after that which ran
    /// the fit are counted, and only those.
    #[test]
    fn settling_counts_the_fits_after_the_stop() {
        assert_eq!(stop_frame(Motion::Stop, 12), Some(6));
        assert_eq!(stop_frame(Motion::Drag, 12), None);
        assert_eq!(stop_frame(Motion::Still, 12), None);
        let frame = |fit: bool| FrameTimings {
            passes: ["nerf-march", if fit { "sg-fit" } else { "composite" }]
                .map(|name| PassTiming {
                    name: name.into(),
                    start_ms: 0.0,
                    gpu_ms: 1.0,
                    cpu_ms: 0.0,
                })
                .to_vec(),
            ..Default::default()
        };
        let run: Vec<FrameTimings> = [true, true, true, true, false, false].map(frame).to_vec();
        assert_eq!(settling_frames(&run, 2), 2);
        assert_eq!(settling_frames(&run, 5), 0);
    }
}
