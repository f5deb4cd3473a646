//! What a photograph's pixel says of the rendered pixel C, and the loss
//! and its gradient that hold C to it.
//!
//! - An HDR value Y (EXR frames): the relative squared error
//!   Σ_c (C_c − Y_c)² / (sg(max(C_c, s·Y_c)) + ε)², sg holding its value
//!   out of the gradient, s = [`RENDER_FLOOR_SHARE`]: RawNeRF's loss
//!   (every pixel weighs by its relative error, so a dim corner counts as
//!   much as a lamp), except that a render darker than s of its
//!   photograph weighs as if it were at s. Divided by the render alone, a
//!   ray rendered black where a lamp was photographed weighs (Y/ε)² (some
//!   10⁵ for PLANTS' lamp), and the lamp's pixels in the trained views
//!   kept 0.61–0.64 of their light; with the floor 0.90–0.91
//!   (`docs/benchmarks.md`, issue 25's twelfth pass). Rays that share a
//!   value keep the same weight above the floor, so where the views
//!   disagree on it (a light smaller than a node) the value settles at
//!   their mean, as the render's weight alone gives; relative to the
//!   larger of render and photograph, the dark rays won and such a lamp
//!   was lost.
//! - A lower bound (a saturated LDR pixel): the same error, only where C
//!   is below it.
//! - A bracket (an LDR pixel y taken with exposure e): the squared error
//!   between srgb(e·C) and y's encoded value, so that the field learns HDR
//!   radiance from exposures directly. Clipped only where the photograph
//!   clipped: a channel recorded white says e·C ≥ 1 (a rendered value
//!   clipped too costs nothing); one recorded below white is compared with
//!   the sRGB curve continued past 1, so a render too bright for it is
//!   pulled down however bright (clipped, it gave no gradient past white:
//!   a field too bright in a pixel was held there by every exposure that
//!   saw it so). Each channel's difference, less the half level its
//!   rounding may hold ([`quantised_residual`]), is divided by the code
//!   difference that an error of the linear loss's denominator makes at
//!   the pixel's level ([`bracket_scale`]), so a well-exposed bracket
//!   weighs a pixel as its linear view does.

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

/// The share of a photograph's value Y below which a render is weighed as
/// if it were at it: the relative loss's denominator is at least this × Y,
/// so a render too dark is off by at most 16 times its denominator (a
/// black one by exactly that).
pub const RENDER_FLOOR_SHARE: f64 = 1.0 / 16.0;

/// sRGB encoding of linear v ≥ 0 ([`crate::dataset::pixels::srgb_encode`]
/// up to 1, its curve continued past 1) and its derivative.
fn srgb_encode(v: f64) -> (f64, f64) {
    if v <= 0.003_130_8 {
        (crate::dataset::pixels::srgb_encode(v), 12.92)
    } else {
        (
            1.055 * v.powf(1.0 / 2.4) - 0.055,
            1.055 / 2.4 * v.powf(1.0 / 2.4 - 1.0),
        )
    }
}

/// The least a bracket's residual is divided by, in sRGB code values: two
/// 8-bit levels, so that a pixel a bracket records a few levels above
/// black (where the code says little of the radiance) weighs by its code
/// difference, not as a relative error.
pub const BRACKET_CODE_FLOOR: f64 = 2.0 / 255.0;

/// Half an 8-bit level: the most by which a recorded code differs from
/// the value it rounded.
pub const BRACKET_HALF_LEVEL: f64 = 0.5 / 255.0;

/// A bracket's code residual less the rounding it may hold: 0 within half
/// a level of the recorded code, and beyond it the excess. A dim pixel's
/// reading in a short bracket is a code or two (a code of 0 says only that
/// the pixel is below half a level): compared as a value, PLANTS' field
/// from brackets down to 1/512 came out 1.6 dB below its linear views'
/// with the linear loss's weights, its dim pixels pulled towards the
/// codes their short brackets rounded them to.
pub fn quantised_residual(r: f64) -> f64 {
    r.signum() * (r.abs() - BRACKET_HALF_LEVEL).max(0.0)
}

/// The held weight 1/σ² of one channel of a bracket's squared code
/// residual (render `c`, recorded code `encoded`, exposure `exposure`, ε
/// the relative loss's floor): σ = slope(e·L)·e·(L + ε) +
/// [`BRACKET_CODE_FLOOR`], L = max(c, s·Y) (Y the recorded radiance), the
/// code difference that an error of the linear loss's denominator L + ε
/// makes at the pixel's level. So a well-exposed bracket weighs a pixel
/// as a linear view does, relative where it is brighter than ε and in
/// linear differences where dimmer (with the slope taken at e·(L + ε), a
/// dim pixel weighed (slope(e·L)/slope(e·(L + ε)))² times what its linear
/// view does: at ε = 0.2 and exposure 1, 16 times at L = 0.02 and 132
/// near black), whatever its brightness: squared
/// code differences alone weigh a render 20 % dim 0.41 times as much at
/// 0.31 of white (PLANTS' lamp in the bracket that records it) as at 0.9,
/// and a dark pixel the lamp's blur lights in a long exposure far more
/// than a lamp pixel 20 % dim in the short one that records it.
pub fn bracket_scale(c: f64, encoded: f64, exposure: f64, epsilon: f64) -> f64 {
    let y = crate::dataset::pixels::srgb_to_linear(encoded.min(1.0) as f32) as f64 / exposure;
    let level = c.max(RENDER_FLOOR_SHARE * y).max(0.0);
    let sigma = srgb_encode(exposure * level).1 * exposure * (level + epsilon) + BRACKET_CODE_FLOOR;
    1.0 / (sigma * sigma)
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
                let floor = RENDER_FLOOR_SHARE * y[k];
                let scale = 1.0 / (c[k].max(floor).max(0.0) + epsilon).powi(2);
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
                // Recorded white: the render is clipped as the sensor was.
                let white = encoded[k] >= 1.0;
                let (e, slope) = srgb_encode(if white { v.clamp(0.0, 1.0) } else { v.max(0.0) });
                let r = quantised_residual(e - encoded[k]);
                let scale = bracket_scale(c[k], encoded[k], exposure, epsilon);
                loss += r * r * scale;
                if v > 0.0 && (v < 1.0 || !white) {
                    grad[k] = 2.0 * r * slope * exposure * scale;
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
            // Rendered past white (1.25) where the photograph is not.
            PixelTarget::Bracket {
                encoded: DVec3::new(0.6, 0.9, 0.2),
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
                    PixelTarget::Bracket { encoded, exposure } => {
                        let v = (exposure * x[k]).max(0.0);
                        let v = if encoded[k] >= 1.0 { v.min(1.0) } else { v };
                        quantised_residual(srgb_encode(v).0 - encoded[k]).powi(2)
                            * bracket_scale(c[k], encoded[k], exposure, 1e-2)
                    }
                    PixelTarget::Value(y) | PixelTarget::AtLeast(y) => {
                        let r = x[k] - y[k];
                        let r = if matches!(t, PixelTarget::AtLeast(_)) {
                            r.min(0.0)
                        } else {
                            r
                        };
                        r * r / (c[k].max(RENDER_FLOOR_SHARE * y[k]) + 1e-2).powi(2)
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
        // A render far darker than its photograph weighs as one at the
        // floor: its loss is at most (1/s)² a channel however dark
        // (divided by the render alone, a black render of this lamp cost
        // (Y/ε)² = 1e12 a channel), and it is the same for every render
        // below the floor's.
        let lamp = PixelTarget::Value(DVec3::splat(1e4));
        let bound = 3.0 * (1.0 / RENDER_FLOOR_SHARE).powi(2);
        let (black, g_black) = pixel_loss(DVec3::ZERO, lamp, 1e-2);
        assert!(
            black <= bound && black > 0.9 * bound,
            "{black} against {bound}"
        );
        let g_dim = pixel_loss(DVec3::splat(1.0), lamp, 1e-2).1;
        assert!((g_black - g_dim).abs().max_element() < 1e-3 * g_black.abs().max_element());
        // Above the floor, as divided by the render alone.
        let (above, _) = pixel_loss(DVec3::splat(2e3), lamp, 1e-2);
        assert!((above - 3.0 * (8e3f64 / (2e3 + 1e-2)).powi(2)).abs() < 1e-9);
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

    /// A render past white where the photograph recorded a value below it
    /// is pulled down, the further past the harder; below white the loss
    /// is the clipped one's; the curve is continuous at white.
    #[test]
    fn a_bracket_not_saturated_pulls_a_render_past_white_down() {
        let grey = PixelTarget::Bracket {
            encoded: DVec3::splat(0.5),
            exposure: 0.5,
        };
        let (l2, g2) = pixel_loss(DVec3::splat(4.0), grey, 1e-2);
        let (l8, g8) = pixel_loss(DVec3::splat(16.0), grey, 1e-2);
        assert!(g2.min_element() > 0.0 && g8.min_element() > 0.0);
        assert!(l8 > l2 && l2 > 3.0 * 0.25, "{l2} {l8}");
        let below = pixel_loss(DVec3::splat(1.2), grey, 1e-2).0;
        let expected = 3.0
            * quantised_residual(crate::dataset::pixels::srgb_encode(0.6) - 0.5f64).powi(2)
            * bracket_scale(1.2, 0.5, 0.5, 1e-2);
        assert!((below - expected).abs() < 1e-12);
        let (under, over) = (srgb_encode(1.0 - 1e-9).0, srgb_encode(1.0 + 1e-9).0);
        assert!((under - 1.0).abs() < 1e-8 && (over - 1.0).abs() < 1e-8);
    }

    /// A well-exposed bracket weighs a render by its relative error, as a
    /// linear view does: 20 % dim costs 0.62–0.80 of the linear loss (the
    /// sRGB curve flattens over the 20 %, and half a level of rounding is
    /// a larger share of a dim pixel's few levels) whether the bracket
    /// recorded the pixel at 3 % or 90 % of white (as
    /// squared code differences alone, 0.31 of white, PLANTS' lamp in its
    /// shortest bracket, cost 0.41 of 0.9 of white's). A pixel a bracket
    /// records near black weighs by its code difference over the floor.
    #[test]
    fn a_bracket_weighs_a_render_by_its_relative_error() {
        let eps = 1e-3;
        let mut ratios = Vec::new();
        for (radiance, exposure) in [(160.0, 1.0 / 512.0), (0.9, 1.0), (0.4, 0.125), (0.03, 1.0)] {
            let y = DVec3::splat(radiance);
            let encoded = DVec3::splat(crate::dataset::pixels::srgb_encode(radiance * exposure));
            let bracket = PixelTarget::Bracket { encoded, exposure };
            let dim = 0.8 * y;
            let (b, _) = pixel_loss(dim, bracket, eps);
            let (l, _) = pixel_loss(dim, PixelTarget::Value(y), eps);
            ratios.push(b / l);
            assert!(
                (0.6..0.85).contains(&(b / l)),
                "{radiance} at {exposure}: {b} against {l}"
            );
        }
        let (low, high) = ratios
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), r| (a.min(*r), b.max(*r)));
        assert!(high / low < 1.35, "{ratios:?}");
        // Dimmer than the floor ε (training's is 4 × the mean radiance):
        // as the linear loss, in linear differences.
        for (radiance, exposure) in [(0.02, 1.0), (0.2, 0.125), (0.05, 1.0)] {
            let y = DVec3::splat(radiance);
            let encoded = DVec3::splat(crate::dataset::pixels::srgb_encode(radiance * exposure));
            let bracket = PixelTarget::Bracket { encoded, exposure };
            let (b, _) = pixel_loss(1.5 * y, bracket, 0.4);
            let (l, _) = pixel_loss(1.5 * y, PixelTarget::Value(y), 0.4);
            assert!(
                (0.6..1.4).contains(&(b / l)),
                "{radiance} at {exposure}: {b} against {l}"
            );
        }
        // Recorded a level above black: bounded by the floor, less the
        // rounding.
        let faint = PixelTarget::Bracket {
            encoded: DVec3::splat(1.0 / 255.0),
            exposure: 1.0 / 512.0,
        };
        let (l, _) = pixel_loss(DVec3::splat(0.0), faint, eps);
        assert!(l <= 3.0 * 0.25 * 0.25 + 1e-12 && l > 0.1, "{l}");
        // Within half a level of its code: no pull at all.
        let zero = PixelTarget::Bracket {
            encoded: DVec3::ZERO,
            exposure: 1.0 / 512.0,
        };
        let (l, g) = pixel_loss(DVec3::splat(0.02), zero, eps);
        assert_eq!((l, g), (0.0, DVec3::ZERO));
    }
}
