//! What a photograph's pixel says of the rendered pixel C, and the loss
//! and its gradient that hold C to it.
//!
//! - An HDR value Y (EXR frames): the relative squared error
//!   Σ_c (C_c − Y_c)² / (sg(C_c) + ε)², sg holding its value out of the
//!   gradient (RawNeRF's loss: every pixel weighs by its relative error,
//!   so a dim corner counts as much as a lamp).
//! - A lower bound (a saturated LDR pixel): the same error, only where C
//!   is below it.
//! - A bracket (an LDR pixel y taken with exposure e): the squared error
//!   between srgb(clip(e·C)) and y's encoded value, so that the field
//!   learns HDR radiance from exposures directly; a clipped channel whose
//!   rendered value is clipped too gives no gradient.

use glam::DVec3;

/// What one pixel of a photograph says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PixelTarget {
    /// Linear radiance.
    Value(DVec3),
    /// The radiance is at least this.
    AtLeast(DVec3),
    /// An sRGB-encoded LDR value in [0, 1] taken at exposure `exposure`.
    Bracket {
        /// The recorded, encoded value.
        encoded: DVec3,
        /// The exposure the value was taken with (radiance × exposure is
        /// what the sensor records, 1 at white).
        exposure: f64,
    },
}

/// sRGB encoding of linear [0, 1] ([`crate::dataset::pixels::srgb_encode`])
/// and its derivative.
fn srgb_encode(v: f64) -> (f64, f64) {
    let e = crate::dataset::pixels::srgb_encode(v);
    if v <= 0.003_130_8 {
        (e, 12.92)
    } else {
        (e, 1.055 / 2.4 * v.powf(1.0 / 2.4 - 1.0))
    }
}

/// The loss of rendered pixel `c` against `target` (ε the relative loss's
/// floor, in radiance) and its gradient with respect to `c`.
pub fn pixel_loss(c: DVec3, target: PixelTarget, epsilon: f64) -> (f64, DVec3) {
    match target {
        PixelTarget::Value(y) | PixelTarget::AtLeast(y) => {
            let lower = matches!(target, PixelTarget::AtLeast(_));
            let mut loss = 0.0;
            let mut grad = DVec3::ZERO;
            for k in 0..3 {
                let mut r = c[k] - y[k];
                if lower {
                    r = r.min(0.0);
                }
                let scale = 1.0 / (c[k].max(0.0) + epsilon).powi(2);
                loss += r * r * scale;
                grad[k] = 2.0 * r * scale;
            }
            (loss, grad)
        }
        PixelTarget::Bracket { encoded, exposure } => {
            let mut loss = 0.0;
            let mut grad = DVec3::ZERO;
            for k in 0..3 {
                let v = exposure * c[k];
                let clipped = v.clamp(0.0, 1.0);
                let (e, slope) = srgb_encode(clipped);
                let r = e - encoded[k];
                loss += r * r;
                if v > 0.0 && v < 1.0 {
                    grad[k] = 2.0 * r * slope * exposure;
                }
            }
            (loss, grad)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each loss's gradient matches central differences (the relative
    /// loss with its denominator held, as the gradient holds it).
    #[test]
    fn loss_gradients_match_finite_differences() {
        let c = DVec3::new(0.4, 2.5, 0.05);
        let cases = [
            PixelTarget::Value(DVec3::new(0.5, 2.0, 0.1)),
            PixelTarget::AtLeast(DVec3::new(0.5, 2.0, 0.1)),
            PixelTarget::Bracket {
                encoded: DVec3::new(0.6, 1.0, 0.2),
                exposure: 0.5,
            },
        ];
        for t in cases {
            let (_, g) = pixel_loss(c, t, 1e-2);
            for k in 0..3 {
                let h = 1e-6;
                let mut a = c;
                let mut b = c;
                a[k] += h;
                b[k] -= h;
                let held = |x: DVec3| match t {
                    PixelTarget::Bracket { .. } => pixel_loss(x, t, 1e-2).0,
                    PixelTarget::Value(y) | PixelTarget::AtLeast(y) => {
                        let r = x[k] - y[k];
                        let r = if matches!(t, PixelTarget::AtLeast(_)) {
                            r.min(0.0)
                        } else {
                            r
                        };
                        r * r / (c[k] + 1e-2).powi(2)
                    }
                };
                let numeric = (held(a) - held(b)) / (2.0 * h);
                assert!(
                    (numeric - g[k]).abs() < 1e-5 * (1.0 + numeric.abs()),
                    "{t:?} {k}: {numeric} vs {}",
                    g[k]
                );
            }
        }
        // A lower bound below the pixel costs nothing; a clipped bracket
        // rendered clipped gives no gradient.
        assert_eq!(
            pixel_loss(c, PixelTarget::AtLeast(DVec3::splat(0.01)), 1e-2).0,
            0.0
        );
        let (_, g) = pixel_loss(
            DVec3::splat(5.0),
            PixelTarget::Bracket {
                encoded: DVec3::ONE,
                exposure: 1.0,
            },
            1e-2,
        );
        assert_eq!(g, DVec3::ZERO);
    }
}
