//! The exact spherical signed distance S(d; x) of a triangle mesh (METHOD.md
//! "SSDF field"): the angle from direction d to the object's silhouette as
//! seen from x, positive where the ray from x along d misses the object,
//! negative where it hits. The f64 CPU reference of the bake kernels
//! (`shaders/ssdf/`, see `super::bake`), which compute it the same way:
//!
//! - the sign is a ray cast (through the bounding-volume hierarchy);
//! - the angle is the smallest angle from d to the **outline** seen from x:
//!   the boundary between the directions that hit the object and those
//!   that miss. The outline is made of pieces of the great-circle arcs of
//!   the **silhouette edges** seen from x: edges whose two faces face x on
//!   opposite sides, and edges with one face (open meshes) or more than
//!   two. Not every silhouette edge is on the outline (a part in front of
//!   another, a fold: inner contours), so each silhouette edge is cut into
//!   pieces of at most [`PIECE_ANGLE`] (but no more than [`ARC_PIECES`]),
//!   and a piece is **outer** when a ray just outside its middle (by
//!   [`OUTSIDE_OFFSET`], on the side away from the front face) misses; the
//!   outer pieces are the outline. A piece only partly on the outline is
//!   judged by its middle, so S is exact up to about one piece's angle
//!   where the outline passes behind another part, and exact elsewhere.
//!
//! Every outline point is the nearest point of the hit directions to some
//! miss and of the miss directions to some hit, so the outer pieces serve
//! both signs. (Until issue 26's ninth pass a miss measured its angle to
//! every silhouette arc, inner ones included, and every edge was cut into
//! four pieces: on a mesh of 100k triangles that was five times the arcs
//! and four times the rays, for the same values up to a piece's angle.)
//!
//! From inside a closed mesh nothing is a silhouette and every ray hits:
//! S = −π. Positions are welded by their exact bits, so split vertices
//! (normal or UV seams) do not open the mesh.

use std::collections::HashMap;

use glam::{DVec3, DVec4};

use crate::object::ObjectMesh;

/// One welded edge with the planes of its faces.
#[derive(Debug, Clone, Copy)]
pub struct SilhouetteEdge {
    /// First end point (object space).
    pub a: DVec3,
    /// Second end point.
    pub b: DVec3,
    /// The two faces' planes (n, n·a) with unit n; an edge with one face
    /// or more than two has `always` set and its planes unused.
    pub planes: [DVec4; 2],
    /// The third corners of the two faces (the same twice for `always`).
    pub opposite: [DVec3; 2],
    /// A silhouette from everywhere (open or non-manifold edge).
    pub always: bool,
}

/// The angle (radians) by which the probe ray that tells an outer
/// silhouette arc from an inner contour passes outside the arc's middle.
pub const OUTSIDE_OFFSET: f64 = 2e-3;

/// Most pieces a silhouette arc is cut into to tell outline from inner
/// contour (at most 16: the kernels' piece records hold four bits).
pub const ARC_PIECES: u32 = 16;

/// The angle (radians) a piece of a silhouette arc spans at most, unless
/// that would take more than [`ARC_PIECES`] pieces: where the outline
/// passes behind another part, S may be off by about this much. A tenth
/// of a 32² direction map's texel (0.11 rad).
pub const PIECE_ANGLE: f64 = 0.01;

impl SilhouetteEdge {
    /// Whether the edge is on the silhouette seen from `x`: its faces face
    /// `x` on opposite sides.
    pub fn is_silhouette(&self, x: DVec3) -> bool {
        self.always || self.faces_x(0, x) != self.faces_x(1, x)
    }

    fn faces_x(&self, face: usize, x: DVec3) -> bool {
        let p = self.planes[face];
        p.truncate().dot(x) - p.w > 0.0
    }

    /// How many pieces the edge's arc seen from `x` is cut into: enough
    /// that none spans more than [`PIECE_ANGLE`], at most [`ARC_PIECES`].
    /// Mirrored by `piece_count` in `shaders/ssdf/silhouette_edges.wgsl`.
    pub fn pieces(&self, x: DVec3) -> u32 {
        let angle = angle_between((self.a - x).normalize(), (self.b - x).normalize());
        ((angle / PIECE_ANGLE).ceil() as u32).clamp(1, ARC_PIECES)
    }

    /// Piece `k` of `n` of the edge's arc seen from `x`: its ends, and the
    /// direction just outside its middle, on the side away from the face
    /// that faces `x`.
    pub fn piece(&self, x: DVec3, k: u32, n: u32) -> (DVec3, DVec3, DVec3) {
        let (a, b) = (self.a - x, self.b - x);
        let at = |t: f64| (a + (b - a) * t).normalize();
        let n = n as f64;
        let (p, q) = (at(k as f64 / n), at((k as f64 + 1.0) / n));
        let m = at((k as f64 + 0.5) / n);
        let front = if self.faces_x(0, x) { 0 } else { 1 };
        let normal = a.cross(b).normalize_or_zero();
        let side = normal.dot(self.opposite[front] - x).signum();
        (p, q, (m - normal * (side * OUTSIDE_OFFSET)).normalize())
    }
}

/// The outline seen from one point: the outer pieces of its silhouette
/// arcs, consecutive ones of an edge joined.
#[derive(Debug, Clone)]
pub struct SilhouetteView {
    arcs: Vec<(DVec3, DVec3)>,
}

impl SilhouetteView {
    /// S(d) for unit `d`, given whether the ray along `d` hits.
    pub fn signed_angle(&self, d: DVec3, hit: bool) -> f64 {
        let nearest = self
            .arcs
            .iter()
            .fold(4.0f64, |m, &(a, b)| m.min(chord2_to_arc(d, a, b)));
        let best = angle_of_chord2(nearest);
        if hit {
            -best
        } else {
            best
        }
    }

    /// How many arcs the outline has.
    pub fn arcs(&self) -> usize {
        self.arcs.len()
    }
}

/// A mesh's welded edges, ready for `SilhouetteMesh::signed_angle`.
#[derive(Debug, Clone)]
pub struct SilhouetteMesh {
    /// The edges.
    pub edges: Vec<SilhouetteEdge>,
}

impl SilhouetteMesh {
    /// Welds `mesh` and collects its edges (zero-area triangles are left out).
    pub fn new(mesh: &ObjectMesh) -> Self {
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let mut points: Vec<DVec3> = Vec::new();
        let welded: Vec<u32> = mesh
            .vertices
            .iter()
            .map(|v| {
                let key = v.position.to_array().map(f32::to_bits);
                *ids.entry(key).or_insert_with(|| {
                    points.push(v.position.as_dvec3());
                    points.len() as u32 - 1
                })
            })
            .collect();
        let mut faces: HashMap<(u32, u32), Vec<(DVec4, DVec3)>> = HashMap::new();
        for t in mesh.indices.chunks_exact(3) {
            let v = [t[0], t[1], t[2]].map(|i| welded[i as usize]);
            let p = v.map(|i| points[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            if n.length() <= 1e-12 * (p[1] - p[0]).length_squared().max(1e-300) {
                continue;
            }
            let n = n.normalize();
            let plane = n.extend(n.dot(p[0]));
            for k in 0..3 {
                let (i, j) = (v[k], v[(k + 1) % 3]);
                if i != j {
                    let third = p[(k + 2) % 3];
                    faces
                        .entry((i.min(j), i.max(j)))
                        .or_default()
                        .push((plane, third));
                }
            }
        }
        let mut keys: Vec<_> = faces.keys().copied().collect();
        keys.sort_unstable();
        let edges = keys
            .into_iter()
            .map(|k| {
                let f = &faces[&k];
                let second = *f.get(1).unwrap_or(&f[0]);
                SilhouetteEdge {
                    a: points[k.0 as usize],
                    b: points[k.1 as usize],
                    planes: [f[0].0, second.0],
                    opposite: [f[0].1, second.1],
                    always: f.len() != 2,
                }
            })
            .collect();
        Self { edges }
    }

    /// The outline seen from `x`; `hits(x, d)` says whether the ray from
    /// x along d hits the object (used to find the outer pieces). Each
    /// silhouette edge is classified in [`SilhouetteEdge::pieces`] pieces;
    /// consecutive outer pieces are kept as one arc (they lie on one great
    /// circle, so the angle to their union is the angle to that arc).
    pub fn view_from(&self, x: DVec3, hits: impl Fn(DVec3, DVec3) -> bool) -> SilhouetteView {
        let mut arcs: Vec<(DVec3, DVec3)> = Vec::new();
        for e in self.edges.iter().filter(|e| e.is_silhouette(x)) {
            let n = e.pieces(x);
            let mut run: Option<(DVec3, DVec3)> = None;
            for k in 0..n {
                let (a, b, probe) = e.piece(x, k, n);
                if hits(x, probe) {
                    arcs.extend(run.take());
                } else {
                    run = Some((run.map_or(a, |r| r.0), b));
                }
            }
            arcs.extend(run);
        }
        SilhouetteView { arcs }
    }
}

/// The angle between unit vectors (atan2 form: accurate near 0 and π).
pub fn angle_between(u: DVec3, v: DVec3) -> f64 {
    u.cross(v).length().atan2(u.dot(v))
}

/// The squared chord from unit `d` to the nearest point of the shorter
/// great-circle arc from unit `a` to unit `b`: to the great circle where d's
/// projection falls within the arc, else to the nearer end. The chord,
/// 2 sin(θ/2), grows with the angle θ, so the nearest arc is the one of
/// smallest chord; it is accurate near θ = 0, where a cosine is not, and
/// costs no inverse trigonometry. Mirrored by `ssdf_arc_chord2` and
/// `ssdf_chord2_of` in `shaders/ssdf/angles.wgsl` (which prepare each arc
/// once, and keep the nearest end and the nearest great circle apart).
pub fn chord2_to_arc(d: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ends = (d - a).length_squared().min((d - b).length_squared());
    let n = a.cross(b);
    let len = n.length();
    if len < 1e-12 || a.dot(b) < -1.0 + 1e-12 {
        return ends;
    }
    let n = n / len;
    if d.dot(n.cross(a)) >= 0.0 && d.dot(b.cross(n)) >= 0.0 {
        // sin θ = |d·n|; 2(1 − cos θ) without cancellation.
        let s2 = d.dot(n).powi(2);
        ends.min(2.0 * s2 / (1.0 + (1.0 - s2).max(0.0).sqrt()))
    } else {
        ends
    }
}

/// The angle whose chord squared is `chord2` (0..=4).
pub fn angle_of_chord2(chord2: f64) -> f64 {
    2.0 * (0.5 * chord2.max(0.0).sqrt()).min(1.0).asin()
}

/// The smallest angle from unit `d` to the shorter great-circle arc from
/// unit `a` to unit `b` ([`chord2_to_arc`] as an angle).
pub fn angle_to_arc(d: DVec3, a: DVec3, b: DVec3) -> f64 {
    angle_of_chord2(chord2_to_arc(d, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn arc_distances() {
        let (a, b) = (DVec3::X, DVec3::Y);
        // Above the arc's middle: the angle to the great circle.
        let d = DVec3::new(1.0, 1.0, 1.0).normalize();
        assert!((angle_to_arc(d, a, b) - (1.0f64 / 3.0).sqrt().asin()).abs() < 1e-12);
        // Beyond an end: the angle to that end.
        let d = DVec3::new(1.0, -0.3, 0.2).normalize();
        assert!((angle_to_arc(d, a, b) - angle_between(d, a)).abs() < 1e-12);
        // On the arc.
        let d = DVec3::new(0.3, 0.7, 0.0).normalize();
        assert!(angle_to_arc(d, a, b) < 1e-12);
        // The antipode of the arc's middle is π − π/4 from both ends.
        let d = -DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!((angle_to_arc(d, a, b) - 0.75 * PI).abs() < 1e-12);
    }
}
