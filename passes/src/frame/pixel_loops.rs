//! The loops one pixel's invocation of the object's shading and of its
//! cast shadow runs for the direct lobes (the sharp lobes of L_env and the
//! local lights, each seen along its own rays) and for the field light's
//! rays, checked against the device's loop limit when the frame is built
//! ([`crate::march::loop_budget`]). These kernels take one pixel per
//! invocation and cannot split its rays, so knobs whose rays would pass
//! the limit are refused, naming them, rather than cut short silently.
//! The counts are lower bounds where a ray meets the object's mesh (its
//! traversal of the mesh's hierarchy is counted as one step) and upper
//! ones along the field (a march across its whole diagonal).

use crate::lighting::DirectRayCounts;
use crate::march::MarchKnobs;

/// Invocations of the shading's workgroup, which share the field light's
/// rays (`shaders/shade/field_light.wgsl`).
const SHADE_GROUP: u64 = 64;

/// Loops per pixel of the object's shading: each sharp lobe's rays through
/// the mesh, each local light's rays through the mesh and along the field
/// to it, and the pixel's share of the field light's `field_side`² rays
/// (each a march, two more per local light inside whose sphere it
/// starts, and the `fitted` and `env_lobes` lobes along it), with the gain
/// pass's pick and sums over the rays at each of the pixels an invocation
/// takes (at most [`MAX_TILE_SCALE`](crate::shade::field_light::MAX_TILE_SCALE)²).
pub fn shade_loop_iterations(
    rays: &DirectRayCounts,
    march: &MarchKnobs,
    field_side: u32,
    fitted: u32,
    env_lobes: u32,
) -> u64 {
    let m = march.loop_iterations();
    let sharp = rays.sharp as u64 * (rays.side as u64).pow(2) * 2;
    let local = rays.local as u64 * (rays.local_side as u64).pow(2) * (2 + m);
    let side = field_side.min(crate::shade::field_light::MAX_SIDE) as u64;
    let field_rays = (side * side).div_ceil(SHADE_GROUP);
    let per_field_ray = m * (1 + 2 * rays.local as u64) + (rays.local + fitted + env_lobes) as u64;
    let tile_pixels = (crate::shade::field_light::MAX_TILE_SCALE as u64).pow(2);
    let gain_sums = if side > 0 {
        tile_pixels * (side * side + 1)
    } else {
        0
    };
    sharp + local + field_rays * per_field_ray + gain_sums
}

/// Loops per pixel of the cast shadow for the direct lobes: each sharp
/// lobe's rays through the mesh, and each local light's arrival (its rays'
/// side over the disk, one march to it) and its rays through the mesh.
pub fn cast_loop_iterations(rays: &DirectRayCounts, march: &MarchKnobs) -> u64 {
    let sharp = rays.sharp as u64 * (rays.side as u64).pow(2) * 2;
    let local_rays = (rays.local_side as u64).pow(2);
    let local = rays.local as u64 * (3 * local_rays + march.loop_iterations());
    sharp + local
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(sharp: u32, side: u32, local: u32, local_side: u32) -> DirectRayCounts {
        DirectRayCounts {
            sharp,
            side,
            local,
            local_side,
        }
    }

    #[test]
    fn the_bundled_knobs_stay_well_under_llvmpipes_limit() {
        // The most a bundled scene takes: one sharp lobe at 6 × 6 rays,
        // two local lights at 2 × 2, the field light at 16 × 16, 512
        // samples per ray, 32 lobes.
        let march = MarchKnobs::default();
        let c = counts(1, 6, 2, 2);
        let shade = shade_loop_iterations(&c, &march, 16, 32, 8);
        assert!(shade < 20_000, "{shade}");
        assert!(cast_loop_iterations(&c, &march) < 5_000);
    }

    #[test]
    fn eight_local_lights_of_eight_by_eight_rays_are_over_it() {
        let march = MarchKnobs::default();
        let c = counts(0, 6, 8, 8);
        // 8 lights × 64 rays × (513 + 2): a quarter of a million.
        assert_eq!(shade_loop_iterations(&c, &march, 0, 32, 0), 8 * 64 * 515);
        assert!(shade_loop_iterations(&c, &march, 0, 32, 0) > inlay_engine::LLVMPIPE_LOOP_LIMIT);
    }
}
