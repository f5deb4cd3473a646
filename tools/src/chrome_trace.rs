//! Frame timings as a Chrome trace (the JSON "Trace Event Format" that
//! chrome://tracing and ui.perfetto.dev open): one complete event per pass
//! on a GPU track, named by pass with its Table 1 module as category, one
//! event per frame on a frame track, and an instant event per skipped pass
//! carrying the reason.

use inlay_engine::timing::FrameTimings;
use serde_json::{json, Value};

use crate::table1::module_of;

/// The trace of `frames`, frame `i` placed at `origins_ms[i]` (wall-clock
/// milliseconds after the run began, when the frame was submitted; frames
/// without one follow the previous frame back to back).
pub fn chrome_trace(frames: &[FrameTimings], origins_ms: &[f64], device: &str) -> Value {
    let mut events = vec![
        json!({"ph": "M", "name": "process_name", "pid": 1, "args": {"name": format!("inlay on {device}")}}),
        json!({"ph": "M", "name": "thread_name", "pid": 1, "tid": 1, "args": {"name": "frames"}}),
        json!({"ph": "M", "name": "thread_name", "pid": 1, "tid": 2, "args": {"name": "GPU passes"}}),
    ];
    let mut next_free = 0.0f64;
    for (i, f) in frames.iter().enumerate() {
        let origin = origins_ms
            .get(i)
            .copied()
            .unwrap_or(next_free)
            .max(next_free);
        next_free = origin + f.gpu_total_ms;
        let us = |ms: f64| (ms * 1000.0 * 1000.0).round() / 1000.0;
        events.push(json!({
            "ph": "X", "name": format!("frame {}", f.frame), "cat": "frame",
            "pid": 1, "tid": 1, "ts": us(origin), "dur": us(f.gpu_total_ms),
        }));
        for p in &f.passes {
            events.push(json!({
                "ph": "X", "name": p.name, "cat": module_of(&p.name).unwrap_or("other"),
                "pid": 1, "tid": 2, "ts": us(origin + p.start_ms), "dur": us(p.gpu_ms),
                "args": {"frame": f.frame, "cpu_record_ms": p.cpu_ms},
            }));
        }
        for s in &f.skipped {
            events.push(json!({
                "ph": "i", "s": "t", "name": format!("{} skipped", s.name), "cat": "skipped",
                "pid": 1, "tid": 2, "ts": us(origin),
                "args": {"frame": f.frame, "reason": s.reason},
            }));
        }
    }
    json!({"traceEvents": events, "displayTimeUnit": "ms"})
}

#[cfg(test)]
mod tests {
    use super::*;
    use inlay_engine::graph::SkippedPass;
    use inlay_engine::timing::PassTiming;

    #[test]
    fn passes_become_complete_events_inside_their_frame() {
        let frame = |n: u64| FrameTimings {
            frame: n,
            passes: vec![
                PassTiming {
                    name: "nerf-march".into(),
                    start_ms: 0.0,
                    gpu_ms: 2.0,
                    cpu_ms: 0.1,
                },
                PassTiming {
                    name: "composite".into(),
                    start_ms: 2.5,
                    gpu_ms: 0.5,
                    cpu_ms: 0.1,
                },
            ],
            culled: vec![],
            skipped: vec![SkippedPass {
                name: "sg-fit".into(),
                reason: "object and lighting unchanged".into(),
            }],
            gpu_total_ms: 3.0,
        };
        // The second frame's origin overlaps the first: it is pushed back.
        let t = chrome_trace(&[frame(0), frame(1)], &[10.0, 11.0], "test");
        let ev = t["traceEvents"].as_array().unwrap();
        let composite: Vec<&Value> = ev.iter().filter(|e| e["name"] == "composite").collect();
        assert_eq!(composite.len(), 2);
        assert_eq!(composite[0]["ts"], 12500.0);
        assert_eq!(composite[1]["ts"], 15500.0);
        assert_eq!(composite[0]["cat"], "Compositing");
        assert_eq!(composite[0]["dur"], 500.0);
        let skipped = ev.iter().find(|e| e["name"] == "sg-fit skipped").unwrap();
        assert_eq!(skipped["args"]["reason"], "object and lighting unchanged");
    }
}
