//! Mouse picking for the viewer: which object a ray hits (its triangles,
//! in their poses), where a ray meets the field's surface (the march's
//! expected depth, once the ray is mostly opaque), and where an object
//! stands when dragged onto such a point.

use glam::DVec3;
use inlay_passes::field::GridField;
use inlay_passes::geometry::MeshScene;
use inlay_passes::geometry::Ray;
use inlay_passes::march::{march_ray, MarchKnobs};
use inlay_passes::object::PlacedObject;

/// The opacity a ray must reach for the field to count as a surface there.
pub const SURFACE_OPACITY: f64 = 0.5;

/// The nearest of `objects` that `ray` hits: its index and distance.
pub fn pick_object(objects: &[PlacedObject], ray: &Ray) -> Option<(usize, f64)> {
    objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            let (c, r) = o.sphere();
            // Cheap rejection by the bounding sphere before the triangles.
            let to = c - ray.origin;
            let along = to.dot(ray.dir);
            if to.length_squared() - along * along > r * r {
                return None;
            }
            MeshScene::new(std::slice::from_ref(o))
                .intersect(ray, 0.0, f64::INFINITY)
                .map(|h| (i, h.t))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The nearest of `objects` that `ray` hits in front of the field's
/// surface (what the user sees under the cursor): an object the field
/// hides there is not picked. With `occlusion` off (objects drawn over the
/// field) the field hides nothing.
pub fn pick_visible(
    objects: &[PlacedObject],
    ray: &Ray,
    field: &GridField,
    knobs: &MarchKnobs,
    occlusion: bool,
) -> Option<(usize, f64)> {
    let (i, t) = pick_object(objects, ray)?;
    let hidden = occlusion && field_depth(field, ray, knobs).is_some_and(|d| d < t);
    (!hidden).then_some((i, t))
}

/// Where `ray` meets the field's surface: the point at the march's
/// expected depth D̂/Ô, when the ray's opacity reaches [`SURFACE_OPACITY`].
pub fn field_surface(field: &GridField, ray: &Ray, knobs: &MarchKnobs) -> Option<DVec3> {
    field_depth(field, ray, knobs).map(|t| ray.at(t))
}

/// The ray parameter of [`field_surface`]'s point.
pub fn field_depth(field: &GridField, ray: &Ray, knobs: &MarchKnobs) -> Option<f64> {
    let m = march_ray(field, ray, f64::INFINITY, knobs);
    let t = m.depth / m.opacity;
    (m.opacity >= SURFACE_OPACITY && t.is_finite()).then_some(t)
}

/// The pose position that puts `placed`'s bounding-sphere centre above
/// `surface` and its lowest point (of its posed bounding box) on it.
pub fn rest_on(placed: &PlacedObject, surface: DVec3) -> DVec3 {
    let m = placed.pose.matrix();
    let b = placed.mesh.bounds();
    let lowest = b
        .corners()
        .iter()
        .map(|&corner| m.transform_point3(corner).y)
        .fold(f64::INFINITY, f64::min);
    let (centre, _) = placed.sphere();
    let p = placed.pose.position;
    DVec3::new(
        surface.x - (centre.x - p.x),
        surface.y + (p.y - lowest),
        surface.z - (centre.z - p.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::UVec3;
    use inlay_passes::geometry::Aabb;
    use inlay_passes::object::{load_gltf, Pose, Scale};
    use std::sync::Arc;

    /// A 0.2-wide sphere at the origin inside a field whose only matter is
    /// a dense slab at z ∈ [`lo`, `hi`].
    fn scene(lo: f64, hi: f64) -> (Vec<PlacedObject>, GridField) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/objects/metal-sphere.gltf");
        let ball = PlacedObject {
            name: "ball".into(),
            mesh: Arc::new(load_gltf(&path).unwrap()),
            pose: Pose {
                scale: Scale::Uniform(0.1),
                ..Pose::default()
            },
            material: Default::default(),
        };
        let n = 33u32;
        let bounds = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        let nodes = (0..n * n * n)
            .map(|i| {
                let z = -1.0 + 2.0 * (i / (n * n)) as f64 / (n - 1) as f64;
                let d = if (lo..=hi).contains(&z) { 200.0 } else { 0.0 };
                [0.5, 0.5, 0.5, d]
            })
            .collect();
        (
            vec![ball],
            GridField::new(UVec3::splat(n), bounds, nodes, 4),
        )
    }

    fn ray_down_z() -> Ray {
        Ray {
            origin: DVec3::new(0.0, 0.0, 3.0),
            dir: DVec3::new(0.0, 0.0, -1.0),
        }
    }

    #[test]
    fn the_field_in_front_hides_an_object_from_the_cursor() {
        let (objects, field) = scene(0.5, 0.8);
        let knobs = MarchKnobs::default();
        let ray = ray_down_z();
        assert!(
            pick_object(&objects, &ray).is_some(),
            "the ray meets the ball"
        );
        assert_eq!(pick_visible(&objects, &ray, &field, &knobs, true), None);
        // Drawn over the field (occlusion off), it is picked through it.
        assert_eq!(
            pick_visible(&objects, &ray, &field, &knobs, false).map(|h| h.0),
            Some(0)
        );
    }

    #[test]
    fn the_field_behind_an_object_does_not_hide_it() {
        let (objects, field) = scene(-0.8, -0.5);
        let ray = ray_down_z();
        let hit = pick_visible(&objects, &ray, &field, &MarchKnobs::default(), true);
        assert_eq!(hit.map(|h| h.0), Some(0));
        let depth = field_depth(&field, &ray, &MarchKnobs::default()).unwrap();
        assert!(
            hit.unwrap().1 < depth && depth > 3.4 && depth < 3.6,
            "{depth}"
        );
    }
}
