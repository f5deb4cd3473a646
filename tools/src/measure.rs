//! Helpers the measuring commands share: image sizes on the command line
//! and the error of an image against a reference.

use inlay_engine::HdrImage;

/// Parses `WxH` (each side 1..=16384).
pub fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| anyhow::anyhow!("size `{s}` is not WxH"))?;
    let (w, h): (u32, u32) = (w.parse()?, h.parse()?);
    anyhow::ensure!(
        (1..=16384).contains(&w) && (1..=16384).contains(&h),
        "size `{s}` is out of range"
    );
    Ok((w, h))
}

/// Mean |a − b| over rgb, divided by the mean of b: the relative error of
/// image `a` against reference pixels `b` (NaN when `a` has a
/// non-finite pixel).
pub fn relative_error(a: &HdrImage, b: &[[f32; 4]]) -> f64 {
    let (mut err, mut mean) = (0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(b) {
        for c in 0..3 {
            err += (p[c] - q[c]).abs() as f64;
            mean += q[c] as f64;
        }
    }
    err / mean.max(1e-30)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_bad_ones_are_refused() {
        assert_eq!(parse_size("320x180").unwrap(), (320, 180));
        for bad in ["320", "0x10", "axb", "20000x10"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn relative_error_is_mean_absolute_over_mean() {
        let a = HdrImage {
            width: 2,
            height: 1,
            pixels: vec![[1.0, 1.0, 1.0, 1.0], [3.0, 3.0, 3.0, 1.0]],
        };
        let b = [[2.0, 2.0, 2.0, 1.0], [2.0, 2.0, 2.0, 1.0]];
        assert!((relative_error(&a, &b) - 0.5).abs() < 1e-12);
        let mut nan = a.clone();
        nan.pixels[0][1] = f32::NAN;
        assert!(relative_error(&nan, &b).is_nan());
    }
}
