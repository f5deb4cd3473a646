//! The march's quality knobs (`[march]` in a scene file).

use crate::scene::spec::MarchSpec;

/// How finely the field is integrated along each ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarchKnobs {
    /// Segments across the field's bounding-box diagonal: the step is the
    /// diagonal divided by this.
    pub samples_per_ray: u32,
    /// Stop once the transmittance falls below this (0: never stop early).
    pub termination: f64,
    /// Skip samples in empty occupancy cells (exact: they add nothing).
    pub skip_empty: bool,
}

impl Default for MarchKnobs {
    fn default() -> Self {
        Self {
            samples_per_ray: 512,
            termination: 1e-4,
            skip_empty: true,
        }
    }
}

impl MarchKnobs {
    /// The step length for a field whose bounds have this diagonal.
    pub fn step(&self, diagonal: f64) -> f64 {
        diagonal / self.samples_per_ray as f64
    }

    /// Why the knobs cannot be used, naming the knob.
    pub fn check(&self) -> Result<(), (String, String)> {
        if !(4..=1 << 16).contains(&self.samples_per_ray) {
            return Err((
                "samples_per_ray".into(),
                format!("{} must be in 4..=65536", self.samples_per_ray),
            ));
        }
        if !(self.termination.is_finite() && (0.0..=0.5).contains(&self.termination)) {
            return Err((
                "termination".into(),
                format!("{} must be in [0, 0.5]", self.termination),
            ));
        }
        Ok(())
    }

    pub(crate) fn from_spec(spec: Option<&MarchSpec>) -> Result<Self, (String, String)> {
        let d = Self::default();
        let k = match spec {
            None => d,
            Some(s) => Self {
                samples_per_ray: s.samples_per_ray.unwrap_or(d.samples_per_ray),
                termination: s.termination.unwrap_or(d.termination),
                skip_empty: s.skip_empty.unwrap_or(d.skip_empty),
            },
        };
        k.check()?;
        Ok(k)
    }
}
