//! The analytic shapes a recipe is made of: signed distance (for the baked
//! density), ray intervals (for the path tracer) and outward normals.

use glam::{DMat3, DVec3};

use crate::geometry::{Aabb, Ray};

/// One analytic shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// The solid half-space below the plane through `point` with outward
    /// unit `normal`.
    Plane {
        /// A point on the plane.
        point: DVec3,
        /// Outward unit normal.
        normal: DVec3,
    },
    /// A ball.
    Sphere {
        /// Centre.
        centre: DVec3,
        /// Radius.
        radius: f64,
    },
    /// A box, turned by `rotation` about its centre.
    Box {
        /// Centre.
        centre: DVec3,
        /// Half the edge lengths, along the box's own axes.
        half: DVec3,
        /// World from box axes (orthonormal, determinant +1; identity for
        /// an axis-aligned box).
        rotation: DMat3,
    },
    /// A capped cylinder.
    Cylinder {
        /// Midpoint of the axis.
        centre: DVec3,
        /// Unit axis direction.
        axis: DVec3,
        /// Radius.
        radius: f64,
        /// Half the height.
        half_height: f64,
    },
}

impl Shape {
    /// Signed distance from `x` to the surface: negative inside.
    pub fn sdf(&self, x: DVec3) -> f64 {
        match *self {
            Shape::Plane { point, normal } => (x - point).dot(normal),
            Shape::Sphere { centre, radius } => (x - centre).length() - radius,
            Shape::Box {
                centre,
                half,
                rotation,
            } => {
                let q = (rotation.transpose() * (x - centre)).abs() - half;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
            Shape::Cylinder {
                centre,
                axis,
                radius,
                half_height,
            } => {
                let v = x - centre;
                let a = v.dot(axis);
                let r = (v - a * axis).length();
                let (dx, dy) = (r - radius, a.abs() - half_height);
                dx.max(dy).min(0.0) + (dx.max(0.0).powi(2) + dy.max(0.0).powi(2)).sqrt()
            }
        }
    }

    /// The largest depth of a point inside the shape below its surface
    /// (the largest −sdf): a ball's radius, a box's smallest half edge, the
    /// smaller of a cylinder's radius and half height; a half-space has no
    /// limit.
    pub fn inner_radius(&self) -> f64 {
        match *self {
            Shape::Plane { .. } => f64::INFINITY,
            Shape::Sphere { radius, .. } => radius,
            Shape::Box { half, .. } => half.min_element(),
            Shape::Cylinder {
                radius,
                half_height,
                ..
            } => radius.min(half_height),
        }
    }

    /// Unit gradient of the signed distance at `x` (central differences).
    pub fn sdf_gradient(&self, x: DVec3) -> DVec3 {
        let e = 1e-6 * (1.0 + x.abs().max_element());
        let g = DVec3::new(
            self.sdf(x + DVec3::X * e) - self.sdf(x - DVec3::X * e),
            self.sdf(x + DVec3::Y * e) - self.sdf(x - DVec3::Y * e),
            self.sdf(x + DVec3::Z * e) - self.sdf(x - DVec3::Z * e),
        );
        g.try_normalize().unwrap_or(DVec3::Y)
    }

    /// The outward unit normal at surface point `p`.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        match *self {
            Shape::Plane { normal, .. } => normal,
            Shape::Sphere { centre, .. } => (p - centre).normalize_or(DVec3::Y),
            Shape::Box {
                centre,
                half,
                rotation,
            } => {
                let q = rotation.transpose() * (p - centre) / half;
                let a = q.abs();
                rotation
                    * if a.x >= a.y && a.x >= a.z {
                        DVec3::X * q.x.signum()
                    } else if a.y >= a.z {
                        DVec3::Y * q.y.signum()
                    } else {
                        DVec3::Z * q.z.signum()
                    }
            }
            Shape::Cylinder {
                centre,
                axis,
                radius,
                half_height,
            } => {
                let v = p - centre;
                let a = v.dot(axis);
                let radial = v - a * axis;
                if (a.abs() - half_height).abs() * radius
                    < (radial.length() - radius).abs() * half_height
                {
                    axis * a.signum()
                } else {
                    radial.normalize_or(axis.any_orthonormal_vector())
                }
            }
        }
    }

    /// The parameter interval in which `ray` is inside the shape (may start
    /// at a negative t or be unbounded for planes); `None` if never inside.
    pub fn interval(&self, ray: &Ray) -> Option<(f64, f64)> {
        match *self {
            Shape::Plane { point, normal } => {
                let s0 = (ray.origin - point).dot(normal);
                let denom = ray.dir.dot(normal);
                if denom == 0.0 {
                    (s0 <= 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY))
                } else if denom > 0.0 {
                    Some((f64::NEG_INFINITY, -s0 / denom))
                } else {
                    Some((-s0 / denom, f64::INFINITY))
                }
            }
            Shape::Sphere { centre, radius } => {
                let oc = ray.origin - centre;
                let a = ray.dir.length_squared();
                let b = oc.dot(ray.dir);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - a * c;
                if disc < 0.0 {
                    return None;
                }
                let s = disc.sqrt();
                // Numerically stable roots.
                let q = -(b + s.copysign(b));
                let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
                Some((t0.min(t1), t0.max(t1)))
            }
            Shape::Box {
                centre,
                half,
                rotation,
            } => {
                let to_box = rotation.transpose();
                slab(
                    to_box * (ray.origin - centre),
                    to_box * ray.dir,
                    -half,
                    half,
                )
            }
            Shape::Cylinder {
                centre,
                axis,
                radius,
                half_height,
            } => {
                let o = ray.origin - centre;
                let (oa, da) = (o.dot(axis), ray.dir.dot(axis));
                let (op, dp) = (o - oa * axis, ray.dir - da * axis);
                // Axial slab.
                let (mut t0, mut t1) = if da == 0.0 {
                    if oa.abs() > half_height {
                        return None;
                    }
                    (f64::NEG_INFINITY, f64::INFINITY)
                } else {
                    let a = (-half_height - oa) / da;
                    let b = (half_height - oa) / da;
                    (a.min(b), a.max(b))
                };
                // Infinite cylinder.
                let a = dp.length_squared();
                let c = op.length_squared() - radius * radius;
                if a == 0.0 {
                    if c > 0.0 {
                        return None;
                    }
                } else {
                    let b = op.dot(dp);
                    let disc = b * b - a * c;
                    if disc < 0.0 {
                        return None;
                    }
                    let s = disc.sqrt();
                    t0 = t0.max((-b - s) / a);
                    t1 = t1.min((-b + s) / a);
                }
                (t0 <= t1).then_some((t0, t1))
            }
        }
    }

    /// A box around the shape, `None` for the unbounded plane.
    pub fn bounds(&self) -> Option<Aabb> {
        match *self {
            Shape::Plane { .. } => None,
            Shape::Sphere { centre, radius } => Some(Aabb::new(centre - radius, centre + radius)),
            Shape::Box {
                centre,
                half,
                rotation,
            } => {
                // Per world axis, Σ_j |R_ij| h_j.
                let abs = DMat3::from_cols(
                    rotation.x_axis.abs(),
                    rotation.y_axis.abs(),
                    rotation.z_axis.abs(),
                );
                let e = abs * half;
                Some(Aabb::new(centre - e, centre + e))
            }
            Shape::Cylinder {
                centre,
                axis,
                radius,
                half_height,
            } => {
                // Exact box of a capped cylinder: per axis, h·|a_i| + r·sqrt(1 − a_i²).
                let e = axis.abs() * half_height
                    + (DVec3::ONE - axis * axis).max(DVec3::ZERO).powf(0.5) * radius;
                Some(Aabb::new(centre - e, centre + e))
            }
        }
    }

    /// Whether the shape is bounded and convex (what a medium needs).
    pub fn is_bounded(&self) -> bool {
        !matches!(self, Shape::Plane { .. })
    }

    /// Short name for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Plane { .. } => "plane",
            Shape::Sphere { .. } => "sphere",
            Shape::Box { .. } => "box",
            Shape::Cylinder { .. } => "cylinder",
        }
    }
}

fn slab(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
        } else {
            let p = (lo[a] - o[a]) / d[a];
            let q = (hi[a] - o[a]) / d[a];
            t0 = t0.max(p.min(q));
            t1 = t1.min(p.max(q));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shapes() -> Vec<Shape> {
        vec![
            Shape::Plane {
                point: DVec3::new(0.0, -0.5, 0.0),
                normal: DVec3::new(0.3, 1.0, 0.1).normalize(),
            },
            Shape::Sphere {
                centre: DVec3::new(0.1, 0.2, -0.1),
                radius: 0.6,
            },
            Shape::Box {
                centre: DVec3::new(-0.1, 0.0, 0.2),
                half: DVec3::new(0.5, 0.3, 0.7),
                rotation: DMat3::IDENTITY,
            },
            Shape::Box {
                centre: DVec3::new(0.1, -0.1, 0.0),
                half: DVec3::new(0.6, 0.2, 0.4),
                rotation: DMat3::from_quat(glam::DQuat::from_euler(
                    glam::EulerRot::ZYX,
                    0.4,
                    -0.7,
                    1.1,
                )),
            },
            Shape::Cylinder {
                centre: DVec3::new(0.0, 0.1, 0.0),
                axis: DVec3::new(1.0, 2.0, 0.5).normalize(),
                radius: 0.4,
                half_height: 0.6,
            },
        ]
    }

    /// The interval, the signed distance and the normal must agree: inside
    /// the interval the SDF is negative, outside positive, at the ends zero,
    /// and the normal there matches the SDF gradient.
    #[test]
    fn intervals_sdf_and_normals_agree() {
        let mut rng = crate::rng::Pcg32::new(1, 1);
        for shape in shapes() {
            let mut hits = 0;
            for _ in 0..2000 {
                let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - 2.0;
                let d =
                    (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5).normalize();
                let ray = Ray { origin: o, dir: d };
                let Some((t0, t1)) = shape.interval(&ray) else {
                    for k in 0..50 {
                        assert!(shape.sdf(ray.at(k as f64 * 0.1)) > -1e-9, "{shape:?}");
                    }
                    continue;
                };
                hits += 1;
                for t in [t0, t1] {
                    if t.is_finite() {
                        let p = ray.at(t);
                        assert!(shape.sdf(p).abs() < 1e-9, "{shape:?} sdf {}", shape.sdf(p));
                        let n = shape.normal(p);
                        assert!(
                            n.dot(shape.sdf_gradient(p)) > 0.99,
                            "{shape:?} at {p}: {n} vs {}",
                            shape.sdf_gradient(p)
                        );
                    }
                }
                if t0.is_finite() && t1.is_finite() && t1 - t0 > 1e-6 {
                    assert!(shape.sdf(ray.at(0.5 * (t0 + t1))) < 0.0);
                }
                if t0.is_finite() {
                    assert!(shape.sdf(ray.at(t0 - 0.01)) > 0.0);
                }
            }
            assert!(hits > 100, "{shape:?} hit only {hits} times");
        }
    }

    /// The bounds of every bounded shape (cylinder, turned box included)
    /// contain every point inside it.
    #[test]
    fn bounds_contain_the_shape() {
        for s in shapes().iter().filter(|s| s.is_bounded()) {
            let b = s.bounds().unwrap();
            let mut rng = crate::rng::Pcg32::new(2, 1);
            let mut inside = 0;
            for _ in 0..20_000 {
                let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 3.0 - 1.5;
                if s.sdf(p) < 0.0 {
                    inside += 1;
                    assert!(b.contains(p), "{s:?} at {p}");
                }
            }
            assert!(inside > 100, "{s:?}");
        }
    }

    /// A turned box is the axis-aligned box seen in its own frame: the
    /// same signed distance at corresponding points.
    #[test]
    fn turned_box_is_the_box_in_its_frame() {
        let Shape::Box {
            centre,
            half,
            rotation,
        } = shapes()[3].clone()
        else {
            panic!()
        };
        let aligned = Shape::Box {
            centre: DVec3::ZERO,
            half,
            rotation: DMat3::IDENTITY,
        };
        let turned = &shapes()[3];
        let mut rng = crate::rng::Pcg32::new(3, 1);
        for _ in 0..500 {
            let local = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0;
            let world = centre + rotation * local;
            assert!((turned.sdf(world) - aligned.sdf(local)).abs() < 1e-12);
        }
    }
}
