//! The viewer's overlay lines: frame rate, preset and camera mode, the
//! effects, the selected object's material, each Table 1 module's GPU time
//! (or why it was skipped) over the recent frames, and the key help.

use crate::insertion_view::Effects;
use crate::table1::{module_ms, modules};
use crate::timings_table::quantile;
use crate::window_app::HudStats;
use inlay_passes::frame::effect_switches;
use inlay_passes::object::PlacedObject;

/// How much the overlay shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Overlay {
    /// Frame rate, settings, per-module GPU times (and help when asked).
    Full,
    /// One line: frame rate, GPU frame time and preset.
    Compact,
    /// Nothing (no overlay pass runs).
    Off,
}

impl Overlay {
    /// The next mode (the `O` key).
    pub fn next(self) -> Self {
        match self {
            Overlay::Full => Overlay::Compact,
            Overlay::Compact => Overlay::Off,
            Overlay::Off => Overlay::Full,
        }
    }
}

/// What the overlay describes besides the frame statistics.
pub struct HudState<'a> {
    /// The quality preset's name.
    pub preset: &'a str,
    /// Fly (true) or orbit camera.
    pub fly: bool,
    /// The effects drawn.
    pub effects: Effects,
    /// The selected object, if any.
    pub selected: Option<PlacedObject>,
    /// Help lines to append (empty: help hidden).
    pub help: Vec<String>,
}

fn on_off(b: bool) -> &'static str {
    if b {
        "on"
    } else {
        "off"
    }
}

/// The overlay's lines.
pub fn hud_lines(stats: &HudStats<'_>, state: &HudState<'_>, mode: Overlay) -> Vec<String> {
    let (w, h) = stats.extent;
    let totals: Vec<f64> = stats.recent.iter().map(|f| f.gpu_total_ms).collect();
    match mode {
        Overlay::Off => return Vec::new(),
        Overlay::Compact => {
            return vec![format!(
                "{:.1} fps  GPU {:.1} ms  {} (H help, O overlay)",
                stats.fps,
                quantile(&totals, 0.5),
                state.preset
            )]
        }
        Overlay::Full => {}
    }
    let mut lines = vec![
        format!("{:.1} fps  {w}x{h}  {}", stats.fps, stats.device),
        format!(
            "preset {} (F5)  camera {} (Tab)  H help",
            state.preset,
            if state.fly { "fly" } else { "orbit" }
        ),
        effect_switches()
            .iter()
            .map(|s| format!("{} {}", s.name, on_off(state.effects.on(s.effect))))
            .collect::<Vec<_>>()
            .join(" "),
    ];
    if let Some(p) = &state.selected {
        let m = p.material_of(0);
        let c = m.base_colour;
        lines.push(format!(
            "{}: rough {:.2} metal {:.2} colour {:.2} {:.2} {:.2}",
            p.name, m.roughness, m.metallic, c.x, c.y, c.z
        ));
    }
    lines.push("GPU ms (median of recent frames):".into());
    for (module, passes) in modules() {
        let times: Vec<f64> = stats
            .recent
            .iter()
            .filter_map(|f| module_ms(f, &passes))
            .collect();
        let skipped = stats.recent.last().and_then(|f| {
            f.skipped
                .iter()
                .find(|s| passes.contains(&s.name.as_str()))
                .map(|s| s.reason.clone())
        });
        lines.push(match (skipped, times.is_empty()) {
            (Some(why), _) => format!("  {module:<15} skipped: {why}"),
            (None, true) => format!("  {module:<15} -"),
            (None, false) => format!("  {module:<15} {:8.2}", quantile(&times, 0.5)),
        });
    }
    if !totals.is_empty() {
        lines.push(format!("  {:<15} {:8.2}", "frame", quantile(&totals, 0.5)));
    }
    lines.extend(state.help.iter().cloned());
    lines
}
