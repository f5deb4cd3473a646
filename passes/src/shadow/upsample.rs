//! The cast shadow at a fraction of the image's resolution (`[shadows]
//! cast_scale`), brought back to full resolution by `shadow-upsample`
//! (`shaders/shadow/upsample.wgsl`, mirrored by [`upsample_shadow`]): ρ is
//! smooth across a surface, so it is taken at one pixel of each s × s block
//! (its centre pixel, [`source_pixel`]) and each pixel blends the four
//! nearest blocks bilinearly, each weighted down as its depth departs from
//! the pixel's (a block seen on another surface does not bleed across a
//! silhouette); where no block lies on the pixel's surface, the block
//! nearest in depth stands. Beyond that, `shadow-refine` takes ρ exactly
//! at the pixels the blocks cannot stand for ([`upsample_with_flags`]:
//! fewer than two blocks on the pixel's surface, or blocks whose ρ spread
//! by more than `[shadows] cast_refine`), so a shadow's edges and small
//! shadows keep the full resolution's ρ at about the half resolution's
//! cost. With refinement the image is brought down a level at a time, each
//! of half the scale of the one before ([`next_level`], [`refine_levels`]):
//! the pixels a shadow's edge flags lie in a band as wide as the blocks
//! blended, so refining at 4, then 2, then 1 from 8 takes ρ exactly at
//! about half the points one step from 8 to 1 does, for the same flags.

use glam::DVec3;

/// Largest cast-shadow scale a scene may ask for.
pub const MAX_CAST_SCALE: u32 = 8;

/// The low image [`CastScale::Auto`] keeps the cast shadow's at most: the
/// scale grows with the image so that about this many pixels of it are
/// taken (scale 4 at 640 × 360, 8 at 1280 × 720; docs/benchmarks.md,
/// issue 26's tenth pass, measures the trade against scale 4 there).
pub const AUTO_LOW_SIZE: (u32, u32) = (160, 90);

/// How coarsely the cast shadow is taken (`[shadows] cast_scale`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CastScale {
    /// At one pixel of each s × s block, whatever the image's size (1:
    /// every pixel, the paper's).
    Fixed(u32),
    /// At a scale that grows with the image ([`Self::at`]): a shadow's
    /// extent in pixels grows with the image, and its edges are refined
    /// at full resolution either way, so a 1280 × 720 image is taken at 8
    /// with about as many pixels off as at 4, the mean error in shadow
    /// about doubled (docs/benchmarks.md, issue 26's seventh and tenth
    /// passes).
    Auto,
}

impl CastScale {
    /// The scale for a `width` × `height` image: a fixed one as it is;
    /// automatic, the smallest that keeps the low image within
    /// [`AUTO_LOW_SIZE`], at least 2 and at most [`MAX_CAST_SCALE`].
    pub fn at(self, width: u32, height: u32) -> u32 {
        match self {
            CastScale::Fixed(s) => s,
            CastScale::Auto => width
                .div_ceil(AUTO_LOW_SIZE.0)
                .max(height.div_ceil(AUTO_LOW_SIZE.1))
                .clamp(2, MAX_CAST_SCALE),
        }
    }

    /// Whether every pixel is taken (a fixed scale of 1).
    pub fn is_full(self) -> bool {
        self == CastScale::Fixed(1)
    }
}

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
    upsample_with_flags(low, depth, width, height, scale, f64::INFINITY)
        .into_iter()
        .map(|(rho, _)| rho)
        .collect()
}

/// [`upsample_shadow`] with, per pixel, whether it is to be taken exactly
/// (`shadow-refine`): fewer than two of the four corners it blends lie on
/// its surface (at the image's border a block can be two corners), or
/// the ρ of those that do spread by more than `spread` in some channel (a
/// penumbra or a shadow's edge the blocks straddle). Where the field is
/// empty nothing is refined.
pub fn upsample_with_flags(
    low: &[DVec3],
    depth: &[Option<f64>],
    width: u32,
    height: u32,
    scale: u32,
    spread: f64,
) -> Vec<(DVec3, bool)> {
    upsample_level(low, depth, (width, height), scale, 1, spread)
}

/// [`upsample_with_flags`] onto the image at `out_scale` (below `scale`)
/// rather than at full resolution: each of its pixels takes the value at
/// its block's [`source_pixel`] (`shadow-upsample` with `out_scale`).
pub fn upsample_level(
    low: &[DVec3],
    depth: &[Option<f64>],
    (width, height): (u32, u32),
    scale: u32,
    out_scale: u32,
    spread: f64,
) -> Vec<(DVec3, bool)> {
    let (lw, lh) = low_size(width, height, scale);
    let (ow, oh) = low_size(width, height, out_scale);
    let depth_at = |x: u32, y: u32| depth[(y * width + x) as usize];
    let mut out = Vec::with_capacity((ow * oh) as usize);
    for oy in 0..oh {
        for ox in 0..ow {
            let (x, y) = source_pixel(ox, oy, out_scale, width, height);
            let Some(z) = depth_at(x, y) else {
                out.push((DVec3::ONE, false));
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
            let (mut lo, mut hi, mut on_surface) = (DVec3::ONE, DVec3::ZERO, 0);
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
                if gap < DEPTH_FALLOFF {
                    on_surface += 1;
                    lo = lo.min(rho);
                    hi = hi.max(rho);
                }
                let w = bilinear * (1.0 - gap / DEPTH_FALLOFF).max(0.0);
                sum += w * rho;
                weight += w;
            }
            let rho = if weight > 1e-6 { sum / weight } else { nearest };
            let refine = spread < 1.0 && (on_surface < 2 || (hi - lo).max_element() > spread);
            out.push((rho, refine));
        }
    }
    out
}

/// The scale of the image the cast shadow at `scale` is brought to next:
/// half of it when the flagged pixels are refined (`refines`), so that
/// each image's blends span half the pixels of the one before and a
/// shadow's edge is refined over a band half as wide; else full
/// resolution at once (halving would only blend more often).
pub fn next_level(scale: u32, refines: bool) -> u32 {
    if refines {
        (scale / 2).max(1)
    } else {
        1
    }
}

/// ρ at full resolution as `CastShadowPass::finish` takes it from `low`
/// (at `scale`): brought to [`next_level`] by [`upsample_level`], the
/// flagged pixels replaced by `exact` at their source pixel (when
/// `spread` < 1), and so on until full resolution.
pub fn refine_levels(
    low: &[DVec3],
    depth: &[Option<f64>],
    (width, height): (u32, u32),
    scale: u32,
    spread: f64,
    exact: impl Fn(u32, u32) -> DVec3,
) -> Vec<DVec3> {
    let refines = spread < 1.0;
    let mut image = low.to_vec();
    let mut scale = scale;
    while scale > 1 {
        let out_scale = next_level(scale, refines);
        let (ow, _) = low_size(width, height, out_scale);
        image = upsample_level(&image, depth, (width, height), scale, out_scale, spread)
            .into_iter()
            .enumerate()
            .map(|(i, (rho, flag))| {
                let (ox, oy) = (i as u32 % ow, i as u32 / ow);
                let (x, y) = source_pixel(ox, oy, out_scale, width, height);
                if flag {
                    exact(x, y)
                } else {
                    rho
                }
            })
            .collect();
        scale = out_scale;
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The automatic scale keeps the low image within `AUTO_LOW_SIZE`,
    /// never under 2 nor over the largest; a fixed one stays.
    #[test]
    fn the_automatic_scale_follows_the_image() {
        let auto = CastScale::Auto;
        assert_eq!(auto.at(160, 90), 2);
        assert_eq!(auto.at(320, 180), 2);
        assert_eq!(auto.at(480, 270), 3);
        assert_eq!(auto.at(640, 360), 4);
        assert_eq!(auto.at(641, 360), 5);
        assert_eq!(auto.at(1280, 720), 8);
        assert_eq!(auto.at(360, 640), 8);
        assert_eq!(auto.at(1920, 1080), MAX_CAST_SCALE);
        for (w, h) in [(321, 181), (1000, 700), (2560, 1440)] {
            let s = auto.at(w, h);
            let (lw, lh) = low_size(w, h, s);
            assert!(s == MAX_CAST_SCALE || (lw <= AUTO_LOW_SIZE.0 && lh <= AUTO_LOW_SIZE.1));
            assert!(
                s == 2
                    || low_size(w, h, s - 1).0 > AUTO_LOW_SIZE.0
                    || low_size(w, h, s - 1).1 > AUTO_LOW_SIZE.1
            );
        }
        assert_eq!(CastScale::Fixed(1).at(1280, 720), 1);
        assert!(CastScale::Fixed(1).is_full() && !auto.is_full());
    }

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

    /// Pixels are flagged for refinement where the blocks they blend
    /// disagree by more than the spread or fewer than two lie on their
    /// surface; never where the field is empty, nor at spread ≥ 1; the
    /// values are upsample_shadow's.
    #[test]
    fn refinement_flags_edges_and_silhouettes_only() {
        let (w, h) = (12u32, 8u32);
        let depth: Vec<Option<f64>> = (0..w * h)
            .map(|i| match (i % w, i / w) {
                (0, 0) => None,
                (10, 3) => Some(9.0),
                _ => Some(1.0),
            })
            .collect();
        let (lw, lh) = low_size(w, h, 2);
        // ρ steps from 1 to 0.5 between blocks 2 and 3 (pixels 5 and 6).
        let low: Vec<DVec3> = (0..lw * lh)
            .map(|i| DVec3::splat(if i % lw < 3 { 1.0 } else { 0.5 }))
            .collect();
        let flags = upsample_with_flags(&low, &depth, w, h, 2, 0.02);
        let plain = upsample_shadow(&low, &depth, w, h, 2);
        for (i, ((rho, flag), p)) in flags.iter().zip(&plain).enumerate() {
            assert_eq!(rho, p, "{i}");
            let (x, y) = (i as u32 % w, i as u32 / w);
            let expect = match (x, y) {
                (0, 0) => false,
                // Blends block 2 (ρ 1) with block 3 (ρ 0.5).
                (5 | 6, _) => true,
                // A far pixel among near blocks: none lies on its surface.
                (10, 3) => true,
                _ => false,
            };
            assert_eq!(*flag, expect, "pixel ({x}, {y})");
        }
        assert!(upsample_with_flags(&low, &depth, w, h, 2, 1.0)
            .iter()
            .all(|(_, f)| !f));
    }

    /// Refined a level at a time, a sharp edge and a constant ρ come back
    /// exact at every pixel, with fewer exact points than one step from
    /// the cast scale to full resolution takes; without refinement the
    /// levels are one upsampling.
    #[test]
    fn levels_refine_an_edge_with_fewer_exact_points() {
        use std::cell::Cell;
        let (w, h, scale) = (61u32, 13u32, 8u32);
        let truth = |x: u32, _y: u32| DVec3::splat(if x < 27 { 1.0 } else { 0.3 });
        let depth = vec![Some(2.0); (w * h) as usize];
        let (lw, lh) = low_size(w, h, scale);
        let low: Vec<DVec3> = (0..lw * lh)
            .map(|i| {
                let (x, y) = source_pixel(i % lw, i / lw, scale, w, h);
                truth(x, y)
            })
            .collect();
        let taken = Cell::new(0u32);
        // Counts the points taken exactly.
        let exact = |x, y| {
            taken.set(taken.get() + 1);
            truth(x, y)
        };
        let out = refine_levels(&low, &depth, (w, h), scale, 0.02, exact);
        for (i, r) in out.iter().enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            let off = (*r - truth(x, y)).abs().max_element();
            assert!(off < 1e-12, "({x}, {y}): {r}");
        }
        let one_step = upsample_with_flags(&low, &depth, w, h, scale, 0.02)
            .iter()
            .filter(|(_, f)| *f)
            .count() as u32;
        assert!(
            taken.get() * 3 < one_step * 2,
            "{} exact points against {one_step}",
            taken.get()
        );
        assert_eq!(
            (
                next_level(8, true),
                next_level(3, true),
                next_level(8, false)
            ),
            (4, 1, 1)
        );
        let flat = vec![DVec3::splat(0.6); (lw * lh) as usize];
        let none = |_, _| -> DVec3 { panic!("nothing to refine on a constant ρ") };
        let out = refine_levels(&flat, &depth, (w, h), scale, 0.02, none);
        assert!(out
            .iter()
            .all(|r| (*r - DVec3::splat(0.6)).abs().max_element() < 1e-12));
        let once = refine_levels(&low, &depth, (w, h), scale, 1.0, |_, _| DVec3::ZERO);
        assert_eq!(once, upsample_shadow(&low, &depth, w, h, scale));
    }
}
