//! Which bricks a sparse stage of the trainer trains: those around what the
//! stage before made visible. A node of the coarser grid whose rendering
//! weight in some training ray reaches the threshold ([`super::prune`]'s
//! visibility) marks the brick of 8³ nodes of the finer grid that holds
//! its place, and the 26 around it (the finer surface may move by up to a
//! brick as it sharpens). Everything else is held empty: space no
//! photograph sees into, which the dense grid would have pruned at the end.

use glam::{IVec3, UVec3};

use crate::field::bricks::{BrickLayout, BRICK_SIDE};
use crate::field::GridField;

/// The bricks of a grid of `target` nodes over `coarse`'s bounds to train,
/// from `coarse`'s nodes whose `visibility` (one per node) is at least
/// `threshold` (above zero where it is zero).
pub fn stage_bricks(
    coarse: &GridField,
    visibility: &[f32],
    threshold: f64,
    target: UVec3,
) -> BrickLayout {
    let dims = BrickLayout::dims_of(target);
    let mut keep = vec![false; (dims.x * dims.y * dims.z) as usize];
    let r = coarse.resolution;
    let scale = (target - UVec3::ONE).as_dvec3() / (r - UVec3::ONE).as_dvec3();
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                let v = visibility[coarse.index(x, y, z)] as f64;
                if v <= 0.0 || v < threshold {
                    continue;
                }
                let fine = (UVec3::new(x, y, z).as_dvec3() * scale).round().as_ivec3();
                let b = fine / BRICK_SIDE as i32;
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let n = b + IVec3::new(dx, dy, dz);
                            if n.cmpge(IVec3::ZERO).all() && n.cmplt(dims.as_ivec3()).all() {
                                let n = n.as_uvec3();
                                keep[(n.x + dims.x * (n.y + dims.y * n.z)) as usize] = true;
                            }
                        }
                    }
                }
            }
        }
    }
    BrickLayout::from_kept(target, &keep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::DVec3;

    #[test]
    fn a_visible_node_keeps_its_brick_and_the_ones_around() {
        let r = UVec3::new(17, 17, 17);
        let coarse = GridField::new(
            r,
            Aabb::new(DVec3::ZERO, DVec3::ONE),
            vec![[0.0; 4]; (r.x * r.y * r.z) as usize],
            4,
        );
        let mut visibility = vec![0.0f32; coarse.nodes.len()];
        // Node (8, 0, 16): the finer grid's (32, 0, 64), brick (4, 0, 8).
        visibility[coarse.index(8, 0, 16)] = 0.5;
        visibility[coarse.index(1, 1, 1)] = 0.001; // under the threshold
        let layout = stage_bricks(&coarse, &visibility, 0.01, UVec3::splat(65));
        assert_eq!(layout.dims, UVec3::splat(9));
        let kept: Vec<UVec3> = (0..layout.table.len() as u32)
            .filter(|&b| layout.table[b as usize] != crate::field::bricks::EMPTY_BRICK)
            .map(|b| UVec3::new(b % 9, (b / 9) % 9, b / 81))
            .collect();
        // 3 × 2 × 2 around brick (4, 0, 8): y and z clipped at the grid.
        assert_eq!(kept.len(), 12, "{kept:?}");
        assert!(kept
            .iter()
            .all(|b| (3..=5).contains(&b.x) && b.y <= 1 && b.z >= 7));
    }
}
