//! The field's light at the object's surface (`[shading] field_light`),
//! beyond the paper: its lobes are the light at the object's centre, so a
//! point of the object that the field hides from part of that light (a toy
//! among foliage, the side of an object against a wall) is lit as if it
//! stood at the centre. Against Cycles this was the largest error left on
//! PLANTS' toy (`docs/fidelity.md`).
//!
//! The correction scales each point's diffuse light from the fitted lobes
//! by what the field sends it over what the lobes say it gets, on the same
//! rays: per tile of ([`TILE`] · k)² pixels (k the [`TileScale`], which
//! grows with the image: 1 up to 639 × 359, 4 at 1280 × 720), one of the
//! tile's object pixels that have diffuse light (the nearest to the tile's
//! centre, [`tile_pick`]) casts `side`² rays from its point, lifted off
//! the surface ([`ray_origin`]), along fixed directions spread evenly over
//! the sphere (a Fibonacci lattice).
//! Each ray keeps the field's light, Ĉ + (1 − Ô)·L_env(d), with the broad
//! lobes of L_env beyond the field as the probe adds them and a local
//! light's own colour taken off as the probe takes it off (it is shaded
//! per pixel), and the fitted lobes' L_fit(d) ([`tile_rays`]): at the
//! centre the first is the probe the lobes were fitted to. Every pixel of
//! the tile weighs the rays by its own clamped cosine ([`diffuse_gain`]):
//!
//!   g = Σ_r max(0, n·d_r) (field light)_r / Σ_r max(0, n·d_r) L_fit(d_r),
//!
//! per colour channel. The same rays stand in numerator and denominator,
//! so where the field sends what the lobes say the gain is 1 whatever the
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
/// hold 256 rays).
pub const MAX_SIDE: u32 = 16;

/// The largest gain, a bound and not a model: a field sending more than
/// this many times the lobes' light onto a plane is not an error of the
/// lobes this corrects. (A cap at 1, tried while the rays took the lobes
/// for what lies past the field, cost PLANTS' toy 8–11 % of its
/// brightness once they took L_env: `docs/fidelity.md`, sixteenth pass.)
pub const GAIN_MAX: f64 = 16.0;

/// Pixels a side of a tile at scale 1: the shading pass's 8 × 8
/// workgroup (at scale k each invocation takes k² pixels). At the
/// same rays per workgroup, one tile of 16² rays did better against
/// Cycles than four 4 × 4 tiles of 8² each (PLANTS' toy 0.121 and 0.170
/// against 0.127 and 0.203; `docs/fidelity.md`, sixteenth pass): the
/// rays' count matters more than their origins' spacing.
pub const TILE: u32 = 8;

/// The most pixels a side of a tile, as a multiple of [`TILE`]: a
/// workgroup's 8 × 8 invocations take up to this many squared pixels each.
pub const MAX_TILE_SCALE: u32 = 4;

/// The image at which [`TileScale::Auto`] keeps the tiles of [`TILE`]
/// pixels: there they were measured against Cycles (`inlay fidelity` runs
/// at 320 × 180), and a larger image takes tiles as many times larger as
/// it is, so that the picks stand as far apart on the object.
pub const AUTO_TILE_IMAGE: (u32, u32) = (320, 180);

/// How large the field light's tiles are (`[shading] field_light_scale`):
/// their side is [`TILE`] times the scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileScale {
    /// Tiles of [`TILE`] times this many pixels a side, at any image size.
    Fixed(u32),
    /// The scale grows with the image ([`Self::at`]): the field's light
    /// varies over the object's surface, not over its pixels, and an
    /// object casts about as many rays at 1280 × 720 as at 320 × 180.
    Auto,
}

impl TileScale {
    /// The scale at a `width` × `height` image: the fixed one, or how many
    /// times [`AUTO_TILE_IMAGE`] fits into the image along both axes, from
    /// 1 to [`MAX_TILE_SCALE`].
    pub fn at(self, width: u32, height: u32) -> u32 {
        match self {
            TileScale::Fixed(k) => k,
            TileScale::Auto => (width / AUTO_TILE_IMAGE.0)
                .min(height / AUTO_TILE_IMAGE.1)
                .clamp(1, MAX_TILE_SCALE),
        }
    }
}

/// One ray of a tile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileRay {
    /// Its direction (unit).
    pub dir: DVec3,
    /// The field's light along it, L_env beyond the field.
    pub field: DVec3,
    /// The fitted lobes' radiance along it.
    pub lobes: DVec3,
}

/// The pixel of tile `tile` (in tiles of `side` pixels a side) whose
/// point casts the tile's rays: of the tile's pixels inside the image
/// where `is_object` holds (the shading takes the object's pixels with a
/// diffuse colour: a metal's tiles cast none), the nearest to the tile's
/// centre, the first in row-major order among equals.
pub fn tile_pick(
    tile: (u32, u32),
    side: u32,
    width: u32,
    height: u32,
    is_object: impl Fn(u32, u32) -> bool,
) -> Option<(u32, u32)> {
    let mut best: Option<(u32, (u32, u32))> = None;
    for j in 0..side {
        for i in 0..side {
            let (x, y) = (tile.0 * side + i, tile.1 * side + j);
            if x >= width || y >= height || !is_object(x, y) {
                continue;
            }
            let c = side as i32 - 1;
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

/// The lobes a tile's rays compare: the `fitted` lobes, and the broad
/// lobes of L_env the probe adds past the field (`environment`).
#[derive(Debug, Clone, Copy)]
pub struct RayLight<'a> {
    /// The object's fitted lobes (the direct ones left out).
    pub fitted: &'a [Sg64],
    /// L_env's broad lobes, as the probe adds them.
    pub environment: &'a [Sg64],
}

/// The tile's `side`² rays from `origin` through `field` (marched with
/// `march`), with `light.environment` beyond it and the colour inside
/// each of the active `local` lights taken off, beside `light.fitted`.
pub fn tile_rays(
    field: &dyn RadianceField,
    march: &MarchKnobs,
    origin: DVec3,
    light: RayLight<'_>,
    local: &[LocalLight],
    side: u32,
) -> Vec<TileRay> {
    let count = side.min(MAX_SIDE).pow(2);
    (0..count)
        .map(|r| {
            let dir = fibonacci_axis(r, count);
            let lobes: DVec3 = light.fitted.iter().map(|g| g.eval(dir)).sum();
            let beyond: DVec3 = light.environment.iter().map(|g| g.eval(dir)).sum();
            let m = march_ray(field, &Ray { origin, dir }, f64::INFINITY, march);
            let mut colour = m.colour;
            for light in local.iter().filter(|l| l.active(origin)) {
                colour -= local::inside_colour(field, light, origin, dir, march);
            }
            TileRay {
                dir,
                field: colour.max(DVec3::ZERO) + (1.0 - m.opacity) * beyond,
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
            DVec3::splat(1000.0 * self.glow)
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

    /// The lobes fitted to the probe of a clear field under the sky are the
    /// sky: both terms alike.
    fn rays_with(field: &dyn RadianceField, side: u32) -> Vec<TileRay> {
        let sky = sky();
        let light = RayLight {
            fitted: &sky,
            environment: &sky,
        };
        tile_rays(field, &MarchKnobs::default(), DVec3::ZERO, light, &[], side)
    }

    #[test]
    fn a_clear_field_leaves_the_lobes_alone() {
        let field = Slab {
            roof: false,
            glow: 0.0,
        };
        for side in [1, 4, 8, 16] {
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
    fn past_the_field_the_rays_see_the_environment_not_the_lobes() {
        // A clear field with no environment: the lobes (fitted where the
        // field held light the point no longer sees) light nothing here.
        let sky = sky();
        let light = RayLight {
            fitted: &sky,
            environment: &[],
        };
        let clear = Slab {
            roof: false,
            glow: 0.0,
        };
        let rays = tile_rays(&clear, &MarchKnobs::default(), DVec3::ZERO, light, &[], 8);
        assert_eq!(diffuse_gain(DVec3::Y, &rays), DVec3::ZERO);
    }

    #[test]
    fn the_gain_stops_at_its_bound() {
        // A glowing medium sends far more than the lobes hold: the gain
        // stops at GAIN_MAX, and stays finite (1) with black lobes.
        let field = Slab {
            roof: false,
            glow: 1.0,
        };
        let rays = rays_with(&field, 8);
        assert!(rays
            .iter()
            .all(|r| r.field.min_element() > 2.0 * GAIN_MAX * r.lobes.max_element()));
        assert_eq!(diffuse_gain(DVec3::Z, &rays), DVec3::splat(GAIN_MAX));
        let none = RayLight {
            fitted: &[],
            environment: &[],
        };
        let dark = tile_rays(&field, &MarchKnobs::default(), DVec3::ZERO, none, &[], 8);
        assert_eq!(diffuse_gain(DVec3::Z, &dark), DVec3::ONE);
    }

    #[test]
    fn the_pick_is_the_object_pixel_nearest_the_centre() {
        let all = |_, _| true;
        assert_eq!(tile_pick((0, 0), TILE, 64, 64, all), Some((3, 3)));
        assert_eq!(tile_pick((2, 1), TILE, 64, 64, all), Some((19, 11)));
        assert_eq!(tile_pick((0, 0), TILE, 64, 64, |x, _| x == 7), Some((7, 3)));
        assert_eq!(tile_pick((0, 0), TILE, 64, 64, |_, _| false), None);
        // Pixels past the image's edge are never picked.
        assert_eq!(tile_pick((0, 0), TILE, 2, 2, all), Some((1, 1)));
        // Tiles of 16: the centre's four pixels tie, the first in rows wins.
        assert_eq!(tile_pick((1, 1), 16, 64, 64, all), Some((23, 23)));
        assert_eq!(
            tile_pick((1, 1), 16, 64, 64, |x, y| x > 23 && y > 23),
            Some((24, 24))
        );
    }

    #[test]
    fn the_automatic_tiles_grow_with_the_image() {
        let auto = TileScale::Auto;
        assert_eq!(auto.at(160, 90), 1);
        assert_eq!(auto.at(320, 180), 1);
        assert_eq!(auto.at(480, 270), 1);
        assert_eq!(auto.at(640, 360), 2);
        assert_eq!(auto.at(1280, 720), 4);
        assert_eq!(auto.at(1280, 200), 1);
        assert_eq!(auto.at(3840, 2160), MAX_TILE_SCALE);
        assert_eq!(TileScale::Fixed(3).at(160, 90), 3);
    }
}
