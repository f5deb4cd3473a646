//! Printing per-pass timings as a table: median and p95 over frames.

use inlay_engine::timing::FrameTimings;

/// The `q` quantile (0..=1) of `values` (nearest rank); 0 for none.
pub fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// A table of each pass's GPU and CPU time (median and p95; passes of one
/// name summed within a frame) over the frames it ran in (passes that ran
/// in only some frames, such as the probe and the SG fit, say in how
/// many), with the culled passes and the frame total.
pub fn format_table(frames: &[FrameTimings], device: &str) -> String {
    let mut out = String::new();
    let Some(last) = frames.last() else {
        return "no completed frames\n".into();
    };
    out.push_str(&format!(
        "per-pass timings over {} frame(s) on {device}\n",
        frames.len()
    ));
    out.push_str(&format!(
        "{:<16} {:>12} {:>12} {:>12}\n",
        "pass", "gpu ms p50", "gpu ms p95", "cpu ms p50"
    ));
    // Every pass that ran in any frame, in first-seen order.
    let mut names: Vec<&str> = Vec::new();
    for f in frames {
        for p in &f.passes {
            if !names.contains(&p.name.as_str()) {
                names.push(&p.name);
            }
        }
    }
    // A name's time in a frame is the sum over its passes (one per object,
    // or a pass's stages).
    let per_frame = |name: &str, time: fn(&inlay_engine::timing::PassTiming) -> f64| -> Vec<f64> {
        frames
            .iter()
            .filter_map(|f| {
                let mut of = f.passes.iter().filter(|p| p.name == name).peekable();
                of.peek().is_some().then(|| of.map(time).sum())
            })
            .collect()
    };
    for name in names {
        let gpu = per_frame(name, |p| p.gpu_ms);
        let cpu = per_frame(name, |p| p.cpu_ms);
        let ran = if gpu.len() < frames.len() {
            format!("  (ran in {} of {} frames)", gpu.len(), frames.len())
        } else {
            String::new()
        };
        out.push_str(&format!(
            "{:<16} {:>12.3} {:>12.3} {:>12.3}{ran}\n",
            name,
            quantile(&gpu, 0.5),
            quantile(&gpu, 0.95),
            quantile(&cpu, 0.5)
        ));
    }
    let totals: Vec<f64> = frames.iter().map(|f| f.gpu_total_ms).collect();
    out.push_str(&format!(
        "{:<16} {:>12.3} {:>12.3}\n",
        "frame (gpu)",
        quantile(&totals, 0.5),
        quantile(&totals, 0.95)
    ));
    if !last.culled.is_empty() {
        out.push_str(&format!(
            "culled (nothing consumes them): {}\n",
            last.culled.join(", ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_use_nearest_rank() {
        let v = [5.0, 1.0, 3.0, 2.0, 4.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert_eq!(quantile(&v, 0.95), 5.0);
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }

    /// Passes of one name in a frame (one per object, or a pass's stages)
    /// count together; a pass that ran in some frames says so.
    #[test]
    fn passes_of_one_name_are_summed_within_a_frame() {
        let pass = |name: &str, gpu_ms: f64| inlay_engine::timing::PassTiming {
            name: name.into(),
            start_ms: 0.0,
            gpu_ms,
            cpu_ms: 0.5,
        };
        let frames: Vec<FrameTimings> = (0..3)
            .map(|i| FrameTimings {
                frame: i,
                passes: if i == 1 {
                    vec![pass("march", 10.0), pass("cast", 2.0), pass("cast", 7.0)]
                } else {
                    vec![pass("march", 10.0), pass("cast", 3.0), pass("cast", 6.0)]
                },
                gpu_total_ms: 20.0,
                ..Default::default()
            })
            .chain(std::iter::once(FrameTimings {
                frame: 3,
                passes: vec![pass("march", 10.0), pass("fit", 4.0)],
                gpu_total_ms: 14.0,
                ..Default::default()
            }))
            .collect();
        let table = format_table(&frames, "test device");
        let row = |name: &str| {
            table
                .lines()
                .find(|l| l.split_whitespace().next() == Some(name))
                .unwrap_or_else(|| panic!("no {name} row in\n{table}"))
                .to_string()
        };
        let cast: Vec<String> = row("cast").split_whitespace().map(String::from).collect();
        assert_eq!(cast[1..4], ["9.000", "9.000", "1.000"], "{table}");
        assert!(row("cast").contains("(ran in 3 of 4 frames)"), "{table}");
        assert!(row("fit").contains("(ran in 1 of 4 frames)"), "{table}");
    }
}
