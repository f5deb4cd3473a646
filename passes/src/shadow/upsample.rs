//! The cast shadow at a fraction of the image's resolution (`[shadows]
//! cast_scale`), brought back to full resolution by `shadow-upsample`
//! (`shaders/shadow/upsample.wgsl`, mirrored by [`upsample_shadow`]): ρ is
//! smooth across a surface, so it is taken at one pixel of each s × s block
//! (its centre pixel, [`source_pixel`]) and each pixel blends the four
//! nearest blocks bilinearly, each weighted down as its depth departs from
//! the pixel's (a block seen on another surface does not bleed across a
//! silhouette); where no block lies on the pixel's surface, the block
//! nearest in depth stands.

use glam::DVec3;

/// Largest cast-shadow scale a scene may ask for.
pub const MAX_CAST_SCALE: u32 = 4;

/// Relative depth difference at which a block's weight reaches zero
/// (`UPSAMPLE_DEPTH_FALLOFF` in the shader).
pub const DEPTH_FALLOFF: f64 = 0.05;

/// The low-resolution image's size for a `width` × `height` image at `scale`.
pub fn low_size(width: u32, height: u32, scale: u32) -> (u32, u32) {
    (width.div_ceil(scale), height.div_ceil(scale))
}

/// The full-resolution pixel low-resolution pixel (`x`, `y`) is taken at:
/// its block's centre, inside the image.
pub fn source_pixel(x: u32, y: u32, scale: u32, width: u32, height: u32) -> (u32, u32) {
    (
        (x * scale + scale / 2).min(width - 1),
        (y * scale + scale / 2).min(height - 1),
    )
}

/// ρ at full resolution from `low` (row-major, [`low_size`]), with `depth`
/// each full-resolution pixel's depth along its ray (None where the field
/// is empty: ρ = 1 there).
pub fn upsample_shadow(
    low: &[DVec3],
    depth: &[Option<f64>],
    width: u32,
    height: u32,
    scale: u32,
) -> Vec<DVec3> {
    let (lw, lh) = low_size(width, height, scale);
    let depth_at = |x: u32, y: u32| depth[(y * width + x) as usize];
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let Some(z) = depth_at(x, y) else {
                out.push(DVec3::ONE);
                continue;
            };
            let f = |p: u32, n: u32| {
                let t = ((p as f64 + 0.5) / scale as f64 - 0.5).max(0.0);
                let i0 = (t.floor() as u32).min(n - 1);
                (i0, (i0 + 1).min(n - 1), (t - i0 as f64).clamp(0.0, 1.0))
            };
            let (x0, x1, tx) = f(x, lw);
            let (y0, y1, ty) = f(y, lh);
            let corners = [
                (x0, y0, (1.0 - tx) * (1.0 - ty)),
                (x1, y0, tx * (1.0 - ty)),
                (x0, y1, (1.0 - tx) * ty),
                (x1, y1, tx * ty),
            ];
            let (mut sum, mut weight) = (DVec3::ZERO, 0.0);
            let (mut nearest, mut nearest_gap) = (DVec3::ONE, f64::INFINITY);
            for (cx, cy, bilinear) in corners {
                let (sx, sy) = source_pixel(cx, cy, scale, width, height);
                let rho = low[(cy * lw + cx) as usize];
                let Some(zq) = depth_at(sx, sy) else {
                    continue;
                };
                let gap = (zq - z).abs() / z.max(1e-30);
                if gap < nearest_gap {
                    (nearest, nearest_gap) = (rho, gap);
                }
                let w = bilinear * (1.0 - gap / DEPTH_FALLOFF).max(0.0);
                sum += w * rho;
                weight += w;
            }
            out.push(if weight > 1e-6 { sum / weight } else { nearest });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At scale 1 the image passes through; a constant ρ stays constant; a
    /// pixel on a near surface beside a far one takes the near blocks alone.
    #[test]
    fn upsampling_keeps_surfaces_apart() {
        let (w, h) = (9u32, 7u32);
        let depth: Vec<Option<f64>> = (0..w * h)
            .map(|i| {
                let x = i % w;
                if i == 0 {
                    None
                } else if x < 4 {
                    Some(1.0)
                } else {
                    Some(5.0)
                }
            })
            .collect();
        let low: Vec<DVec3> = (0..w * h).map(|i| DVec3::splat(i as f64 / 100.0)).collect();
        let same = upsample_shadow(&low, &depth, w, h, 1);
        for (i, r) in same.iter().enumerate() {
            let expect = if i == 0 { DVec3::ONE } else { low[i] };
            assert_eq!(*r, expect, "{i}");
        }
        let (lw, lh) = low_size(w, h, 2);
        assert_eq!((lw, lh), (5, 4));
        let flat = upsample_shadow(&vec![DVec3::splat(0.4); 20], &depth, w, h, 2);
        assert!(flat[1..]
            .iter()
            .all(|r| (*r - DVec3::splat(0.4)).abs().max_element() < 1e-12));
        // Near surface (x < 4): blocks 0 and 1 sample x = 1 and 3 (near),
        // block 2 samples x = 5 (far). Far blocks say 0, near ones 1.
        let low: Vec<DVec3> = (0..lw * lh)
            .map(|i| if i % lw < 2 { DVec3::ONE } else { DVec3::ZERO })
            .collect();
        let up = upsample_shadow(&low, &depth, w, h, 2);
        for y in 0..h {
            for x in 1..w {
                let r = up[(y * w + x) as usize];
                let expect = if x < 4 { 1.0 } else { 0.0 };
                assert_eq!(r, DVec3::splat(expect), "({x}, {y})");
            }
        }
    }
}
