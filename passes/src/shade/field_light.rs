//! The field's light at the object's surface (`[shading] field_light`),
//! beyond the paper: its lobes are the light at the object's centre, so a
//! point of the object that the field hides from part of that light (a toy
//! among foliage, the side of an object against a wall) is lit as if it
//! stood at the centre. Against Cycles this was the largest error left on
//! PLANTS' toy (`docs/fidelity.md`).
//!
//! The correction scales each point's diffuse light from the fitted lobes
//! by what the field sends it over what the lobes say it gets, on the same
//! rays: per tile of [`TILE`]² pixels of the shading pass, one of the
//! tile's object pixels that have diffuse light (the nearest to the tile's
//! centre, [`tile_pick`]) casts `side`²
//! rays from its point, lifted off the surface ([`ray_origin`]), along
//! fixed directions spread evenly over the sphere (a Fibonacci lattice).
//! Each ray keeps the field's light, Ĉ + (1 − Ô)·L_fit(d), with the fitted
//! lobes standing for what lies beyond the field and a local light's own
//! colour taken off as the probe takes it off (it is shaded per pixel), and
//! the lobes' L_fit(d) ([`tile_rays`]). Every pixel of the tile weighs the
//! rays by its own clamped cosine ([`diffuse_gain`]):
//!
//!   g = Σ_r max(0, n·d_r) (field light)_r / Σ_r max(0, n·d_r) L_fit(d_r),
//!
//! per colour channel, at most 1 ([`GAIN_MAX`] says why). The same rays
//! stand in numerator and denominator, so
//! where the field sends what the lobes say the gain is 1 whatever the
//! rays' count, and their quadrature error largely cancels. The specular
//! term, the direct lobes (sharp lights outside the field, ray-cast) and
//! the local lights are left as they are: they already see from the point.
//! Mirrored by `shaders/shade/field_light.wgsl`.

use glam::DVec3;

use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::lighting::{local, LocalLight};
use crate::march::{march_ray, MarchKnobs};
use crate::sg::Sg64;
use crate::sgfit::model::fibonacci_axis;
use crate::shadow::DIRECT_RAY_OFFSET;

/// The largest side of the rays per tile (the shader's workgroup arrays
/// hold 256 rays, for the 4 tiles of its 8 × 8 workgroup).
pub const MAX_SIDE: u32 = 8;

/// The largest gain: the correction only takes light away. The lobes
/// already hold what the field sends the object's centre; what they cannot
/// know is what the field hides from a point of its surface. A point may
/// also see more than the centre (nearer a bright wall), but with a few
/// dozen directions shared by a tile, a gain above 1 was mostly a small
/// bright patch of the field one ray hit and the smooth lobes spread:
/// against Cycles, uncapped gains (up to 16) took PLANTS' toy's median
/// error to 0.147 and 0.265 but ROOM's from 0.104 to 0.107 and CUPS' side
/// view's to 0.125, the toy 8 % too bright, and were unstable in the
/// rays' count (6² rays: 0.166 and 0.293); capped at 1, 0.142 and 0.266,
/// ROOM 0.103, CUPS 0.121, improving steadily with the rays (4², 6², 8²:
/// 0.169, 0.154, 0.142 on the front view).
pub const GAIN_MAX: f64 = 1.0;

/// Pixels a side of a tile. Against Cycles on PLANTS' toy, 8 × 8 tiles
/// (one pick per workgroup) left its median error at 0.157 where the
/// point's own rays give 0.135 and 4 × 4 tiles 0.147 (`docs/fidelity.md`).
pub const TILE: u32 = 4;

/// One ray of a tile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileRay {
    /// Its direction (unit).
    pub dir: DVec3,
    /// The field's light along it, the lobes beyond the field.
    pub field: DVec3,
    /// The fitted lobes' radiance along it.
    pub lobes: DVec3,
}

/// The pixel of tile `tile` (in tiles) whose point casts the tile's rays:
/// of the tile's pixels inside the image where `is_object` holds (the
/// shading takes the object's pixels with a diffuse colour: a metal's
/// tiles cast none), the nearest to the tile's centre, the first in
/// row-major order among equals.
pub fn tile_pick(
    tile: (u32, u32),
    width: u32,
    height: u32,
    is_object: impl Fn(u32, u32) -> bool,
) -> Option<(u32, u32)> {
    let mut best: Option<(u32, (u32, u32))> = None;
    for j in 0..TILE {
        for i in 0..TILE {
            let (x, y) = (tile.0 * TILE + i, tile.1 * TILE + j);
            if x >= width || y >= height || !is_object(x, y) {
                continue;
            }
            let c = TILE as i32 - 1;
            let (ox, oy) = (2 * i as i32 - c, 2 * j as i32 - c);
            let key = (ox * ox + oy * oy) as u32;
            if best.is_none_or(|(k, _)| key < k) {
                best = Some((key, (x, y)));
            }
        }
    }
    best.map(|(_, p)| p)
}

/// Where the rays of a surface point `x` with unit normal `n` start, for
/// an object of bounding radius `radius`: lifted along the normal as the
/// direct lobes' shadow rays are.
pub fn ray_origin(x: DVec3, n: DVec3, radius: f64) -> DVec3 {
    x + n * (DIRECT_RAY_OFFSET * radius)
}

/// The tile's `side`² rays from `origin` through `field` (marched with
/// `march`), with the `fitted` lobes beyond it and the colour inside each
/// of the active `local` lights taken off.
pub fn tile_rays(
    field: &dyn RadianceField,
    march: &MarchKnobs,
    origin: DVec3,
    fitted: &[Sg64],
    local: &[LocalLight],
    side: u32,
) -> Vec<TileRay> {
    let count = side.min(MAX_SIDE).pow(2);
    (0..count)
        .map(|r| {
            let dir = fibonacci_axis(r, count);
            let lobes: DVec3 = fitted.iter().map(|g| g.eval(dir)).sum();
            let m = march_ray(field, &Ray { origin, dir }, f64::INFINITY, march);
            let mut colour = m.colour;
            for light in local.iter().filter(|l| l.active(origin)) {
                colour -= local::inside_colour(field, light, origin, dir, march);
            }
            TileRay {
                dir,
                field: colour.max(DVec3::ZERO) + (1.0 - m.opacity) * lobes,
                lobes,
            }
        })
        .collect()
}

/// The gain on the fitted lobes' diffuse light at a point of unit normal
/// `n` of the tile whose rays are `rays`, per channel, in [0, GAIN_MAX]
/// (1 in a channel the lobes leave dark on its plane).
pub fn diffuse_gain(n: DVec3, rays: &[TileRay]) -> DVec3 {
    let (mut field, mut lobes) = (DVec3::ZERO, DVec3::ZERO);
    for r in rays {
        let w = n.dot(r.dir).max(0.0);
        field += w * r.field;
        lobes += w * r.lobes;
    }
    let gain = |f: f64, l: f64| {
        if l > 0.0 {
            (f / l).clamp(0.0, GAIN_MAX)
        } else {
            1.0
        }
    };
    DVec3::new(
        gain(field.x, lobes.x),
        gain(field.y, lobes.y),
        gain(field.z, lobes.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;

    /// A cube of side 2 about the origin, clear but for an optional black
    /// slab y ∈ [0.3, 0.6] of density 10⁴, or glowing throughout.
    struct Slab {
        roof: bool,
        glow: f64,
    }

    impl RadianceField for Slab {
        fn bounds(&self) -> Aabb {
            Aabb {
                min: DVec3::splat(-1.0),
                max: DVec3::splat(1.0),
            }
        }
        fn density(&self, x: DVec3) -> f64 {
            if self.roof && (0.3..=0.6).contains(&x.y) {
                1e4
            } else {
                self.glow
            }
        }
        fn colour(&self, _x: DVec3, _d: DVec3) -> DVec3 {
            DVec3::splat(100.0 * self.glow)
        }
    }

    fn sky() -> Vec<Sg64> {
        vec![
            Sg64 {
                direction: DVec3::Y,
                sharpness: 2.0,
                amplitude: DVec3::new(1.0, 0.8, 0.6),
            },
            Sg64 {
                direction: DVec3::new(0.6, 0.0, 0.8),
                sharpness: 20.0,
                amplitude: DVec3::splat(5.0),
            },
        ]
    }

    fn rays_with(field: &dyn RadianceField, side: u32) -> Vec<TileRay> {
        tile_rays(
            field,
            &MarchKnobs::default(),
            DVec3::ZERO,
            &sky(),
            &[],
            side,
        )
    }

    #[test]
    fn a_clear_field_leaves_the_lobes_alone() {
        let field = Slab {
            roof: false,
            glow: 0.0,
        };
        for side in [1, 4, 8] {
            let rays = rays_with(&field, side);
            assert_eq!(rays.len(), (side * side) as usize);
            for n in [DVec3::Y, DVec3::X, DVec3::new(0.3, -0.5, 0.8).normalize()] {
                let g = diffuse_gain(n, &rays);
                assert!(
                    (g - DVec3::ONE).abs().max_element() < 1e-12,
                    "side {side}: {g}"
                );
            }
        }
    }

    #[test]
    fn a_black_roof_takes_the_sky_away() {
        // Facing the roof the point keeps only what comes in under it (rays
        // below 17–23° of elevation leave the cube's sides first, with a
        // cosine under 0.4); facing away, all of it.
        let rays = rays_with(
            &Slab {
                roof: true,
                glow: 0.0,
            },
            8,
        );
        let up = diffuse_gain(DVec3::Y, &rays);
        let down = diffuse_gain(-DVec3::Y, &rays);
        assert!(up.max_element() < 0.15, "facing the roof: {up}");
        assert!(
            (down - DVec3::ONE).abs().max_element() < 1e-12,
            "facing away: {down}"
        );
        let side = diffuse_gain(DVec3::X, &rays);
        assert!(
            side.min_element() > 0.05 && side.max_element() < 0.95,
            "{side}"
        );
    }

    #[test]
    fn a_field_brighter_than_the_lobes_adds_nothing() {
        // A glowing medium sends far more than the lobes hold: the gain
        // stops at 1 (GAIN_MAX), and stays finite with black lobes.
        let field = Slab {
            roof: false,
            glow: 1.0,
        };
        let rays = rays_with(&field, 8);
        assert!(rays
            .iter()
            .all(|r| r.field.min_element() > 10.0 * r.lobes.max_element()));
        assert_eq!(diffuse_gain(DVec3::Z, &rays), DVec3::ONE);
        let dark = tile_rays(&field, &MarchKnobs::default(), DVec3::ZERO, &[], &[], 8);
        assert_eq!(diffuse_gain(DVec3::Z, &dark), DVec3::ONE);
    }

    #[test]
    fn the_pick_is_the_object_pixel_nearest_the_centre() {
        let all = |_, _| true;
        assert_eq!(tile_pick((0, 0), 64, 64, all), Some((1, 1)));
        assert_eq!(tile_pick((2, 1), 64, 64, all), Some((9, 5)));
        assert_eq!(tile_pick((0, 0), 64, 64, |x, _| x == 3), Some((3, 1)));
        assert_eq!(tile_pick((0, 0), 64, 64, |_, _| false), None);
        // Pixels past the image's edge are never picked.
        assert_eq!(tile_pick((1, 1), 6, 6, all), Some((5, 5)));
    }
}
