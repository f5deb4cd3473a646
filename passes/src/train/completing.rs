//! A training in two runs where the photographs leave surfaces open: the
//! first on the photographs alone; then the planes through the surfaces
//! it places complete those it leaves open ([`super::planes`]), and the
//! second trains from the start with the completed depths held as depth
//! maps are.

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::Context;

use super::pixels::training_frames;
use super::planes::{complete_plain_surfaces, Completion};
use super::trainer::{train, view_march, TrainControl, TrainProgress, Trained};
use super::TrainKnobs;
use crate::dataset::Dataset;

/// Which run a progress report is of, with the report.
#[derive(Debug, Clone, Copy)]
pub struct RunProgress {
    /// 0 for the first run (or the only one), 1 for the second.
    pub run: u32,
    /// The runs the training makes: 2 where it completes open surfaces.
    pub runs: u32,
    /// The run's own progress.
    pub progress: TrainProgress,
}

/// A training's result ([`train_completing`]).
#[derive(Debug, Clone)]
pub struct CompletedTraining {
    /// The field the training ends with and its held-out views.
    pub trained: Trained,
    /// What the planes completed, where a second run trained on it.
    pub completion: Option<Completion>,
    /// Why no second run trained, where none did.
    pub single: Option<&'static str>,
}

/// Whether a training of `dataset` with `knobs`, holding out `hold_out`
/// poses, from the start or from a field (`resumed`), completes open
/// surfaces (two runs), or the reason it does not.
pub fn completion_runs(
    dataset: &Dataset,
    knobs: &TrainKnobs,
    hold_out: u32,
    resumed: bool,
) -> Result<(), &'static str> {
    if !knobs.planes {
        return Err("--planes off");
    }
    if resumed {
        return Err("a resumed field trains on as it is");
    }
    if knobs.depth_weight <= 0.0 {
        return Err("--depth-weight 0 holds no depth");
    }
    let frames = training_frames(dataset, hold_out);
    if frames
        .iter()
        .all(|&f| !dataset.frames[f as usize].depth.is_empty())
    {
        return Err("every training frame records its depth");
    }
    Ok(())
}

/// Trains a field on `dataset` as [`train`] does; where
/// [`completion_runs`] allows, that is a first run on the photographs
/// alone, the open surfaces of its field completed by planes
/// ([`complete_plain_surfaces`], reported to `completed`), and a second
/// run from the start with those depths, within what is left of
/// `control`'s time budget. Where either run is stopped early (Ctrl-C,
/// the budget), or the planes complete nothing, the first run's field is
/// the result, its held-out views scored.
#[allow(clippy::too_many_arguments)]
pub fn train_completing(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    dataset: &Dataset,
    knobs: &TrainKnobs,
    hold_out: u32,
    background: DVec3,
    control: &TrainControl,
    progress: &dyn Fn(&RunProgress),
    completed: &dyn Fn(&Completion),
) -> anyhow::Result<CompletedTraining> {
    // Run `run` of `runs` under `control`, its progress reported as such.
    let run_of = |run: u32, runs: u32, control: &TrainControl| {
        train(
            ctx,
            lib,
            dataset,
            knobs,
            hold_out,
            background,
            control,
            &|p| {
                progress(&RunProgress {
                    run,
                    runs,
                    progress: *p,
                })
            },
        )
    };
    let single = |trained, why| CompletedTraining {
        trained,
        completion: None,
        single: Some(why),
    };
    if let Err(why) = completion_runs(dataset, knobs, hold_out, control.resume.is_some()) {
        return Ok(single(run_of(0, 1, control)?, why));
    }
    let started = Instant::now();
    let first_control = TrainControl {
        score_held_out: false,
        ..*control
    };
    let first = run_of(0, 2, &first_control)?;
    let rescored = |first: Trained| {
        let held = super::pixels::held_out_poses(dataset, hold_out);
        let behind = first
            .sky
            .as_ref()
            .map_or(super::Behind::Colour(background), super::Behind::Sky);
        let held_out = super::trainer::score_held_out(
            dataset,
            &held,
            &first.field,
            knobs,
            behind,
            control.seen_lights,
        );
        Trained { held_out, ..first }
    };
    if first.steps < knobs.iterations || (control.stop)() {
        return Ok(single(rescored(first), "the first run was stopped"));
    }
    let frames = training_frames(dataset, hold_out);
    let completion = complete_plain_surfaces(
        dataset,
        &frames,
        &first.field,
        &view_march(knobs),
        knobs.seed,
    );
    completed(&completion);
    if completion.completed == 0 {
        return Ok(single(rescored(first), "the planes completed no pixel"));
    }
    let second_control = TrainControl {
        depth: Some(&completion.depth),
        budget: control.budget.map(|b| b.saturating_sub(started.elapsed())),
        ..*control
    };
    let trained = run_of(1, 2, &second_control)?;
    // A second run cut short is a field part way to its end: the first,
    // which ran its course, is the better one.
    if trained.steps < knobs.iterations {
        return Ok(single(
            rescored(first),
            "the second run was stopped: the first run's field",
        ));
    }
    Ok(CompletedTraining {
        trained,
        completion: Some(completion),
        single: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::pixels::PixelCounts;
    use crate::dataset::{BoundsSource, Dialect};
    use crate::geometry::Aabb;
    use crate::train::geometry::tests::frame;

    /// Two runs only where they can complete something: planes on, from
    /// the start, a depth weight above 0, and some training frame without
    /// a depth map (a held-out frame's map does not count).
    #[test]
    fn two_runs_only_where_a_training_frame_has_no_depth_map() {
        let mut recorded = frame();
        recorded.depth = vec![1.0; 32 * 32];
        let dataset = |frames| Dataset {
            file: "transforms.json".into(),
            dialect: Dialect::InstantNgp,
            frames,
            bounds: Aabb::new(glam::DVec3::splat(-1.0), glam::DVec3::splat(1.0)),
            bounds_source: BoundsSource::AabbKey,
            counts: PixelCounts::default(),
            skipped: Vec::new(),
        };
        let plain = dataset(vec![recorded.clone(), frame(), recorded.clone()]);
        let knobs = TrainKnobs::default();
        assert_eq!(completion_runs(&plain, &knobs, 0, false), Ok(()));
        assert!(completion_runs(&plain, &knobs, 0, true).is_err());
        let off = TrainKnobs {
            planes: false,
            ..knobs
        };
        assert!(completion_runs(&plain, &off, 0, false).is_err());
        let no_depth = TrainKnobs {
            depth_weight: 0.0,
            ..knobs
        };
        assert!(completion_runs(&plain, &no_depth, 0, false).is_err());
        let all = dataset(vec![recorded.clone(), recorded.clone(), recorded.clone()]);
        assert!(completion_runs(&all, &knobs, 0, false).is_err());
        // Held out, the frame without a map leaves only recorded ones.
        let held = crate::train::pixels::held_out_poses(&plain, 1);
        assert_eq!(held, vec![1], "the test holds out the plain frame");
        assert!(completion_runs(&plain, &knobs, 1, false).is_err());
    }
}
