//! The paper's Table 1 from per-pass timestamps: each module (NeRF
//! rendering, Lighting, SG updating, Rendering, Compositing, Shadow) is the
//! sum of its passes' GPU times in a frame; its median and p95 are taken
//! over the frames it ran in, the first frame's SG update (a cold fit) is
//! reported apart, and a module that never ran says why it was skipped.

use inlay_engine::timing::FrameTimings;
use serde::Serialize;

use inlay_passes::frame::Table1Module;

use crate::timings_table::quantile;

/// The modules of Table 1 and the passes each is made of, as the frame's
/// passes declare them.
pub use inlay_passes::frame::table1 as modules;

/// One module's row.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModuleRow {
    /// The module's name as Table 1 gives it.
    pub module: String,
    /// Its passes.
    pub passes: Vec<String>,
    /// Median GPU milliseconds over the frames it ran in (after the first,
    /// for SG updating).
    pub median_ms: Option<f64>,
    /// 95th percentile of the same.
    pub p95_ms: Option<f64>,
    /// The first frame's time (SG updating: the cold fit).
    pub first_frame_ms: Option<f64>,
    /// In how many of the frames it ran.
    pub ran_in: usize,
    /// Why it did not run, where it was skipped (the most frequent reason).
    pub skipped_because: Option<String>,
    /// Its median over NeRF rendering's median (how Table 1 reads: the
    /// paper's SG updating is 0.18 × its NeRF rendering).
    pub march_ratio: Option<f64>,
}

/// The whole table.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Table1 {
    /// Frames summarised.
    pub frames: usize,
    /// One row per module, in Table 1's order.
    pub modules: Vec<ModuleRow>,
    /// Median GPU milliseconds from a frame's first pass to its last.
    pub frame_median_ms: f64,
    /// 95th percentile of the same.
    pub frame_p95_ms: f64,
    /// Frames per second from the median GPU frame time.
    pub gpu_fps: f64,
    /// Median wall-clock milliseconds between frame submissions (what the
    /// user sees, CPU work and waiting included), when measured.
    pub wall_median_ms: Option<f64>,
    /// Frames per second from the median wall time.
    pub wall_fps: Option<f64>,
    /// Median, over the frames after the first (whose cold fit stands
    /// apart), of everything but NeRF rendering: what inserting the
    /// objects costs a frame.
    pub insertion_median_ms: Option<f64>,
    /// That over NeRF rendering's median (paper: 15 ms / 40 ms = 0.38).
    pub insertion_ratio: Option<f64>,
}

/// A module's GPU time in `frame`, if any of its passes ran.
pub fn module_ms(frame: &FrameTimings, passes: &[&str]) -> Option<f64> {
    let times: Vec<f64> = frame
        .passes
        .iter()
        .filter(|p| passes.contains(&p.name.as_str()))
        .map(|p| p.gpu_ms)
        .collect();
    (!times.is_empty()).then(|| times.iter().sum())
}

/// The module a pass belongs to, if it is one of Table 1's.
pub fn module_of(pass: &str) -> Option<&'static str> {
    modules()
        .into_iter()
        .find(|(_, passes)| passes.contains(&pass))
        .map(|(m, _)| m)
}

/// Summarises `frames` (oldest first, the first frame being the run's
/// first) with the wall-clock frame times `wall_ms` (may be empty).
pub fn summarise(frames: &[FrameTimings], wall_ms: &[f64]) -> Table1 {
    let modules = modules()
        .into_iter()
        .map(|(module, passes)| {
            let per_frame: Vec<Option<f64>> =
                frames.iter().map(|f| module_ms(f, &passes)).collect();
            let first_is_apart = module == Table1Module::SgUpdating.name();
            let first_frame_ms = per_frame.first().copied().flatten();
            let counted: Vec<f64> = per_frame
                .iter()
                .enumerate()
                .filter(|(i, _)| !(first_is_apart && *i == 0))
                .filter_map(|(_, t)| *t)
                .collect();
            let mut reasons: Vec<(String, usize)> = Vec::new();
            for f in frames {
                for s in f
                    .skipped
                    .iter()
                    .filter(|s| passes.contains(&s.name.as_str()))
                {
                    match reasons.iter_mut().find(|(r, _)| *r == s.reason) {
                        Some((_, n)) => *n += 1,
                        None => reasons.push((s.reason.clone(), 1)),
                    }
                }
            }
            reasons.sort_by_key(|r| std::cmp::Reverse(r.1));
            ModuleRow {
                module: module.to_string(),
                passes: passes.iter().map(|p| p.to_string()).collect(),
                median_ms: (!counted.is_empty()).then(|| quantile(&counted, 0.5)),
                p95_ms: (!counted.is_empty()).then(|| quantile(&counted, 0.95)),
                first_frame_ms,
                ran_in: per_frame.iter().filter(|t| t.is_some()).count(),
                skipped_because: reasons.first().map(|(r, _)| r.clone()),
                march_ratio: None,
            }
        })
        .collect::<Vec<ModuleRow>>();
    let march_name = Table1Module::NerfRendering.name();
    let march = modules
        .iter()
        .find(|r: &&ModuleRow| r.module == march_name)
        .and_then(|r| r.median_ms)
        .filter(|&m| m > 0.0);
    let modules: Vec<ModuleRow> = modules
        .into_iter()
        .map(|mut r| {
            r.march_ratio = r.median_ms.zip(march).map(|(m, n)| m / n);
            r
        })
        .collect();
    let insertion: Vec<f64> = frames
        .iter()
        .skip(1)
        .map(|f| {
            crate::table1::modules()
                .into_iter()
                .filter(|(m, _)| *m != march_name)
                .filter_map(|(_, passes)| module_ms(f, &passes))
                .sum()
        })
        .collect();
    let insertion_median_ms = (!insertion.is_empty()).then(|| quantile(&insertion, 0.5));
    let totals: Vec<f64> = frames.iter().map(|f| f.gpu_total_ms).collect();
    let frame_median_ms = quantile(&totals, 0.5);
    let wall_median = (!wall_ms.is_empty()).then(|| quantile(wall_ms, 0.5));
    Table1 {
        frames: frames.len(),
        modules,
        frame_median_ms,
        frame_p95_ms: quantile(&totals, 0.95),
        gpu_fps: if frame_median_ms > 0.0 {
            1000.0 / frame_median_ms
        } else {
            0.0
        },
        wall_median_ms: wall_median,
        wall_fps: wall_median.filter(|&m| m > 0.0).map(|m| 1000.0 / m),
        insertion_median_ms,
        insertion_ratio: insertion_median_ms.zip(march).map(|(i, m)| i / m),
    }
}

impl Table1 {
    /// The table as text, in Table 1's layout with median and p95 columns.
    pub fn format(&self, title: &str) -> String {
        let mut out = format!("{title}\n");
        out.push_str(&format!(
            "{:<16} {:>10} {:>10} {:>20} {:>8}  {}\n",
            "module", "ms p50", "ms p95", "first frame (× march)", "× march", "ran"
        ));
        let march = self
            .modules
            .iter()
            .find(|r| r.module == Table1Module::NerfRendering.name())
            .and_then(|r| r.median_ms)
            .filter(|&m| m > 0.0);
        let ratio = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
        let ms = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
        for r in &self.modules {
            let ran = if r.ran_in == self.frames {
                "every frame".to_string()
            } else if r.ran_in == 0 {
                format!(
                    "skipped ({})",
                    r.skipped_because.as_deref().unwrap_or("not in this scene")
                )
            } else {
                format!(
                    "{} of {} frames{}",
                    r.ran_in,
                    self.frames,
                    r.skipped_because
                        .as_ref()
                        .map_or(String::new(), |why| format!("; otherwise skipped ({why})"))
                )
            };
            let first = if r.module == Table1Module::SgUpdating.name() {
                // The cold fit, and its ratio to the march.
                let cold = r.first_frame_ms.zip(march).map(|(f, m)| f / m);
                format!("{} ({})", ms(r.first_frame_ms), ratio(cold))
            } else {
                String::new()
            };
            out.push_str(&format!(
                "{:<16} {:>10} {:>10} {:>20} {:>8}  {ran}\n",
                r.module,
                ms(r.median_ms),
                ms(r.p95_ms),
                first,
                ratio(r.march_ratio)
            ));
        }
        if let Some(i) = self.insertion_median_ms {
            out.push_str(&format!(
                "{:<16} {:>10.3} {:>10} {:>20} {:>8}  everything but NeRF rendering, frames after the first (paper: 0.38)\n",
                "insertion",
                i,
                "",
                "",
                ratio(self.insertion_ratio)
            ));
        }
        out.push_str(&format!(
            "{:<16} {:>10.3} {:>10.3} {:>29}  {:.1} fps (GPU time)\n",
            "frame", self.frame_median_ms, self.frame_p95_ms, "", self.gpu_fps
        ));
        if let (Some(m), Some(fps)) = (self.wall_median_ms, self.wall_fps) {
            out.push_str(&format!(
                "{:<16} {:>10.3} {:>10} {:>29}  {fps:.1} fps (wall clock)\n",
                "frame (wall)", m, "", ""
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use inlay_engine::graph::SkippedPass;
    use inlay_engine::timing::PassTiming;

    fn pass(name: &str, gpu_ms: f64) -> PassTiming {
        PassTiming {
            name: name.into(),
            start_ms: 0.0,
            gpu_ms,
            cpu_ms: 0.0,
        }
    }

    #[test]
    fn modules_sum_their_passes_and_the_first_fit_stands_apart() {
        let mut frames = Vec::new();
        for i in 0..5 {
            let mut passes = vec![
                pass("nerf-march", 10.0 + i as f64),
                pass("object-gbuffer", 1.0),
                pass("object-shade", 2.0),
                pass("composite", 0.5),
            ];
            let mut skipped = Vec::new();
            if i == 0 || i == 3 {
                passes.push(pass("probe-trace", 4.0));
                passes.push(pass("sg-fit", if i == 0 { 80.0 } else { 7.0 }));
            } else {
                skipped.push(SkippedPass {
                    name: "sg-fit".into(),
                    reason: "unchanged".into(),
                });
            }
            skipped.push(SkippedPass {
                name: "cast-shadow".into(),
                reason: "cast shadows off".into(),
            });
            frames.push(FrameTimings {
                frame: i,
                passes,
                culled: vec![],
                skipped,
                gpu_total_ms: 20.0,
            });
        }
        let t = summarise(&frames, &[50.0, 50.0, 40.0]);
        let row = |m: &str| t.modules.iter().find(|r| r.module == m).unwrap().clone();
        assert_eq!(row("NeRF rendering").median_ms, Some(12.0));
        assert_eq!(row("NeRF rendering").p95_ms, Some(14.0));
        assert_eq!(row("Rendering").median_ms, Some(3.0));
        let sg = row("SG updating");
        assert_eq!(
            (sg.first_frame_ms, sg.median_ms, sg.ran_in),
            (Some(80.0), Some(7.0), 2)
        );
        assert_eq!(sg.skipped_because.as_deref(), Some("unchanged"));
        let shadow = row("Shadow");
        assert_eq!((shadow.ran_in, shadow.median_ms), (0, None));
        assert_eq!(shadow.skipped_because.as_deref(), Some("cast shadows off"));
        assert_eq!(t.gpu_fps, 50.0);
        assert_eq!(t.wall_fps, Some(20.0));
        let text = t.format("title");
        assert!(text.contains("skipped (cast shadows off)"), "{text}");
        assert!(
            text.contains("2 of 5 frames; otherwise skipped (unchanged)"),
            "{text}"
        );
        assert!(text.contains("80.000"), "{text}");
        // Ratios to the march (median 12 ms): Rendering 3 ms; the cold fit
        // 80 ms; insertion per frame after the first 3.5, 3.5, 14.5, 3.5.
        assert_eq!(row("Rendering").march_ratio, Some(0.25));
        assert_eq!(row("NeRF rendering").march_ratio, Some(1.0));
        assert_eq!(t.insertion_median_ms, Some(3.5));
        assert_eq!(t.insertion_ratio, Some(3.5 / 12.0));
        assert!(text.contains("80.000 (6.667)"), "{text}");
        assert!(
            text.contains("insertion") && text.contains("0.292"),
            "{text}"
        );
    }
}
