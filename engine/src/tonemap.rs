//! Display mapping of linear HDR colour: exposure, the ACES filmic curve
//! (Narkowicz's fit) and the sRGB transfer function. Mirrored once in WGSL by
//! `shaders/common/tonemap.wgsl`; a test keeps the two in step.

/// Maps one linear HDR channel to a display-referred value in [0, 1]
/// (before sRGB encoding). Non-finite or negative input maps to 0.
pub fn aces_filmic(x: f32) -> f32 {
    if !x.is_finite() {
        return if x == f32::INFINITY { 1.0 } else { 0.0 };
    }
    // Clamped to the f16 range so the rational curve cannot overflow.
    let x = x.clamp(0.0, 65504.0);
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(0.0, 1.0)
}

/// The sRGB opto-electronic transfer function for a value in [0, 1]
/// (clipped to it first), in f64: the one definition, for the trainer's
/// losses and references as for display.
pub fn srgb_encode_f64(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// [`srgb_encode_f64`] in f32.
pub fn srgb_encode(x: f32) -> f32 {
    srgb_encode_f64(x as f64) as f32
}

/// Linear HDR RGB → 8-bit sRGB after `exposure` (a multiplier).
pub fn tonemap_to_srgb8(rgb: [f32; 3], exposure: f32) -> [u8; 3] {
    rgb.map(|c| (srgb_encode(aces_filmic(c * exposure)) * 255.0 + 0.5) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_is_monotone_bounded_and_safe() {
        let mut last = -1.0;
        for i in 0..2000 {
            let y = aces_filmic(i as f32 * 0.01);
            assert!(y >= last && (0.0..=1.0).contains(&y));
            last = y;
        }
        assert_eq!(aces_filmic(f32::NAN), 0.0);
        assert_eq!(aces_filmic(-3.0), 0.0);
        assert_eq!(aces_filmic(f32::INFINITY), 1.0);
        assert_eq!(tonemap_to_srgb8([0.0, 1e30, f32::NAN], 1.0), [0, 255, 0]);
    }

    #[test]
    fn srgb_matches_the_standard_at_known_points() {
        assert!((srgb_encode(0.5) - 0.735_357).abs() < 1e-5);
        assert!((srgb_encode(0.001) - 0.012_92).abs() < 1e-7);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
    }
}
