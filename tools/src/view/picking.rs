//! Mouse picking for the viewer: which object a ray hits (its triangles,
//! in their poses), where a ray meets the field's surface (the march's
//! expected depth, once the ray is mostly opaque), and where an object
//! stands when dragged onto such a point.

use glam::DVec3;
use inlay_passes::bake::MeshScene;
use inlay_passes::field::GridField;
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

/// Where `ray` meets the field's surface: the point at the march's
/// expected depth D̂/Ô, when the ray's opacity reaches [`SURFACE_OPACITY`].
pub fn field_surface(field: &GridField, ray: &Ray, knobs: &MarchKnobs) -> Option<DVec3> {
    let m = march_ray(field, ray, f64::INFINITY, knobs);
    (m.opacity >= SURFACE_OPACITY && m.depth.is_finite()).then(|| ray.at(m.depth / m.opacity))
}

/// The pose position that puts `placed`'s bounding-sphere centre above
/// `surface` and its lowest point (of its posed bounding box) on it.
pub fn rest_on(placed: &PlacedObject, surface: DVec3) -> DVec3 {
    let m = placed.pose.matrix();
    let b = placed.mesh.bounds();
    let lowest = (0..8)
        .map(|k| {
            let corner = DVec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            m.transform_point3(corner).y
        })
        .fold(f64::INFINITY, f64::min);
    let (centre, _) = placed.sphere();
    let p = placed.pose.position;
    DVec3::new(
        surface.x - (centre.x - p.x),
        surface.y + (p.y - lowest),
        surface.z - (centre.z - p.z),
    )
}
