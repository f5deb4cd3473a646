//! Pruning what no photograph sees. A node's visibility is the largest
//! rendering weight it takes in any training ray: over the ray's samples
//! (the march's quadrature, with skipping of empty space, as the field
//! will be rendered), the sample's weight T·α times the node's trilinear
//! weight at the sample. A node below the threshold lies outside every
//! camera's view, or behind what every camera sees first: nothing in the
//! photographs constrains it, and what the trainer left there (floaters
//! in the space around the scene, haze) is seen only by views the
//! photographs did not have: an estimate's views from around the field,
//! a probe, a cast shadow's rays. Pruning sets its density to zero.

use rayon::prelude::*;

use crate::field::{GridField, DEFAULT_OCCUPANCY_BLOCK};
use crate::geometry::Ray;
use crate::march::{march_samples, MarchKnobs};

/// Each node's largest weight along `ray`, folded into `out` (max).
fn ray_visibility(field: &GridField, ray: &Ray, knobs: &MarchKnobs, out: &mut [f32]) {
    march_samples(field, ray, f64::INFINITY, knobs, |s| {
        if s.weight > 0.0 {
            for (n, wn) in field.corners(s.x).into_iter().flatten() {
                out[n] = out[n].max((s.weight * wn) as f32);
            }
        }
    });
}

/// Every node's visibility over `rays` (unit directions).
pub fn node_visibility(field: &GridField, rays: &[Ray], knobs: &MarchKnobs) -> Vec<f32> {
    let n = field.nodes.len();
    let chunk = rays.len().div_ceil(4 * rayon::current_num_threads()).max(1);
    rays.par_chunks(chunk)
        .map(|rays| {
            let mut out = vec![0.0f32; n];
            for ray in rays {
                ray_visibility(field, ray, knobs, &mut out);
            }
            out
        })
        .reduce(
            || vec![0.0f32; n],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(x, y)| *x = x.max(y));
                a
            },
        )
}

/// `field` with every negative density that no point's density depends on
/// set to zero, and how many: a node below zero with no node above zero
/// among its 26 neighbours (every cell it corners is clamped to zero
/// throughout, [`crate::field::density_at`]). The trainer pushes empty
/// space below zero; zeroed, it is left out of a sparse field's bricks.
pub fn clear_inert_negatives(field: &GridField) -> (GridField, usize) {
    let r = field.resolution;
    let positive = |i: u32, j: u32, k: u32| field.nodes[field.index(i, j, k)][3] > 0.0;
    let near_positive = |i: u32, j: u32, k: u32| {
        let span = |c: u32, n: u32| c.saturating_sub(1)..=(c + 1).min(n - 1);
        span(k, r.z).any(|c| span(j, r.y).any(|b| span(i, r.x).any(|a| positive(a, b, c))))
    };
    let mut nodes = field.nodes.clone();
    let mut cleared = 0;
    for k in 0..r.z {
        for j in 0..r.y {
            for i in 0..r.x {
                let n = field.index(i, j, k);
                if nodes[n][3] < 0.0 && !near_positive(i, j, k) {
                    nodes[n][3] = 0.0;
                    cleared += 1;
                }
            }
        }
    }
    let out = GridField::new(r, field.bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
        .with_sh(field.sh_degree, field.sh.clone());
    (out, cleared)
}

/// `field` with the density of every node whose visibility is below
/// `threshold` set to zero (occupancy rebuilt), and how many nodes that
/// took density from.
pub fn prune(field: &GridField, visibility: &[f32], threshold: f64) -> (GridField, usize) {
    let mut nodes = field.nodes.clone();
    let mut pruned = 0;
    for (node, v) in nodes.iter_mut().zip(visibility) {
        if (*v as f64) < threshold && node[3] > 0.0 {
            node[3] = 0.0;
            pruned += 1;
        }
    }
    let out = GridField::new(
        field.resolution,
        field.bounds,
        nodes,
        DEFAULT_OCCUPANCY_BLOCK,
    )
    .with_sh(field.sh_degree, field.sh.clone());
    (out, pruned)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::{DVec3, UVec3};

    /// A slab the cameras see, a blob outside every ray and a blob behind
    /// the slab: both blobs are pruned, the slab's front is kept, and the
    /// training rays' pixels hardly change.
    #[test]
    fn what_no_ray_sees_is_pruned_and_the_rays_do_not_change() {
        let res = UVec3::new(17, 17, 17);
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let h = 2.0 / 16.0;
        let at = |i: u32| -1.0 + i as f64 * h;
        let mut nodes = Vec::new();
        for k in 0..17 {
            for j in 0..17 {
                for i in 0..17 {
                    let (x, y, z) = (at(i), at(j), at(k));
                    let slab = z.abs() < 0.15 && x.abs() < 0.6 && y.abs() < 0.6;
                    let outside =
                        (DVec3::new(x, y, z) - DVec3::new(0.85, 0.0, -0.6)).length() < 0.15;
                    let behind = (DVec3::new(x, y, z) - DVec3::new(0.0, 0.0, 0.7)).length() < 0.2;
                    let sigma = if slab {
                        40.0
                    } else if outside || behind {
                        10.0
                    } else {
                        0.0
                    };
                    nodes.push([0.5, 0.4, 0.3, sigma]);
                }
            }
        }
        let field = GridField::new(res, bounds, nodes, 2);
        // Parallel rays along +z over |x|, |y| < 0.5.
        let rays: Vec<Ray> = (0..21)
            .flat_map(|a| (0..21).map(move |b| (a, b)))
            .map(|(a, b)| Ray {
                origin: DVec3::new(-0.5 + a as f64 * 0.05, -0.5 + b as f64 * 0.05, -3.0),
                dir: DVec3::Z,
            })
            .collect();
        let knobs = MarchKnobs {
            samples_per_ray: 256,
            termination: 1e-4,
            skip_empty: true,
        };
        let vis = node_visibility(&field, &rays, &knobs);
        let (pruned, count) = prune(&field, &vis, 0.01);
        let density = |f: &GridField, x: DVec3| {
            let n = ((x - bounds.min) / h).round().as_uvec3();
            f.nodes[f.index(n.x, n.y, n.z)][3]
        };
        assert_eq!(density(&pruned, DVec3::new(0.875, 0.0, -0.625)), 0.0);
        assert_eq!(density(&pruned, DVec3::new(0.0, 0.0, 0.75)), 0.0);
        assert!(density(&pruned, DVec3::new(0.0, 0.0, -0.125)) > 0.0);
        assert!(density(&field, DVec3::new(0.875, 0.0, -0.625)) > 0.0);
        assert!(count > 10, "{count}");
        for ray in &rays {
            let a = crate::march::march_ray(&field, ray, f64::INFINITY, &knobs);
            let b = crate::march::march_ray(&pruned, ray, f64::INFINITY, &knobs);
            assert!(
                (a.colour - b.colour).abs().max_element() < 0.01,
                "{} vs {}",
                a.colour,
                b.colour
            );
        }
    }

    /// A random field with negative densities: the negatives far from any
    /// positive node are zeroed, the others kept, and the density at every
    /// point read is unchanged.
    #[test]
    fn clearing_inert_negatives_changes_no_density() {
        let res = UVec3::new(9, 8, 7);
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::new(1.0, 0.9, 0.8));
        let mut rng = crate::rng::Pcg32::new(4, 1);
        let nodes: Vec<[f32; 4]> = (0..res.x * res.y * res.z)
            .map(|_| {
                let r = rng.next_f64();
                // One in twenty above zero: most negatives have a
                // positive neighbour, some do not.
                let sigma = if r < 0.05 { 3.0 * r / 0.05 } else { -r };
                [0.2, 0.3, 0.4, sigma as f32]
            })
            .collect();
        let field = GridField::new(res, bounds, nodes, 2);
        let (cleared, count) = clear_inert_negatives(&field);
        let kept_negative = cleared.nodes.iter().filter(|n| n[3] < 0.0).count();
        assert!(count > 0 && kept_negative > 0, "{count} {kept_negative}");
        let mut rng = crate::rng::Pcg32::new(5, 1);
        for _ in 0..20_000 {
            let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let x = bounds.min + u * bounds.size();
            use crate::field::RadianceField;
            assert_eq!(field.density(x), cleared.density(x), "{x}");
        }
    }
}
