//! Where a training step's time goes: each pass's GPU time summed over the
//! steps taken, beside the steps' wall-clock time, so a run says which
//! pass to make faster (and the cost of a knob is measured, not guessed).

use inlay_engine::timing::FrameTimings;

/// GPU milliseconds per pass over a run's steps, and their wall-clock time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepTimes {
    /// Steps counted.
    pub steps: u32,
    /// Wall-clock seconds of those steps (batch drawn, recorded, run and
    /// read back).
    pub wall_seconds: f64,
    /// (pass name, GPU milliseconds summed over the steps), in the order
    /// the passes first ran; the SH pages' Adam passes count as one.
    pub passes: Vec<(String, f64)>,
}

impl StepTimes {
    /// Adds one step: its frame's timings and its wall-clock seconds.
    pub fn add(&mut self, frame: Option<&FrameTimings>, wall_seconds: f64) {
        self.steps += 1;
        self.wall_seconds += wall_seconds;
        for p in frame.map_or(&[][..], |f| &f.passes) {
            // "train-adam-sh-3" counts with the other pages.
            let name = match p.name.rsplit_once("-sh-") {
                Some((base, _)) => format!("{base}-sh"),
                None => p.name.clone(),
            };
            match self.passes.iter_mut().find(|(n, _)| *n == name) {
                Some((_, ms)) => *ms += p.gpu_ms,
                None => self.passes.push((name, p.gpu_ms)),
            }
        }
    }

    /// Mean wall-clock milliseconds per step (0 before any step).
    pub fn wall_ms_per_step(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            1e3 * self.wall_seconds / self.steps as f64
        }
    }

    /// (pass, mean GPU milliseconds per step), largest first.
    pub fn per_step(&self) -> Vec<(String, f64)> {
        let n = self.steps.max(1) as f64;
        let mut v: Vec<(String, f64)> = self
            .passes
            .iter()
            .map(|(p, ms)| (p.clone(), ms / n))
            .collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use inlay_engine::timing::PassTiming;

    fn frame(passes: &[(&str, f64)]) -> FrameTimings {
        FrameTimings {
            passes: passes
                .iter()
                .map(|(n, ms)| PassTiming {
                    name: n.to_string(),
                    start_ms: 0.0,
                    gpu_ms: *ms,
                    cpu_ms: 0.0,
                })
                .collect(),
            ..Default::default()
        }
    }

    /// Passes sum over steps, the SH pages count as one, and the means
    /// come out largest first.
    #[test]
    fn sums_passes_over_steps() {
        let mut t = StepTimes::default();
        t.add(
            Some(&frame(&[
                ("train-rays", 10.0),
                ("train-adam-sh-0", 1.0),
                ("train-adam-sh-1", 2.0),
            ])),
            0.02,
        );
        t.add(
            Some(&frame(&[("train-rays", 30.0), ("train-adam", 4.0)])),
            0.04,
        );
        t.add(None, 0.0);
        assert_eq!(t.steps, 3);
        assert!((t.wall_ms_per_step() - 20.0).abs() < 1e-9);
        let per = t.per_step();
        assert_eq!(per[0].0, "train-rays");
        assert!((per[0].1 - 40.0 / 3.0).abs() < 1e-9);
        assert_eq!(per[1], ("train-adam".to_string(), 4.0 / 3.0));
        assert_eq!(per[2], ("train-adam-sh".to_string(), 1.0));
        assert_eq!(StepTimes::default().wall_ms_per_step(), 0.0);
    }
}
