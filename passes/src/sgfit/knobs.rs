//! The SG fit's knobs: lobe count, iterations, damping.

/// How hard the Levenberg–Marquardt fit works.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitKnobs {
    /// Number of lobes M.
    pub lobes: u32,
    /// Iterations after a cold start (first frame, or after a jump).
    pub cold_iterations: u32,
    /// Iterations after a warm start from the previous frame's lobes.
    pub warm_iterations: u32,
    /// Most iterations of a warm update run in one frame (0: all of them):
    /// the rest run in the frames after, the fit going on from where it
    /// stopped, so a moving object's frame never waits for the whole update
    /// and the lighting reaches the same lobes ⌈warm / this⌉ frames after the
    /// object stops. The cold fit runs whole in its frame.
    pub frame_iterations: u32,
    /// Initial Marquardt damping η (of the Jacobi-scaled normal equations).
    pub damping: f64,
}

impl Default for FitKnobs {
    fn default() -> Self {
        Self {
            lobes: 32,
            cold_iterations: 40,
            warm_iterations: 8,
            frame_iterations: 2,
            damping: 1e-2,
        }
    }
}

/// Most lobes a fit may have (the fit's normal matrix, 6M + 1 columns, and its solve
/// are sized for it).
pub const MAX_LOBES: u32 = 64;
/// Most iterations one fit records (the per-iteration residual log's length).
pub const MAX_ITERATIONS: u32 = 256;

impl FitKnobs {
    /// Why the knobs cannot be used, naming the knob.
    pub fn check(&self) -> Result<(), (String, String)> {
        if !(1..=MAX_LOBES).contains(&self.lobes) {
            return Err((
                "lobes".into(),
                format!("{} must be in 1..={MAX_LOBES}", self.lobes),
            ));
        }
        for (name, v) in [
            ("cold_iterations", self.cold_iterations),
            ("warm_iterations", self.warm_iterations),
            ("frame_iterations", self.frame_iterations),
        ] {
            if v > MAX_ITERATIONS {
                return Err((name.into(), format!("{v} must be at most {MAX_ITERATIONS}")));
            }
        }
        if !(self.damping.is_finite() && (1e-9..=1e9).contains(&self.damping)) {
            return Err((
                "damping".into(),
                format!("{} must be in [1e-9, 1e9]", self.damping),
            ));
        }
        Ok(())
    }

    /// Parameters of the fit: 6 per lobe (√μ rgb, ln λ, two tangent angles).
    pub fn parameters(&self) -> usize {
        6 * self.lobes as usize
    }
}
