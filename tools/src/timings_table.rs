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

/// A table of each pass's GPU and CPU time (median and p95) over the
/// frames it ran in (passes that ran in only some frames, such as the
/// probe and the SG fit, say in how many), with the culled passes and the
/// frame total.
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
    for name in names {
        let gpu: Vec<f64> = frames
            .iter()
            .filter_map(|f| f.passes.iter().find(|p| p.name == name))
            .map(|p| p.gpu_ms)
            .collect();
        let cpu: Vec<f64> = frames
            .iter()
            .filter_map(|f| f.passes.iter().find(|p| p.name == name))
            .map(|p| p.cpu_ms)
            .collect();
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
}
