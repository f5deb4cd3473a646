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
//! centre the first is the probe the lobes were fitted to. A point of
//! normal n weighs the rays by its clamped cosine ([`diffuse_gain`]):
//!
//!   g = Σ_r max(0, n·d_r) (field light)_r / Σ_r max(0, n·d_r) L_fit(d_r),
//!
//! per colour channel. The same rays stand in numerator and denominator,
//! so where the field sends what the lobes say the gain is 1 whatever the
//! rays' count, and their quadrature error largely cancels. The specular
//! term, the direct lobes (sharp lights outside the field, ray-cast) and
//! the local lights are left as they are: they already see from the point.
//!
//! The two sums are kept per tile at the [`TABLE_SIDE`]² normals of an
//! octahedral map ([`tile_table`]), and a pixel blends the sums of the four
//! tiles whose centres surround it, read at its own normal
//! ([`blended_gain`]): bilinear in the image, each tile weighed down where
//! its pick lies off the pixel's tangent plane ([`plane_weight`]). A tile's
//! pick stands for its whole tile, so without the blend the gain steps at
//! the tiles' edges, in blocks as large as the tiles (8 pixels at
//! 320 × 180, 32 at 1280 × 720; `docs/benchmarks.md`, issue 26's fifteenth
//! pass). Mirrored by `shaders/shade/field_light.wgsl`.

use glam::DVec3;

use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::lighting::{local, LocalLight};
use crate::march::{march_ray, MarchKnobs};
use crate::probe::{octahedral_bilinear, DirectionMap, MapKind};
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

/// Normals a side of a tile's table: the sums are kept at the texel
/// centres of a `TABLE_SIDE` × `TABLE_SIDE` octahedral map of normals
/// (one per invocation of the gain pass's 8 × 8 workgroup) and read
/// bilinearly between them.
pub const TABLE_SIDE: u32 = 16;

/// The vec4s one tile's table takes in the GPU's buffer: its pick's point
/// (w 1, or all 0 where the tile picked none), then at each normal the
/// field's sum and the lobes' sum ([`TileTable`]).
pub const TABLE_STRIDE: u32 = 1 + 2 * TABLE_SIDE * TABLE_SIDE;

/// The least weight a tile with a pick keeps in the blend, however far its
/// pick lies off the pixel's tangent plane ([`plane_weight`]): so that a
/// pixel whose four picks all lie on other parts still takes their light,
/// bilinearly, rather than none.
pub const PLANE_WEIGHT_MIN: f64 = 1e-4;

/// The least tile footprint [`plane_weight`] divides by, so that its
/// weight is defined (and at most 1) for any point (the shader takes f32's
/// least normal number).
pub const FOOTPRINT_MIN: f64 = 1e-30;

/// One tile's light as a pixel reads it: where its rays start, and their
/// two sums at each normal of its table.
#[derive(Debug, Clone, PartialEq)]
pub struct TileTable {
    /// The picked surface point (before the lift off the surface).
    pub pick: DVec3,
    /// Σ_r max(0, n·d_r) (field light)_r at each normal, row by row.
    pub field: Vec<DVec3>,
    /// Σ_r max(0, n·d_r) L_fit(d_r) at each normal.
    pub lobes: Vec<DVec3>,
}

/// The normal of entry `j` of a tile's table: the centre of texel
/// (j mod [`TABLE_SIDE`], j div [`TABLE_SIDE`]) of the octahedral map.
pub fn table_normal(j: u32) -> DVec3 {
    DirectionMap::new(MapKind::Octahedral, TABLE_SIDE).direction(j % TABLE_SIDE, j / TABLE_SIDE)
}

/// The table of the tile whose surface point `pick` cast `rays`.
pub fn tile_table(pick: DVec3, rays: &[TileRay]) -> TileTable {
    let (field, lobes) = (0..TABLE_SIDE * TABLE_SIDE)
        .map(|j| ray_sums(table_normal(j), rays))
        .unzip();
    TileTable { pick, field, lobes }
}

impl TileTable {
    /// The two sums at unit normal `n`, bilinear between the table's four
    /// nearest normals.
    pub fn sums(&self, n: DVec3) -> (DVec3, DVec3) {
        let read = |values: &[DVec3]| {
            let channel = |c: usize| octahedral_bilinear(TABLE_SIDE, n, |i| values[i][c]);
            DVec3::new(channel(0), channel(1), channel(2))
        };
        (read(&self.field), read(&self.lobes))
    }
}

/// A tile's weight in a pixel's blend beside its bilinear one: 1 where its
/// pick lies on the tangent plane of the pixel's point `x` (unit normal
/// `n`), falling as exp(−(h / `footprint`)²) with the pick's height h off
/// it (`footprint`: a tile's width on the surface there), never under
/// [`PLANE_WEIGHT_MIN`]. A pick on another part of the object (a cap over
/// a stem, an ear before a head) then lends the pixel little of its light.
/// A footprint of 0 (a point at the eye) counts as [`FOOTPRINT_MIN`].
pub fn plane_weight(x: DVec3, n: DVec3, pick: DVec3, footprint: f64) -> f64 {
    let h = n.dot(pick - x) / footprint.max(FOOTPRINT_MIN);
    (-h * h).exp().max(PLANE_WEIGHT_MIN)
}

/// A tile's width at the surface point `x` seen through pixel centre
/// `centre` from a camera at `eye`: the distance to x times the chord
/// between the unit rays through `centre` and `tile` pixels to its right
/// (`ray_dir` gives the unit ray through an image position).
pub fn tile_footprint(
    eye: DVec3,
    x: DVec3,
    centre: (f64, f64),
    tile: u32,
    ray_dir: impl Fn(f64, f64) -> DVec3,
) -> f64 {
    let chord = (ray_dir(centre.0 + tile as f64, centre.1) - ray_dir(centre.0, centre.1)).length();
    (x - eye).length() * chord
}

/// The four tiles (of `side` pixels) whose centres surround the centre of
/// pixel `pixel`, with their bilinear weights (which sum to 1); tiles
/// before the image's first have negative indices.
pub fn blend_tiles(pixel: (u32, u32), side: u32) -> [((i64, i64), f64); 4] {
    let at = |p: u32| (p as f64 + 0.5) / side as f64 - 0.5;
    let (u, v) = (at(pixel.0), at(pixel.1));
    let (tx, ty) = (u.floor(), v.floor());
    let (fx, fy) = (u - tx, v - ty);
    let (tx, ty) = (tx as i64, ty as i64);
    [
        ((tx, ty), (1.0 - fx) * (1.0 - fy)),
        ((tx + 1, ty), fx * (1.0 - fy)),
        ((tx, ty + 1), (1.0 - fx) * fy),
        ((tx + 1, ty + 1), fx * fy),
    ]
}

/// The gain at a pixel of unit normal `n` and surface point `x` (a tile
/// `footprint` wide there) from the tables of the tiles around it, each
/// with its bilinear weight ([`blend_tiles`]; tiles that picked no pixel
/// left out): both sums blended with the tiles' weights times their
/// [`plane_weight`], then divided ([`gain_of_sums`]). 1 where no tile
/// around the pixel picked one.
pub fn blended_gain<'a>(
    n: DVec3,
    x: DVec3,
    footprint: f64,
    tiles: impl IntoIterator<Item = (&'a TileTable, f64)>,
) -> DVec3 {
    let (mut field, mut lobes) = (DVec3::ZERO, DVec3::ZERO);
    for (table, bilinear) in tiles {
        let w = bilinear * plane_weight(x, n, table.pick, footprint);
        let (f, l) = table.sums(n);
        field += w * f;
        lobes += w * l;
    }
    gain_of_sums(field, lobes)
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
/// `n` from one tile's `rays` alone, exactly, per channel, in [0, GAIN_MAX]
/// (1 in a channel the lobes leave dark on its plane): what a tile's table
/// holds at its normals ([`tile_table`]) and reads between them.
pub fn diffuse_gain(n: DVec3, rays: &[TileRay]) -> DVec3 {
    let (field, lobes) = ray_sums(n, rays);
    gain_of_sums(field, lobes)
}

/// The rays' field light and lobes' light, each weighed by its clamped
/// cosine to unit normal `n`.
pub fn ray_sums(n: DVec3, rays: &[TileRay]) -> (DVec3, DVec3) {
    let (mut field, mut lobes) = (DVec3::ZERO, DVec3::ZERO);
    for r in rays {
        let w = n.dot(r.dir).max(0.0);
        field += w * r.field;
        lobes += w * r.lobes;
    }
    (field, lobes)
}

/// The gain of a field sum over a lobes' sum, per channel, in
/// [0, [`GAIN_MAX`]] (1 in a channel the lobes leave dark).
pub fn gain_of_sums(field: DVec3, lobes: DVec3) -> DVec3 {
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

    /// The field without glow, with the black roof or clear.
    fn dark(roof: bool) -> Slab {
        Slab { roof, glow: 0.0 }
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
        let field = dark(false);
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
        let rays = rays_with(&dark(true), 8);
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
        let clear = dark(false);
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

    /// Unit normals spread over the sphere, none on the table's.
    fn normals() -> Vec<DVec3> {
        (0..500).map(|i| fibonacci_axis(i, 500)).collect()
    }

    #[test]
    fn the_table_holds_the_rays_sums_and_reads_between_them() {
        // Under the roof the light comes from below the slab and from the
        // sky's sides: the gain swings from 0.1 to 1 over the normals.
        let rays = rays_with(&dark(true), 16);
        let table = tile_table(DVec3::ZERO, &rays);
        for j in 0..TABLE_SIDE * TABLE_SIDE {
            let n = table_normal(j);
            let (f, l) = table.sums(n);
            let (rf, rl) = ray_sums(n, &rays);
            assert!((f - rf).abs().max_element() < 1e-9 * rf.max_element().max(1.0));
            assert!((l - rl).abs().max_element() < 1e-9 * rl.max_element().max(1.0));
        }
        // The gain's error, and the light's (the gain's times the lobes'
        // light on the plane, over its most on any plane).
        let all = normals();
        let brightest = all
            .iter()
            .map(|&n| ray_sums(n, &rays).1.max_element())
            .fold(0.0, f64::max);
        let (mut worst, mut sum, mut worst_light, mut sum_light) = (0.0f64, 0.0, 0.0f64, 0.0);
        for &n in &all {
            let (f, l) = table.sums(n);
            let exact = diffuse_gain(n, &rays);
            let err = (gain_of_sums(f, l) - exact).abs();
            let light = (err * ray_sums(n, &rays).1 / brightest).max_element();
            worst = worst.max(err.max_element());
            sum += err.max_element();
            worst_light = worst_light.max(light);
            sum_light += light;
        }
        let (mean, mean_light) = (sum / all.len() as f64, sum_light / all.len() as f64);
        eprintln!("table of {TABLE_SIDE}²: gain off the rays' by {mean:.4} on average, {worst:.4} at worst; light {mean_light:.4}, {worst_light:.4}");
        // Measured: 0.0072 and 0.060 for the gain, 0.0023 and 0.021 for the light.
        assert!(mean < 0.01 && worst < 0.08, "{mean} {worst}");
        assert!(
            mean_light < 0.004 && worst_light < 0.03,
            "{mean_light} {worst_light}"
        );
    }

    #[test]
    fn a_blend_of_like_tiles_is_their_own_gain() {
        let rays = rays_with(&dark(true), 8);
        let table = tile_table(DVec3::ZERO, &rays);
        for pixel in [(0, 0), (3, 4), (13, 2), (100, 37)] {
            let tiles = blend_tiles(pixel, 8);
            let total: f64 = tiles.iter().map(|t| t.1).sum();
            assert!((total - 1.0).abs() < 1e-12);
            for n in [DVec3::Y, DVec3::X, DVec3::new(0.3, -0.5, 0.8).normalize()] {
                // Picks off the plane move nothing when all four are alike.
                let blended =
                    blended_gain(n, DVec3::ZERO, 0.1, tiles.iter().map(|&(_, w)| (&table, w)));
                let (f, l) = table.sums(n);
                assert!((blended - gain_of_sums(f, l)).abs().max_element() < 1e-12);
            }
        }
        // A pixel's tiles: the one it lies in and the three towards the
        // nearest corner between tile centres.
        let t = blend_tiles((9, 14), 8);
        assert_eq!(t.map(|x| x.0), [(0, 1), (1, 1), (0, 2), (1, 2)]);
        assert!((t[0].1 - 0.3125 * 0.6875).abs() < 1e-12);
        assert!((t[3].1 - 0.6875 * 0.3125).abs() < 1e-12);
        assert_eq!(blend_tiles((0, 0), 8)[0].0, (-1, -1));
        // No tile picked a pixel: the gain is 1.
        assert_eq!(blended_gain(DVec3::Y, DVec3::ZERO, 1.0, []), DVec3::ONE);
    }

    #[test]
    fn the_gain_crosses_the_tiles_edges_without_a_step() {
        // Two tiles side by side, one under the roof and one in the open:
        // along a row of pixels across their common edge, the blend moves
        // by at most its share of the difference at each pixel, where each
        // tile's own gain steps by all of it.
        let roofed = rays_with(&dark(true), 8);
        let open = rays_with(&dark(false), 8);
        let (a, b) = (
            tile_table(DVec3::ZERO, &roofed),
            tile_table(DVec3::ZERO, &open),
        );
        let n = DVec3::Y;
        let step = (gain_of_sums(b.sums(n).0, b.sums(n).1)
            - gain_of_sums(a.sums(n).0, a.sums(n).1))
        .abs()
        .max_element();
        assert!(step > 0.8, "{step}");
        let gain = |x: u32| {
            let tiles = blend_tiles((x, 4), 8);
            let pick = |t: (i64, i64)| if t.0 <= 0 { &a } else { &b };
            blended_gain(
                n,
                DVec3::ZERO,
                1.0,
                tiles.iter().map(|&(t, w)| (pick(t), w)),
            )
        };
        let mut largest = 0.0f64;
        for x in 0..15 {
            largest = largest.max((gain(x + 1) - gain(x)).abs().max_element());
        }
        assert!(largest < step / 4.0, "{largest} of {step}");
        // A pick a few footprints off the plane lends almost nothing.
        let lifted = TileTable {
            pick: DVec3::new(0.0, 3.0, 0.0),
            ..b.clone()
        };
        let g = blended_gain(n, DVec3::ZERO, 1.0, [(&a, 0.5), (&lifted, 0.5)]);
        let own = gain_of_sums(a.sums(n).0, a.sums(n).1);
        assert!((g - own).abs().max_element() < 1e-3 * step, "{g} {own}");
        assert_eq!(
            plane_weight(DVec3::ZERO, n, DVec3::new(5.0, 0.0, 2.0), 0.1),
            1.0
        );
        assert_eq!(
            plane_weight(DVec3::ZERO, n, DVec3::Y, 0.01),
            PLANE_WEIGHT_MIN
        );
        // At the extremes the weight stays defined: a footprint of 0 with
        // the pick on the plane or off it, an infinite one, a pick far off.
        assert_eq!(plane_weight(DVec3::ZERO, n, DVec3::X, 0.0), 1.0);
        assert_eq!(
            plane_weight(DVec3::ZERO, n, DVec3::Y, 0.0),
            PLANE_WEIGHT_MIN
        );
        assert_eq!(plane_weight(DVec3::ZERO, n, DVec3::Y, f64::INFINITY), 1.0);
        assert_eq!(
            plane_weight(DVec3::ZERO, n, DVec3::Y * 1e300, 1e-300),
            PLANE_WEIGHT_MIN
        );
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
