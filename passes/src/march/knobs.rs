//! The march's quality knobs (`[march]` in a scene file).

use crate::scene::spec::MarchSpec;

/// Loop iterations a sample of a field with view-dependent colour adds in
/// a kernel compiled with [`SH_CORNER_LOOP_DEFINE`] true: the loop over its
/// cell's eight corners (`shaders/field/sh_trilinear.wgsl`), which
/// llvmpipe does not unroll.
pub const VIEW_DEPENDENT_SAMPLE_LOOPS: u64 = 8;

/// The define (bool) that makes a kernel take a view-dependent sample's
/// eight corners in a loop, not written out: 1.6 times faster on
/// llvmpipe at degree 2, but eight more loop iterations a sample. The
/// march and the trainer, one ray an invocation, set it; every kernel that
/// marches several rays an invocation leaves it false (the shader
/// libraries' default), so that a view-dependent field costs them no more
/// of the loop limit than a plain one.
pub const SH_CORNER_LOOP_DEFINE: &str = "SH_CORNER_LOOP";

/// The most samples a ray may take across the field's diagonal.
pub const MAX_SAMPLES_PER_RAY: u32 = 1 << 15;

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

    /// The most loop iterations one march along a ray takes (what a
    /// kernel counts against the device's loop limit,
    /// [`super::loop_budget`]): one per segment of a ray across the whole
    /// diagonal and one where the last is cut. A view-dependent sample
    /// adds none, its corners written out, except in kernels compiled
    /// with [`SH_CORNER_LOOP_DEFINE`] (the march and the trainer), where it
    /// adds [`VIEW_DEPENDENT_SAMPLE_LOOPS`].
    pub fn loop_iterations(&self) -> u64 {
        self.samples_per_ray as u64 + 1
    }

    /// Why the knobs cannot be used, naming the knob.
    pub fn check(&self) -> Result<(), (String, String)> {
        // At most 32768: one march then stays under llvmpipe's 65535 loop
        // iterations per invocation with room for the loops around it
        // (32768 samples is already 64 per node of a 512³ grid).
        if !(4..=MAX_SAMPLES_PER_RAY).contains(&self.samples_per_ray) {
            return Err((
                "samples_per_ray".into(),
                format!(
                    "{} must be in 4..={MAX_SAMPLES_PER_RAY}",
                    self.samples_per_ray
                ),
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
