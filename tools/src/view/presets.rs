//! Quality presets for the viewer: each sets the per-frame knobs that cost
//! the most (samples per ray, probe resolution, SG lobes, LM iterations),
//! trading accuracy for speed. `Scene` keeps what the scene file says.

use clap::ValueEnum;
use inlay_passes::scene::{CastScale, Scene, DEFAULT_CAST_REFINE};

/// A quality preset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Preset {
    /// 128 samples per ray, a 16×16 probe, 8 lobes, 20 cold and 2 warm
    /// LM iterations, the cast shadow at half resolution (or coarser, as
    /// the scene's scale is) without refinement, the object lit by its
    /// lobes alone (no field light at its surface): interactive on a CPU
    /// device at small sizes.
    Fast,
    /// 256 samples per ray, a 32×32 probe, 16 lobes, 40 cold and 4 warm
    /// iterations, the cast shadow at half resolution (or coarser, as the
    /// scene's scale is), the field's light at the object's surface from
    /// 12 × 12 rays a tile.
    Balanced,
    /// The scene file's knobs (the paper's defaults unless it says otherwise).
    Scene,
}

impl Preset {
    /// All presets, in the order the viewer cycles through them.
    pub const ALL: [Preset; 3] = [Preset::Fast, Preset::Balanced, Preset::Scene];

    /// The preset's name.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Fast => "fast",
            Preset::Balanced => "balanced",
            Preset::Scene => "scene",
        }
    }

    /// The next preset in [`Self::ALL`].
    pub fn next(self) -> Preset {
        let i = Self::ALL.iter().position(|&p| p == self).unwrap_or(0);
        Self::ALL[(i + 1) % Self::ALL.len()]
    }

    /// `authored` with this preset's knobs (never more costly than the
    /// scene file asks for).
    pub fn apply(self, authored: &Scene) -> Scene {
        let mut s = authored.clone();
        let (samples, probe, lobes, cold, warm, cast_scale, cast_refine, field_light) = match self {
            Preset::Fast => (128, 16, 8, 20, 2, 2, 1.0, 0),
            Preset::Balanced => (256, 32, 16, 40, 4, 2, DEFAULT_CAST_REFINE, 12),
            Preset::Scene => return s,
        };
        s.march.samples_per_ray = s.march.samples_per_ray.min(samples);
        s.lighting.probe.resolution = s.lighting.probe.resolution.min(probe);
        s.lighting.fit.lobes = s.lighting.fit.lobes.min(lobes);
        s.lighting.fit.cold_iterations = s.lighting.fit.cold_iterations.min(cold);
        s.lighting.fit.warm_iterations = s.lighting.fit.warm_iterations.min(warm);
        // The automatic scale is never under 2, the presets' floor.
        if let CastScale::Fixed(f) = s.shadows.cast_scale {
            s.shadows.cast_scale = CastScale::Fixed(f.max(cast_scale));
        }
        s.shadows.cast_refine = s.shadows.cast_refine.max(cast_refine);
        s.shading.field_light = s.shading.field_light.min(field_light);
        s
    }
}
