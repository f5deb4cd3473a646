//! The placed objects as world-space triangles in a bounding-volume
//! hierarchy, for the path tracer: nearest hits (Möller–Trumbore), shadow
//! rays, and the surface (interpolated normal, material with textures) at
//! a hit, exactly as the G-buffer pass evaluates it.

use glam::DVec3;

use crate::brdf::SurfaceMaterial;
use crate::geometry::{ray_box, Aabb, Ray};
use crate::object::{Material, PlacedObject, Texture};

/// One triangle with what shading needs.
#[derive(Debug, Clone)]
struct Triangle {
    p: [DVec3; 3],
    n: [DVec3; 3],
    uv: [[f64; 2]; 3],
    /// Index into [`MeshScene::materials`].
    material: usize,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle and count; inner: left child (right = left + 1)
    /// with count 0.
    first: u32,
    count: u32,
}

/// A ray's nearest triangle hit.
#[derive(Debug, Clone, Copy)]
pub struct MeshHit {
    /// Ray parameter.
    pub t: f64,
    tri: usize,
    b: [f64; 2],
}

/// A surface point of an object.
#[derive(Debug, Clone, Copy)]
pub struct MeshSurface {
    /// Position.
    pub point: DVec3,
    /// Interpolated unit normal (shading).
    pub normal: DVec3,
    /// Unit face normal, on the side the ray came from.
    pub face_normal: DVec3,
    /// BRDF parameters there.
    pub material: SurfaceMaterial,
}

/// All placed objects' triangles in one BVH.
pub struct MeshScene {
    triangles: Vec<Triangle>,
    nodes: Vec<Node>,
    materials: Vec<(Material, usize)>,
    textures: Vec<Vec<Texture>>,
}

const LEAF_SIZE: usize = 4;

/// Depth down to which nodes are split by the surface area heuristic;
/// below it, at the median (balanced), so no path is deeper than this
/// plus log2 of the triangles: within the GPU traversal's stack
/// (`BVH_STACK` in `shaders/geometry/mesh_bvh.wgsl`, 48) for any mesh a
/// binding holds.
const SAH_DEPTH: u32 = 24;

/// Bins per axis of the surface area heuristic.
const SAH_BINS: usize = 16;

fn centroid(t: &Triangle) -> DVec3 {
    (t.p[0] + t.p[1] + t.p[2]) / 3.0
}

/// Half the surface area of a box (what the heuristic compares).
fn half_area(b: &Aabb) -> f64 {
    let e = (b.max - b.min).max(DVec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// The bin of `t`'s centroid along `axis`, whose centroids span `a`..`b`.
fn sah_bin(t: &Triangle, axis: usize, a: f64, b: f64) -> usize {
    (((centroid(t)[axis] - a) / (b - a) * SAH_BINS as f64) as usize).min(SAH_BINS - 1)
}

/// Splits `tris` where the binned surface area heuristic says (the cost
/// of a split: each side's box area times its triangles), partitioning
/// them in place and returning the left side's count; `None` where the
/// centroids do not spread (the caller splits at the median).
/// Rays that graze a surface (the SSDF bake's outside rays) cross far
/// fewer boxes than with median splits.
fn sah_split(tris: &mut [Triangle], clo: DVec3, chi: DVec3) -> Option<usize> {
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        let (a, b) = (clo[axis], chi[axis]);
        // The centroids do not spread along this axis (or are NaN).
        if b.partial_cmp(&a) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let empty = Aabb::new(DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut boxes = [empty; SAH_BINS];
        let mut counts = [0usize; SAH_BINS];
        for t in tris.iter() {
            let k = sah_bin(t, axis, a, b);
            let tb = MeshScene::tri_bounds(t);
            boxes[k] = Aabb::new(boxes[k].min.min(tb.min), boxes[k].max.max(tb.max));
            counts[k] += 1;
        }
        let grow = |acc: &Aabb, b: &Aabb| Aabb::new(acc.min.min(b.min), acc.max.max(b.max));
        let mut right = [(0.0f64, 0usize); SAH_BINS];
        let (mut rb, mut rn) = (empty, 0);
        for k in (1..SAH_BINS).rev() {
            rb = grow(&rb, &boxes[k]);
            rn += counts[k];
            right[k] = (half_area(&rb), rn);
        }
        let (mut lb, mut ln) = (empty, 0);
        for k in 0..SAH_BINS - 1 {
            lb = grow(&lb, &boxes[k]);
            ln += counts[k];
            let (ra, rn) = right[k + 1];
            if ln == 0 || rn == 0 {
                continue;
            }
            let cost = half_area(&lb) * ln as f64 + ra * rn as f64;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    let (_, axis, k) = best?;
    let (a, b) = (clo[axis], chi[axis]);
    let mut mid = 0;
    for i in 0..tris.len() {
        if sah_bin(&tris[i], axis, a, b) <= k {
            tris.swap(i, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < tris.len()).then_some(mid)
}

impl MeshScene {
    /// Builds the hierarchy over `objects` in their poses, materials with
    /// overrides applied.
    pub fn new(objects: &[PlacedObject]) -> Self {
        let mut triangles = Vec::new();
        let mut materials = Vec::new();
        let mut textures = Vec::new();
        for (o, placed) in objects.iter().enumerate() {
            let m = placed.pose.matrix();
            let nm = placed.pose.normal_matrix();
            textures.push(placed.mesh.textures.clone());
            for (pi, part) in placed.mesh.parts.iter().enumerate() {
                let material = materials.len();
                materials.push((placed.material_of(pi), o));
                let idx = &placed.mesh.indices
                    [part.first_index as usize..(part.first_index + part.index_count) as usize];
                for t in idx.chunks_exact(3) {
                    let v = [0, 1, 2].map(|k| placed.mesh.vertices[t[k] as usize]);
                    triangles.push(Triangle {
                        p: v.map(|x| m.transform_point3(x.position.as_dvec3())),
                        n: v.map(|x| (nm * x.normal.as_dvec3()).normalize_or(DVec3::Y)),
                        uv: v.map(|x| x.uv.map(f64::from)),
                        material,
                    });
                }
            }
        }
        let mut scene = Self {
            triangles,
            nodes: Vec::new(),
            materials,
            textures,
        };
        if !scene.triangles.is_empty() {
            scene.nodes.push(Node {
                bounds: Aabb::new(DVec3::ZERO, DVec3::ZERO),
                first: 0,
                count: 0,
            });
            let n = scene.triangles.len();
            scene.build(0, 0, n, 0);
        }
        scene
    }

    /// Whether there is nothing to hit.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    fn tri_bounds(t: &Triangle) -> Aabb {
        Aabb::new(
            t.p[0].min(t.p[1]).min(t.p[2]),
            t.p[0].max(t.p[1]).max(t.p[2]),
        )
    }

    fn build(&mut self, node: usize, first: usize, count: usize, depth: u32) {
        let tris = &mut self.triangles[first..first + count];
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut clo = lo;
        let mut chi = hi;
        for t in tris.iter() {
            let b = Self::tri_bounds(t);
            lo = lo.min(b.min);
            hi = hi.max(b.max);
            let c = (b.min + b.max) * 0.5;
            clo = clo.min(c);
            chi = chi.max(c);
        }
        // A little slack so axis-aligned flat triangles still get hit.
        let pad = (hi - lo).max_element() * 1e-9 + 1e-12;
        self.nodes[node].bounds = Aabb::new(lo - pad, hi + pad);
        if count <= LEAF_SIZE {
            self.nodes[node].first = first as u32;
            self.nodes[node].count = count as u32;
            return;
        }
        let mid = match (depth < SAH_DEPTH)
            .then(|| sah_split(tris, clo, chi))
            .flatten()
        {
            Some(mid) => mid,
            None => {
                let extent = chi - clo;
                let axis = if extent.x >= extent.y && extent.x >= extent.z {
                    0
                } else if extent.y >= extent.z {
                    1
                } else {
                    2
                };
                let mid = count / 2;
                tris.select_nth_unstable_by(mid, |a, b| {
                    centroid(a)[axis].total_cmp(&centroid(b)[axis])
                });
                mid
            }
        };
        let left = self.nodes.len();
        let empty = Node {
            bounds: self.nodes[node].bounds,
            first: 0,
            count: 0,
        };
        self.nodes.push(empty);
        self.nodes.push(empty);
        self.nodes[node].first = left as u32;
        self.nodes[node].count = 0;
        self.build(left, first, mid, depth + 1);
        self.build(left + 1, first + mid, count - mid, depth + 1);
    }

    fn intersect_triangle(
        t: &Triangle,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<(f64, [f64; 2])> {
        let e1 = t.p[1] - t.p[0];
        let e2 = t.p[2] - t.p[0];
        let pv = ray.dir.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-300 {
            return None;
        }
        let inv = 1.0 / det;
        let tv = ray.origin - t.p[0];
        let u = tv.dot(pv) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let qv = tv.cross(e1);
        let v = ray.dir.dot(qv) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let d = e2.dot(qv) * inv;
        (d > t_min && d < t_max).then_some((d, [u, v]))
    }

    /// The nearest hit in (`t_min`, `t_max`); with `any`, the first found.
    fn traverse(&self, ray: &Ray, t_min: f64, mut t_max: f64, any: bool) -> Option<MeshHit> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = None;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = self.nodes[i];
            match ray_box(ray, &node.bounds) {
                Some((a, b)) if a < t_max && b > t_min => {}
                _ => continue,
            }
            if node.count == 0 {
                stack.push(node.first as usize);
                stack.push(node.first as usize + 1);
                continue;
            }
            for k in node.first as usize..(node.first + node.count) as usize {
                if let Some((t, b)) =
                    Self::intersect_triangle(&self.triangles[k], ray, t_min, t_max)
                {
                    t_max = t;
                    best = Some(MeshHit { t, tri: k, b });
                    if any {
                        return best;
                    }
                }
            }
        }
        best
    }

    /// The nearest triangle along `ray` in (`t_min`, `t_max`).
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<MeshHit> {
        self.traverse(ray, t_min, t_max, false)
    }

    /// Whether any triangle blocks `ray` in (`t_min`, `t_max`).
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.traverse(ray, t_min, t_max, true).is_some()
    }

    /// The hierarchy in f32 for `shaders/geometry/mesh_bvh.wgsl`: nodes as
    /// two vec4s (min, first as bits), (max, count as bits), boxes widened
    /// by 10⁻⁶ of their size so f32 rounding loses no hit; triangles as
    /// three vec4s (corners, w unused).
    pub fn packed(&self) -> (Vec<f32>, Vec<f32>) {
        let mut nodes = Vec::with_capacity(self.nodes.len() * 8);
        for n in &self.nodes {
            let pad = (n.bounds.max - n.bounds.min).max_element() * 1e-6 + 1e-9;
            let (lo, hi) = (n.bounds.min - pad, n.bounds.max + pad);
            nodes.extend([
                lo.x as f32,
                lo.y as f32,
                lo.z as f32,
                f32::from_bits(n.first),
            ]);
            nodes.extend([
                hi.x as f32,
                hi.y as f32,
                hi.z as f32,
                f32::from_bits(n.count),
            ]);
        }
        let mut tris = Vec::with_capacity(self.triangles.len() * 12);
        for t in &self.triangles {
            for p in t.p {
                tris.extend([p.x as f32, p.y as f32, p.z as f32, 0.0]);
            }
        }
        (nodes, tris)
    }

    /// Whether `p` is inside a closed mesh: most of six axis rays from it
    /// first hit a triangle from behind (its winding faces away).
    pub fn inside(&self, p: DVec3) -> bool {
        let mut behind = 0;
        for dir in [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ] {
            let ray = Ray { origin: p, dir };
            if let Some(hit) = self.intersect(&ray, 0.0, f64::INFINITY) {
                let t = &self.triangles[hit.tri];
                behind += ((t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).dot(dir) > 0.0) as u32;
            }
        }
        behind >= 4
    }

    /// The point of the mesh nearest to `p` and the unit normal (by
    /// winding) of its triangle. Of triangles equally near, the first in
    /// the hierarchy's order, as a search over every triangle in that
    /// order finds; the hierarchy skips the boxes farther than the nearest
    /// so far.
    pub fn nearest_point(&self, p: DVec3) -> Option<(DVec3, DVec3)> {
        if self.nodes.is_empty() {
            return None;
        }
        // A box's distance is rounded apart from its triangles': skip only
        // boxes clearly farther, so no tie is lost.
        let to = |b: &Aabb| (b.min - p).max(p - b.max).max(DVec3::ZERO).length_squared();
        let farther = |b: &Aabb, best: f64| to(b) > best * (1.0 + 1e-9);
        let mut best = (f64::INFINITY, usize::MAX, DVec3::ZERO);
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = self.nodes[i];
            if farther(&node.bounds, best.0) {
                continue;
            }
            if node.count == 0 {
                // The nearer child next.
                let (l, r) = (node.first as usize, node.first as usize + 1);
                let near_left = to(&self.nodes[l].bounds) <= to(&self.nodes[r].bounds);
                stack.extend(if near_left { [r, l] } else { [l, r] });
                continue;
            }
            for k in node.first as usize..(node.first + node.count) as usize {
                let q = closest_point_on_triangle(p, self.triangles[k].p);
                let d = q.distance_squared(p);
                if d < best.0 || (d == best.0 && k < best.1) {
                    best = (d, k, q);
                }
            }
        }
        // None where no distance compared (a point that is not finite).
        let t = self.triangles.get(best.1)?;
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
        Some((best.2, n))
    }

    /// The surface at `hit` of `ray`.
    pub fn surface(&self, ray: &Ray, hit: &MeshHit) -> MeshSurface {
        let t = &self.triangles[hit.tri];
        let [u, v] = hit.b;
        let w = 1.0 - u - v;
        let point = ray.at(hit.t);
        let normal = (t.n[0] * w + t.n[1] * u + t.n[2] * v).normalize_or(DVec3::Y);
        let mut face = (t.p[1] - t.p[0])
            .cross(t.p[2] - t.p[0])
            .normalize_or(normal);
        if face.dot(ray.dir) > 0.0 {
            face = -face;
        }
        let uv = [0, 1].map(|c| t.uv[0][c] * w + t.uv[1][c] * u + t.uv[2][c] * v);
        let (m, object) = &self.materials[t.material];
        MeshSurface {
            point,
            normal,
            face_normal: face,
            material: m.at(uv, &self.textures[*object]),
        }
    }
}

/// The point of triangle `t` nearest to `p` (Ericson, Real-Time Collision
/// Detection §5.1.5: Voronoi regions of corners, edges and face).
fn closest_point_on_triangle(p: DVec3, t: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// The bundled toy as a scene.
    fn toy_scene() -> MeshScene {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/objects/toy.glb");
        let mesh = Arc::new(crate::object::load_gltf(&path).unwrap());
        MeshScene::new(&[PlacedObject {
            name: "toy".into(),
            mesh,
            pose: crate::object::Pose::default(),
            material: Default::default(),
        }])
    }

    /// The BVH finds the same nearest hits as testing every triangle.
    #[test]
    fn bvh_hits_match_brute_force() {
        let scene = toy_scene();
        let mut rng = crate::rng::Pcg32::new(3, 0);
        let mut hits = 0;
        for _ in 0..300 {
            let o = DVec3::new(rng.next_f64() * 4.0 - 2.0, rng.next_f64() * 3.0 - 0.5, 2.5);
            let target = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() * 1.3,
                rng.next_f64() - 0.5,
            );
            let ray = Ray {
                origin: o,
                dir: (target - o).normalize(),
            };
            let fast = scene.intersect(&ray, 0.0, f64::INFINITY).map(|h| h.t);
            let slow = scene
                .triangles
                .iter()
                .filter_map(|t| MeshScene::intersect_triangle(t, &ray, 0.0, f64::INFINITY))
                .map(|(t, _)| t)
                .min_by(f64::total_cmp);
            assert_eq!(fast, slow);
            hits += fast.is_some() as u32;
            assert_eq!(scene.occluded(&ray, 0.0, f64::INFINITY), slow.is_some());
        }
        assert!(hits > 50, "{hits}");
    }

    /// The hierarchy's nearest point is the one a search over every
    /// triangle finds (the first of equally near ones), near the surface
    /// and far from it; a point that is not finite has none.
    #[test]
    fn nearest_points_match_brute_force() {
        let scene = toy_scene();
        let mut rng = crate::rng::Pcg32::new(5, 0);
        for k in 0..400 {
            let spread = if k % 2 == 0 { 1.5 } else { 6.0 };
            let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * spread
                - DVec3::splat(0.5 * spread)
                + DVec3::new(0.0, 0.6, 0.0);
            let slow = scene
                .triangles
                .iter()
                .map(|t| {
                    let q = closest_point_on_triangle(p, t.p);
                    let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
                    (q.distance_squared(p), q, n)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, q, n)| (q, n));
            assert_eq!(scene.nearest_point(p), slow, "{p}");
        }
        assert_eq!(scene.nearest_point(DVec3::NAN), None);
    }
}
