//! Light sources inside a grid field: connected groups of nodes whose
//! radiance stands far above the field's surfaces (a lamp, a softbox, a
//! window). Found once per field, on the CPU, when it is uploaded; the
//! lighting chooses among them the ones it shades as local lights with
//! per-pixel visibility ([`crate::lighting::local`]).

use glam::DVec3;

use super::GridField;

/// Nodes brighter than this many times the median surface node are
/// candidates (the lowest ratio any scene knob may ask for).
pub const MIN_EMITTER_RATIO: f64 = 8.0;

/// At most this many emitters are kept per field (the brightest).
pub const MAX_FIELD_EMITTERS: usize = 16;

/// One light source found in a field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldEmitter {
    /// Its centre (luminance-weighted mean of its nodes).
    pub centre: DVec3,
    /// A sphere of this radius around the centre holds all of its nodes and
    /// the trilinear reach of their light.
    pub radius: f64,
    /// Its brightest node's luminance over the median surface node's.
    pub ratio: f64,
    /// Σ luminance × node volume over its nodes (ranks emitters).
    pub power: f64,
    /// Its power over the same sum across every node with density: the
    /// share of the field's light it holds (0–1).
    pub share: f64,
}

/// Rec. 709 luminance of a node's colour.
fn luminance(n: &[f32; 4]) -> f64 {
    0.2126 * n[0] as f64 + 0.7152 * n[1] as f64 + 0.0722 * n[2] as f64
}

/// The field's emitters, brightest first: groups of 26-connected nodes
/// with density whose luminance exceeds [`MIN_EMITTER_RATIO`] × the median
/// luminance of the surface nodes (those holding at least one optical
/// depth per node spacing and some light). None when the field has no
/// such surface.
pub fn find_emitters(field: &GridField) -> Vec<FieldEmitter> {
    let h = field.spacing();
    let step = h.min_element();
    let surface: Vec<f64> = field
        .nodes
        .iter()
        .filter(|n| n[3] as f64 * step >= 1.0)
        .map(luminance)
        // Inside opaque shapes the nodes are dense and black (no light
        // leaves there): not surfaces.
        .filter(|&y| y > 0.0)
        .collect();
    if surface.is_empty() {
        return Vec::new();
    }
    let mut sorted = surface;
    let mid = sorted.len() / 2;
    let median = *sorted.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
    if median <= 0.0 || !median.is_finite() {
        return Vec::new();
    }
    let limit = MIN_EMITTER_RATIO * median;
    let node_volume = h.x * h.y * h.z;
    let field_power: f64 = field
        .nodes
        .iter()
        .filter(|n| n[3] > 0.0)
        .map(luminance)
        .sum::<f64>()
        * node_volume;
    let bright: Vec<bool> = field
        .nodes
        .iter()
        .map(|n| n[3] > 0.0 && luminance(n) > limit)
        .collect();
    let r = field.resolution;
    let (nx, ny, nz) = (r.x as i64, r.y as i64, r.z as i64);
    let mut seen = vec![false; bright.len()];
    let position = |i: usize| {
        let (x, y, z) = (i as i64 % nx, (i as i64 / nx) % ny, i as i64 / (nx * ny));
        field.bounds.min + DVec3::new(x as f64, y as f64, z as f64) * h
    };
    let mut emitters = Vec::new();
    for start in 0..bright.len() {
        if !bright[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut group = vec![start];
        let mut next = 0;
        while next < group.len() {
            let i = group[next] as i64;
            next += 1;
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (a, b, c) = (x + dx, y + dy, z + dz);
                        if a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz {
                            continue;
                        }
                        let j = (a + nx * (b + ny * c)) as usize;
                        if bright[j] && !seen[j] {
                            seen[j] = true;
                            group.push(j);
                        }
                    }
                }
            }
        }
        let weights: Vec<f64> = group.iter().map(|&i| luminance(&field.nodes[i])).collect();
        let total: f64 = weights.iter().sum();
        let centre = group
            .iter()
            .zip(&weights)
            .map(|(&i, &w)| position(i) * w)
            .sum::<DVec3>()
            / total;
        let reach = group
            .iter()
            .map(|&i| position(i).distance(centre))
            .fold(0.0, f64::max);
        emitters.push(FieldEmitter {
            centre,
            // Trilinear interpolation carries a node's light one spacing
            // further along every axis.
            radius: reach + h.length(),
            ratio: weights.iter().copied().fold(0.0, f64::max) / median,
            power: total * node_volume,
            share: total * node_volume / field_power,
        });
    }
    emitters.sort_by(|a, b| b.power.total_cmp(&a.power));
    emitters.truncate(MAX_FIELD_EMITTERS);
    emitters
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::UVec3;

    /// A 24³ field over [0, 1]³: a dim opaque floor (y < 0.2, luminance
    /// 0.3) and bright balls of `(centre, radius, radiance)`.
    fn field(balls: &[(DVec3, f64, f32)]) -> GridField {
        let n = 24u32;
        let bounds = Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        };
        let mut nodes = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = DVec3::new(x as f64, y as f64, z as f64) / (n - 1) as f64;
                    let mut node = [0.0f32; 4];
                    if p.y < 0.2 {
                        node = [0.3, 0.3, 0.3, 400.0];
                    }
                    for &(c, r, l) in balls {
                        if p.distance(c) <= r {
                            node = [l, l * 0.9, l * 0.8, 400.0];
                        }
                    }
                    nodes.push(node);
                }
            }
        }
        GridField::new(UVec3::splat(n), bounds, nodes, 4)
    }

    #[test]
    fn a_bright_ball_is_one_emitter_around_its_centre() {
        let c = DVec3::new(0.6, 0.7, 0.4);
        let e = find_emitters(&field(&[(c, 0.08, 50.0)]));
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].centre.distance(c) < 0.02, "{:?}", e[0]);
        assert!(
            e[0].radius >= 0.08 && e[0].radius < 0.08 + 0.1,
            "{:?}",
            e[0]
        );
        assert!(e[0].ratio > 100.0);
    }

    #[test]
    fn an_emitters_share_is_its_part_of_the_fields_light() {
        let c = DVec3::new(0.6, 0.7, 0.4);
        let f = field(&[(c, 0.08, 50.0)]);
        let e = find_emitters(&f);
        // The ball's nodes against the floor's, counted from the nodes.
        let lum = |n: &[f32; 4]| luminance(n);
        let ball: f64 = f.nodes.iter().filter(|n| n[0] > 1.0).map(lum).sum();
        let all: f64 = f.nodes.iter().filter(|n| n[3] > 0.0).map(lum).sum();
        assert!((e[0].share - ball / all).abs() < 1e-12, "{:?}", e[0]);
        assert!(e[0].share > 0.0 && e[0].share < 1.0);
    }

    #[test]
    fn separate_balls_are_separate_emitters_brightest_first() {
        let a = DVec3::new(0.25, 0.7, 0.3);
        let b = DVec3::new(0.75, 0.6, 0.7);
        let e = find_emitters(&field(&[(a, 0.06, 20.0), (b, 0.1, 20.0)]));
        assert_eq!(e.len(), 2, "{e:?}");
        assert!(e[0].centre.distance(b) < 0.02 && e[1].centre.distance(a) < 0.02);
    }

    #[test]
    fn a_field_without_bright_nodes_has_no_emitter() {
        assert!(find_emitters(&field(&[])).is_empty());
        // Brighter than the floor, but under the ratio.
        let c = DVec3::new(0.5, 0.6, 0.5);
        assert!(find_emitters(&field(&[(c, 0.1, 2.0)])).is_empty());
    }
}
