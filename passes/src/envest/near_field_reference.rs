//! The f64 CPU mirror of `shaders/envest/near_field.wgsl`: the same rays
//! ([`super::hemisphere`]) marched by the reference march.

use glam::DVec3;

use super::hemisphere::ray_direction;
use super::near_field::{ray_rise, ray_seed, ray_start};
use super::surface::{SurfacePoint, SurfaceTest};
use crate::field::GridField;
use crate::geometry::Ray;
use crate::march::{march_ray, MarchKnobs};
use crate::probe::{DirectionMap, MapKind};

/// E_nerf and the mean Ô of point `index` (its index among the traced
/// points, which seeds its rays) with `rays` rays, risen as `test` has
/// them ([`ray_rise`]).
pub fn irradiance_reference(
    field: &GridField,
    march: &MarchKnobs,
    p: &SurfacePoint,
    test: SurfaceTest,
    index: u32,
    rays: u32,
    seed: u64,
) -> (DVec3, f64) {
    let rise = ray_rise(field, test);
    let seed = ray_seed(seed);
    let mut colour = DVec3::ZERO;
    let mut opacity = 0.0;
    for i in 0..rays {
        let dir = ray_direction(p.normal, index, seed, i, rays);
        let origin = ray_start(p, rise, dir);
        let m = march_ray(field, &Ray { origin, dir }, f64::INFINITY, march);
        colour += m.colour;
        opacity += m.opacity;
    }
    (
        std::f64::consts::PI * colour / rays as f64,
        opacity / rays as f64,
    )
}

/// The opacity map (side² texels) of point `p`, rays risen as `test` has
/// them.
pub fn opacity_map_reference(
    field: &GridField,
    march: &MarchKnobs,
    p: &SurfacePoint,
    test: SurfaceTest,
    side: u32,
) -> Vec<f64> {
    let rise = ray_rise(field, test);
    let map = DirectionMap::new(MapKind::Octahedral, side);
    (0..side * side)
        .map(|t| {
            let dir = map.direction(t % side, t / side);
            let origin = ray_start(p, rise, dir);
            march_ray(field, &Ray { origin, dir }, f64::INFINITY, march).opacity
        })
        .collect()
}
