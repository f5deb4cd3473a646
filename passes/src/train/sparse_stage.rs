//! Which bricks a sparse stage of the trainer trains: those around what the
//! stage before made visible. A node of the coarser grid whose rendering
//! weight in some training ray reaches the threshold ([`super::prune`]'s
//! visibility), and whose density is a surface's, marks the bricks of 8³ nodes of the finer grid that its
//! trilinear reach covers (one coarse cell each way: where the finer
//! surface can sharpen). Everything else is held empty: space no
//! photograph sees into, which the dense grid would have pruned at the end.

use glam::{IVec3, UVec3};

use crate::field::bricks::{brick_index, BrickLayout, BRICK_SIDE};
use crate::field::GridField;

/// The least optical depth per node spacing of a node that marks its
/// bricks: a surface's, not the haze a coarse stage leaves in the air
/// (which its rays see, and which the finer stage would only clear).
pub const MIN_DEPTH: f64 = 0.05;

/// The bricks of a grid of `target` nodes over `coarse`'s bounds to train,
/// from `coarse`'s nodes whose `visibility` (one per node) is at least
/// `threshold` (above zero where it is zero) and whose density is at least
/// [`MIN_DEPTH`] per node spacing.
pub fn stage_bricks(
    coarse: &GridField,
    visibility: &[f32],
    threshold: f64,
    target: UVec3,
) -> BrickLayout {
    let dims = BrickLayout::dims_of(target);
    let mut keep = vec![false; (dims.x * dims.y * dims.z) as usize];
    let r = coarse.resolution;
    let h = coarse.spacing().min_element();
    let scale = (target - UVec3::ONE).as_dvec3() / (r - UVec3::ONE).as_dvec3();
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                let n = coarse.index(x, y, z);
                let v = visibility[n] as f64;
                if v <= 0.0 || v < threshold || (coarse.nodes[n][3] as f64) * h < MIN_DEPTH {
                    continue;
                }
                // The finer nodes the coarse node's trilinear reach
                // covers (one coarse cell each way), and the bricks they lie
                // in.
                let p = UVec3::new(x, y, z).as_dvec3();
                let lo = ((p - 1.0) * scale).floor().as_ivec3().max(IVec3::ZERO);
                let hi = ((p + 1.0) * scale)
                    .ceil()
                    .as_ivec3()
                    .min(target.as_ivec3() - IVec3::ONE);
                let (lo, hi) = (lo / BRICK_SIDE as i32, hi / BRICK_SIDE as i32);
                for bz in lo.z..=hi.z {
                    for by in lo.y..=hi.y {
                        for bx in lo.x..=hi.x {
                            let b = UVec3::new(bx as u32, by as u32, bz as u32);
                            keep[brick_index(dims, b)] = true;
                        }
                    }
                }
            }
        }
    }
    BrickLayout::from_kept(target, &keep)
}

/// The bricks a stage of `target` nodes trains after `before` (the stage
/// before, or a resumed field): [`stage_bricks`], and where `before` is
/// already at `target` (a resumed field) every brick it holds a non-zero
/// value in too ([`BrickLayout::of`]). A resumed field then starts as it
/// was saved: the visibility rule alone dropped the haze and faint colour
/// that the saved views were scored with, and a PLANTS field resumed for
/// one step at no rate read 0.3–0.8 dB lower on its held-out views.
pub fn stage_layout(
    before: &GridField,
    visibility: &[f32],
    threshold: f64,
    target: UVec3,
) -> BrickLayout {
    let seen = stage_bricks(before, visibility, threshold, target);
    if before.resolution == target {
        seen.union(&BrickLayout::of(before))
    } else {
        seen
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::DVec3;

    #[test]
    fn a_visible_node_keeps_the_bricks_of_its_reach() {
        let r = UVec3::new(17, 17, 17);
        let coarse = GridField::new(
            r,
            Aabb::new(DVec3::ZERO, DVec3::ONE),
            vec![[0.5, 0.5, 0.5, 40.0]; (r.x * r.y * r.z) as usize],
            4,
        );
        let mut visibility = vec![0.0f32; coarse.nodes.len()];
        // Node (8, 0, 16) reaches the finer grid's nodes 28..36 along x
        // (bricks 3 and 4), 0..4 along y (brick 0), 60..64 along z (brick
        // 7; 64 is the last node, alone in brick 8).
        visibility[coarse.index(8, 0, 16)] = 0.5;
        visibility[coarse.index(1, 1, 1)] = 0.001; // under the threshold
        let layout = stage_bricks(&coarse, &visibility, 0.01, UVec3::splat(65));
        assert_eq!(layout.dims, UVec3::splat(9));
        let kept: Vec<UVec3> = (0..layout.table.len() as u32)
            .filter(|&b| layout.table[b as usize] != crate::field::bricks::EMPTY_BRICK)
            .map(|b| UVec3::new(b % 9, (b / 9) % 9, b / 81))
            .collect();
        assert_eq!(
            kept,
            [
                UVec3::new(3, 0, 7),
                UVec3::new(4, 0, 7),
                UVec3::new(3, 0, 8),
                UVec3::new(4, 0, 8)
            ]
        );
    }

    /// A resumed field (the target its own resolution) keeps every brick
    /// it holds a value in, haze included, besides those its visible
    /// surfaces mark; a finer stage after it keeps only the latter.
    #[test]
    fn a_resumed_field_keeps_the_bricks_it_holds() {
        let r = UVec3::splat(24);
        let mut field = GridField::new(
            r,
            Aabb::new(DVec3::ZERO, DVec3::ONE),
            vec![[0.0; 4]; (r.x * r.y * r.z) as usize],
            4,
        );
        // A surface in brick (0, 0, 0), seen; haze in brick (2, 2, 2), seen
        // too but below the surface's density.
        let h = field.spacing().min_element();
        let surface = field.index(3, 3, 3);
        field.nodes[surface] = [0.5, 0.5, 0.5, (10.0 * MIN_DEPTH / h) as f32];
        let haze = field.index(20, 20, 20);
        field.nodes[haze] = [0.2, 0.2, 0.2, (0.1 * MIN_DEPTH / h) as f32];
        let mut visibility = vec![0.0f32; field.nodes.len()];
        visibility[surface] = 0.5;
        visibility[haze] = 0.5;
        let kept = |l: &BrickLayout| {
            (0..l.table.len())
                .filter(|&b| l.table[b] != crate::field::bricks::EMPTY_BRICK)
                .count()
        };
        let seen = stage_bricks(&field, &visibility, 0.01, r);
        let resumed = stage_layout(&field, &visibility, 0.01, r);
        assert_eq!(kept(&seen), 1, "the visibility rule drops the haze");
        assert_eq!(kept(&resumed), 2);
        assert_eq!(resumed.slots, 2);
        assert_ne!(
            resumed.table[brick_index(resumed.dims, UVec3::splat(2))],
            crate::field::bricks::EMPTY_BRICK
        );
        // Finer, the haze's brick is not kept.
        let finer = UVec3::splat(48);
        assert_eq!(
            stage_layout(&field, &visibility, 0.01, finer),
            stage_bricks(&field, &visibility, 0.01, finer)
        );
    }
}
