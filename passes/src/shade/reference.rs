//! The brute-force reference of the object's shading: the exact BRDF (not
//! its SG form) integrated against the probe's full incident light, the
//! probe taken as constant over each texel and each texel integrated on an
//! S × S grid of sub-texel directions.

use glam::DVec3;

use crate::brdf::{disney, SurfaceMaterial};
use crate::probe::DirectionMap;
use crate::sgfit::texel_valid;

/// ∫ L(ω) f_r(ω, v) (ω·n) dω over the probe `texels` laid out by `map`
/// (invalid texels count as black), with `subdivisions`² directions per
/// texel. Choose the subdivisions so that the sub-texel spacing resolves
/// the specular lobe (4 × 4 is plenty for rough materials at 32², glossy
/// ones need 8 × 8 or more).
pub fn shade_probe_reference(
    map: &DirectionMap,
    texels: &[[f64; 4]],
    n: DVec3,
    v: DVec3,
    m: &SurfaceMaterial,
    subdivisions: u32,
) -> DVec3 {
    shade_reference_with(map, n, v, m, subdivisions, |texel, _| {
        let t = &texels[texel];
        if texel_valid(t) {
            DVec3::new(t[0], t[1], t[2])
        } else {
            DVec3::ZERO
        }
    })
}

/// The same integral for any incident radiance `light(texel, direction)`
/// evaluated at every sub-texel direction (e.g. SG lobes, which vary within
/// a texel), on the same directions and weights as
/// [`shade_probe_reference`].
pub fn shade_reference_with(
    map: &DirectionMap,
    n: DVec3,
    v: DVec3,
    m: &SurfaceMaterial,
    subdivisions: u32,
    light: impl Fn(usize, DVec3) -> DVec3,
) -> DVec3 {
    let m = m.clamped();
    let s = subdivisions.max(1);
    let da_per_density = 1.0 / (map.texels() as f64 * (s * s) as f64);
    let mut sum = DVec3::ZERO;
    for y in 0..map.height {
        for x in 0..map.width {
            let texel = (y * map.width + x) as usize;
            for j in 0..s {
                for i in 0..s {
                    let u = (x as f64 + (i as f64 + 0.5) / s as f64) / map.width as f64;
                    let w = (y as f64 + (j as f64 + 0.5) / s as f64) / map.height as f64;
                    let (dir, density) = map.direction_and_density(u, w);
                    let cos = n.dot(dir);
                    if cos > 0.0 {
                        let l = light(texel, dir);
                        if l != DVec3::ZERO {
                            sum +=
                                l * disney::eval(&m, n, v, dir) * (cos * density * da_per_density);
                        }
                    }
                }
            }
        }
    }
    sum
}
