//! The bake's quality knobs (`[bake]` in a scene file; the command line can
//! override each).

use crate::scene::spec::BakeSpec;

/// How a recipe is baked into a grid field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BakeKnobs {
    /// Nodes along the longest axis of the bounds (others in proportion).
    pub resolution: u32,
    /// Path-traced samples per node (and per reference pixel).
    pub samples: u32,
    /// Indirect scattering events after direct light (0: direct only).
    pub bounces: u32,
    /// Seed of the random sequence (the result is identical for a seed).
    pub seed: u64,
    /// Half-width of the density's smooth edge, in voxels.
    pub falloff_voxels: f64,
    /// Interior density times the voxel size (optical depth per voxel).
    pub density_scale: f64,
}

impl Default for BakeKnobs {
    fn default() -> Self {
        Self {
            resolution: 64,
            samples: 64,
            bounces: 1,
            seed: 1,
            falloff_voxels: 1.5,
            density_scale: 40.0,
        }
    }
}

impl BakeKnobs {
    /// Why the knobs cannot be used, naming the knob.
    pub fn check(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_owned(), m));
        if !(4..=512).contains(&self.resolution) {
            return bad(
                "resolution",
                format!("{} must be in 4..=512", self.resolution),
            );
        }
        if !(1..=1 << 16).contains(&self.samples) {
            return bad("samples", format!("{} must be in 1..=65536", self.samples));
        }
        if self.bounces > 16 {
            return bad("bounces", format!("{} must be at most 16", self.bounces));
        }
        if !(self.falloff_voxels.is_finite() && (0.25..=8.0).contains(&self.falloff_voxels)) {
            return bad(
                "falloff_voxels",
                format!("{} must be in [0.25, 8]", self.falloff_voxels),
            );
        }
        if !(self.density_scale.is_finite() && (0.01..=1e4).contains(&self.density_scale)) {
            return bad(
                "density_scale",
                format!("{} must be in [0.01, 1e4]", self.density_scale),
            );
        }
        Ok(())
    }

    pub(crate) fn from_spec(spec: Option<&BakeSpec>) -> Result<Self, (String, String)> {
        let d = Self::default();
        let k = match spec {
            None => d,
            Some(s) => Self {
                resolution: s.resolution.unwrap_or(d.resolution),
                samples: s.samples.unwrap_or(d.samples),
                bounces: s.bounces.unwrap_or(d.bounces),
                seed: s.seed.unwrap_or(d.seed),
                falloff_voxels: s.falloff_voxels.unwrap_or(d.falloff_voxels),
                density_scale: s.density_scale.unwrap_or(d.density_scale),
            },
        };
        k.check()?;
        Ok(k)
    }
}
