//! The probe's knobs: direction map and resolution.

use super::direction_map::{DirectionMap, MapKind};

/// How finely the incident light at the object is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeKnobs {
    /// Layout of the probe image.
    pub map: MapKind,
    /// Resolution n: n × n texels (octahedral) or 2n × n (equirect).
    pub resolution: u32,
}

impl Default for ProbeKnobs {
    /// Octahedral 32 × 32: 1024 rays, texels of about 0.012 sr (6° across).
    fn default() -> Self {
        Self {
            map: MapKind::Octahedral,
            resolution: 32,
        }
    }
}

impl ProbeKnobs {
    /// The direction map these knobs describe.
    pub fn direction_map(&self) -> DirectionMap {
        DirectionMap::new(self.map, self.resolution)
    }

    /// Why the knobs cannot be used, naming the knob.
    pub fn check(&self) -> Result<(), (String, String)> {
        if !(4..=256).contains(&self.resolution) {
            return Err((
                "resolution".into(),
                format!("{} must be in 4..=256", self.resolution),
            ));
        }
        Ok(())
    }
}
