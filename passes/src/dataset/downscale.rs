//! Photographs read at 1/n of their width and height (`--downscale n`):
//! each n × n block of pixels becomes one, so that a capture of phone
//! photographs fits in memory. A block keeps what its pixels can tell:
//!
//! - its radiance is the mean of its pixels' (the light over its area, as
//!   a pixel of a smaller sensor would record it);
//! - it is masked where any of its pixels is (never a mean with a value
//!   that is not one), and a lower bound where any is (the mean of lower
//!   bounds and values is a lower bound of the true mean);
//! - its alpha is the mean of its pixels';
//! - its depth is the median of its pixels' recorded depths where more
//!   than half record one (a surface some of its rays meet: at an edge the
//!   mean of a near and a far depth would be a surface that is not there),
//!   else nothing.
//!
//! The camera keeps its lens: the focal lengths and the principal point
//! scale by 1/n (the block's centre, pixel-centre convention, lands where
//! the original pixels' centres put it); the distortion, in normalised
//! coordinates, is unchanged. Pixels past the last whole block (a width
//! not a multiple of n) are left out, which moves nothing else.

use super::intrinsics::Intrinsics;
use super::pixels::{FrameImage, PixelState};

/// The largest factor `--downscale` takes.
pub const MAX_DOWNSCALE: u32 = 64;

/// `k` for an image read at 1/`n` of its size.
pub fn intrinsics(k: &Intrinsics, n: u32) -> Intrinsics {
    let s = 1.0 / n as f64;
    Intrinsics {
        width: k.width / n,
        height: k.height / n,
        fx: k.fx * s,
        fy: k.fy * s,
        cx: k.cx * s,
        cy: k.cy * s,
        distortion: k.distortion,
    }
}

/// The pixel indices of block (bx, by) of an image `width` wide.
fn block(width: u32, n: u32, bx: u32, by: u32) -> impl Iterator<Item = usize> {
    (0..n * n).map(move |i| ((by * n + i / n) * width + bx * n + i % n) as usize)
}

/// `image` at 1/`n` of its width and height. Its counts stay those of the
/// photograph as read (what it held, not what its blocks hold).
pub fn image(image: &FrameImage, n: u32) -> FrameImage {
    let (w, h) = (image.width / n, image.height / n);
    let count = (w * h) as usize;
    let mut radiance = Vec::with_capacity(count);
    let mut state = Vec::with_capacity(count);
    let mut alpha = Vec::with_capacity(if image.alpha.is_empty() { 0 } else { count });
    for by in 0..h {
        for bx in 0..w {
            let mut sum = [0.0f64; 3];
            let mut s = PixelState::Value;
            let mut a = 0.0f64;
            for i in block(image.width, n, bx, by) {
                match image.state[i] {
                    PixelState::Masked => s = PixelState::Masked,
                    PixelState::LowerBound if s == PixelState::Value => s = PixelState::LowerBound,
                    _ => {}
                }
                for (acc, v) in sum.iter_mut().zip(image.radiance[i]) {
                    *acc += v as f64;
                }
                a += image.alpha_at(i) as f64;
            }
            let inv = 1.0 / (n * n) as f64;
            radiance.push(if s == PixelState::Masked {
                [0.0; 3]
            } else {
                sum.map(|v| (v * inv) as f32)
            });
            state.push(s);
            if !image.alpha.is_empty() {
                alpha.push((a * inv) as f32);
            }
        }
    }
    FrameImage {
        width: w,
        height: h,
        radiance,
        state,
        alpha,
        counts: image.counts,
    }
}

/// A depth map `width` × `height` (0 where a pixel records nothing) at
/// 1/`n` of its size: each block the median of its recorded depths where
/// more than half its pixels record one, else 0. An empty map stays empty.
pub fn depth(z: &[f32], width: u32, height: u32, n: u32) -> Vec<f32> {
    if z.is_empty() {
        return Vec::new();
    }
    let (w, h) = (width / n, height / n);
    let mut out = Vec::with_capacity((w * h) as usize);
    let mut recorded = Vec::with_capacity((n * n) as usize);
    for by in 0..h {
        for bx in 0..w {
            recorded.clear();
            recorded.extend(block(width, n, bx, by).map(|i| z[i]).filter(|&d| d > 0.0));
            out.push(if 2 * recorded.len() > (n * n) as usize {
                recorded.sort_by(f32::total_cmp);
                recorded[recorded.len() / 2]
            } else {
                0.0
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::intrinsics::Distortion;
    use crate::dataset::pixels::PixelCounts;

    /// A block looks where the centre of its pixels' area looks, with or
    /// without a lens: block (bx, by)'s centre at 1/n looks where the
    /// original's position ((bx + ½) n, (by + ½) n) does.
    #[test]
    fn a_block_looks_where_the_centre_of_its_pixels_looks() {
        for distortion in [
            Distortion::None,
            Distortion::OpenCv {
                k1: -0.12,
                k2: 0.03,
                p1: 0.001,
                p2: -0.002,
            },
        ] {
            let k = Intrinsics {
                width: 641,
                height: 480,
                fx: 520.0,
                fy: 515.0,
                cx: 322.3,
                cy: 238.9,
                distortion,
            };
            for n in [2, 3, 8] {
                let d = intrinsics(&k, n);
                assert_eq!((d.width, d.height), (641 / n, 480 / n));
                for (bx, by) in [(0u32, 0u32), (17, 5), (d.width - 1, d.height - 1)] {
                    let centre = |bx: u32| (bx as f64 + 0.5) * n as f64;
                    let full = k.direction(centre(bx), centre(by)).unwrap();
                    let block = d.direction(bx as f64 + 0.5, by as f64 + 0.5).unwrap();
                    assert!((full - block).length() < 1e-12, "{n} {bx} {by}");
                }
            }
        }
    }

    /// Means of values, lower bounds kept as lower bounds, masks kept,
    /// alpha averaged; the depth's median where most record one.
    #[test]
    fn blocks_keep_what_their_pixels_can_tell() {
        // 5 × 4 pixels → 2 × 2 blocks (the fifth column left out).
        let state_at = |x: u32, y: u32| match (x, y) {
            (2, 0) => PixelState::LowerBound,
            (1, 3) => PixelState::Masked,
            _ => PixelState::Value,
        };
        let mut img = FrameImage {
            width: 5,
            height: 4,
            radiance: Vec::new(),
            state: Vec::new(),
            alpha: Vec::new(),
            counts: PixelCounts {
                masked: 1,
                ..PixelCounts::default()
            },
        };
        for y in 0..4 {
            for x in 0..5 {
                let s = state_at(x, y);
                let v = if s == PixelState::Masked {
                    0.0
                } else {
                    (x + 10 * y) as f32
                };
                img.radiance.push([v, 2.0 * v, 0.5]);
                img.state.push(s);
                img.alpha.push(if x == 0 { 0.0 } else { 1.0 });
            }
        }
        let d = image(&img, 2);
        assert_eq!((d.width, d.height), (2, 2));
        // Block (0, 0): pixels 0, 1, 10, 11.
        assert_eq!(d.radiance[0], [5.5, 11.0, 0.5]);
        assert_eq!(d.state[0], PixelState::Value);
        assert_eq!(d.alpha[0], 0.5);
        // Block (1, 0): 2 (a lower bound), 3, 12, 13.
        assert_eq!(d.state[1], PixelState::LowerBound);
        assert_eq!(d.radiance[1], [7.5, 15.0, 0.5]);
        assert_eq!(d.alpha[1], 1.0);
        // Block (0, 1): holds the masked pixel (1, 3).
        assert_eq!((d.state[2], d.radiance[2]), (PixelState::Masked, [0.0; 3]));
        assert_eq!(d.state[3], PixelState::Value);
        assert_eq!(d.counts, img.counts);
        // An opaque image stays without alpha.
        img.alpha.clear();
        assert!(image(&img, 2).alpha.is_empty());

        // Depth: a block straddling an edge takes one of its surfaces, not
        // their mean; a block most of whose pixels record nothing records
        // nothing.
        #[rustfmt::skip]
        let z = [
            1.0, 1.0, 0.0, 0.0,
            1.0, 9.0, 0.0, 3.0,
        ];
        assert_eq!(depth(&z, 4, 2, 2), vec![1.0, 0.0]);
        #[rustfmt::skip]
        let z = [
            1.0, 9.0, 2.0, 2.0,
            9.0, 9.0, 0.0, 2.0,
        ];
        assert_eq!(depth(&z, 4, 2, 2), vec![9.0, 2.0]);
        assert!(depth(&[], 4, 2, 2).is_empty());
    }
}
