//! Validating one `[[recipe.primitives]]` entry into a [`Primitive`]: its
//! shape's keys, its material, and where an emitter stands.

use glam::{DMat3, DQuat, DVec3, EulerRot};

use super::spec::PrimitiveSpec;
use super::{Face, Primitive, Shape};
use crate::geometry::Aabb;

/// A quad's default thickness (scene units): thin next to any field's
/// voxel, so the field shows a panel, yet a solid the path tracer can hit.
pub const QUAD_THICKNESS: f64 = 0.01;

/// The shape keys, by name, and which primitive types take them (`rotation`
/// and a quad's `up` and `thickness` are optional).
const SHAPE_KEYS: [&str; 11] = [
    "point",
    "normal",
    "center",
    "radius",
    "size",
    "axis",
    "height",
    "width",
    "thickness",
    "up",
    "rotation",
];

fn positive(name: &str, v: Option<f64>) -> Result<f64, String> {
    match v {
        Some(x) if x.is_finite() && x > 0.0 => Ok(x),
        Some(x) => Err(format!("`{name}` = {x} must be finite and > 0")),
        None => Err(format!("missing `{name}`")),
    }
}

fn vector(name: &str, v: Option<DVec3>) -> Result<DVec3, String> {
    match v {
        Some(x) if x.is_finite() => Ok(x),
        Some(x) => Err(format!("`{name}` = {x} must be finite")),
        None => Err(format!("missing `{name}`")),
    }
}

fn direction(name: &str, v: Option<DVec3>) -> Result<DVec3, String> {
    let d = vector(name, v)?;
    d.try_normalize()
        .ok_or_else(|| format!("`{name}` = {d} must be a non-zero vector"))
}

/// World from box axes for `rotation` (degrees, extrinsic X then Y then Z,
/// as objects are turned).
pub fn rotation_matrix(degrees: DVec3) -> DMat3 {
    let r = degrees * (std::f64::consts::PI / 180.0);
    DMat3::from_quat(DQuat::from_euler(EulerRot::ZYX, r.z, r.y, r.x))
}

/// A quad: the box behind its face, and the face. Its height runs along
/// `up` made perpendicular to the normal (default: world +y, or −z for a
/// face looking straight up or down).
fn quad(p: &PrimitiveSpec) -> Result<(Shape, Face), String> {
    let centre = vector("center", p.center)?;
    let normal = direction("normal", p.normal)?;
    let (width, height) = (positive("width", p.width)?, positive("height", p.height)?);
    let thickness = match p.thickness {
        None => QUAD_THICKNESS,
        t => positive("thickness", t)?,
    };
    let up = match p.up {
        Some(_) => direction("up", p.up)?,
        None if normal.y.abs() > 0.9 => DVec3::NEG_Z,
        None => DVec3::Y,
    };
    let v = (up - normal * up.dot(normal))
        .try_normalize()
        .filter(|_| up.dot(normal).abs() < 0.999)
        .ok_or_else(|| format!("`up` = {up} must not be parallel to `normal`"))?;
    let u = v.cross(normal);
    let face = Face {
        centre,
        u: u * (0.5 * width),
        v: v * (0.5 * height),
        normal,
    };
    let shape = Shape::Box {
        centre: centre - normal * (0.5 * thickness),
        half: DVec3::new(0.5 * width, 0.5 * height, 0.5 * thickness),
        rotation: DMat3::from_cols(u, v, normal),
    };
    Ok((shape, face))
}

/// Validates one primitive of a recipe with `bounds`.
pub(crate) fn parse(p: PrimitiveSpec, bounds: &Aabb) -> Result<Primitive, String> {
    let given = |name: &str| match name {
        "point" => p.point.is_some(),
        "normal" => p.normal.is_some(),
        "center" => p.center.is_some(),
        "radius" => p.radius.is_some(),
        "size" => p.size.is_some(),
        "axis" => p.axis.is_some(),
        "height" => p.height.is_some(),
        "width" => p.width.is_some(),
        "thickness" => p.thickness.is_some(),
        "up" => p.up.is_some(),
        "rotation" => p.rotation.is_some(),
        _ => false,
    };
    let keys: &[&str] = match p.kind.as_str() {
        "plane" => &["point", "normal"],
        "sphere" => &["center", "radius"],
        "box" => &["center", "size", "rotation"],
        "cylinder" => &["center", "axis", "radius", "height"],
        "quad" => &["center", "normal", "width", "height", "thickness", "up"],
        other => {
            return Err(format!(
                "unknown type `{other}` (plane, sphere, box, cylinder, quad)"
            ))
        }
    };
    for k in SHAPE_KEYS {
        if given(k) && !keys.contains(&k) {
            return Err(format!("`{k}` does not apply to a {}", p.kind));
        }
    }
    let mut face = None;
    let shape = match p.kind.as_str() {
        "plane" => Shape::Plane {
            point: vector("point", p.point)?,
            normal: direction("normal", p.normal)?,
        },
        "sphere" => Shape::Sphere {
            centre: vector("center", p.center)?,
            radius: positive("radius", p.radius)?,
        },
        "box" => {
            let size = vector("size", p.size)?;
            if size.min_element() <= 0.0 {
                return Err(format!("`size` = {size} must be > 0 on every axis"));
            }
            let rotation = match p.rotation {
                None => DMat3::IDENTITY,
                r => rotation_matrix(vector("rotation", r)?),
            };
            Shape::Box {
                centre: vector("center", p.center)?,
                half: size * 0.5,
                rotation,
            }
        }
        "quad" => {
            let (shape, f) = quad(&p)?;
            face = Some(f);
            shape
        }
        _ => Shape::Cylinder {
            centre: vector("center", p.center)?,
            axis: direction("axis", p.axis)?,
            radius: positive("radius", p.radius)?,
            half_height: positive("height", p.height)? * 0.5,
        },
    };
    let unit = |v: DVec3| v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0;
    let albedo = p.albedo.unwrap_or(DVec3::splat(0.5));
    if !unit(albedo) {
        return Err(format!(
            "`albedo` = {albedo} must lie in [0, 1] per channel"
        ));
    }
    if let Some(c) = p.checker {
        if !(c.size.is_finite() && c.size > 0.0) {
            return Err(format!(
                "`checker.size` = {} must be finite and > 0",
                c.size
            ));
        }
        if !unit(c.albedo) {
            return Err(format!(
                "`checker.albedo` = {} must lie in [0, 1] per channel",
                c.albedo
            ));
        }
    }
    let emission = p.emission.unwrap_or(DVec3::ZERO);
    if !(emission.is_finite() && emission.min_element() >= 0.0) {
        return Err(format!("`emission` = {emission} must be finite and ≥ 0"));
    }
    if emission.max_element() > super::RADIANCE_LIMIT {
        return Err(format!(
            "`emission` = {emission} is above the radiance limit {:e}",
            super::RADIANCE_LIMIT
        ));
    }
    let medium_density = match p.density {
        None => None,
        Some(d) => {
            if !shape.is_bounded() || face.is_some() {
                return Err(format!("a {} cannot be a medium (`density`)", p.kind));
            }
            if emission.max_element() > 0.0 {
                return Err("a medium (`density`) cannot emit".into());
            }
            if p.checker.is_some() {
                return Err("a medium (`density`) cannot have a `checker`".into());
            }
            Some(positive("density", Some(d))?)
        }
    };
    let prim = Primitive {
        name: p.name,
        shape,
        albedo,
        checker: p.checker,
        emission,
        face,
        medium_density,
        in_field: p.in_field,
    };
    if prim.is_emitter() {
        if !matches!(prim.shape, Shape::Sphere { .. }) && prim.face.is_none() {
            return Err(format!(
                "a {} cannot emit: only spheres and quads may (the path tracer samples those)",
                p.kind
            ));
        }
        let b = prim.shape.bounds().expect("emitters are bounded");
        match prim.in_field {
            None => return Err(
                "an emitter must say `in_field = true` or `false` (whether the field contains it)"
                    .into(),
            ),
            Some(true) if !bounds.contains_box(&b) => {
                return Err(
                    "declared `in_field = true` but it is not inside the recipe's bounds".into(),
                )
            }
            Some(false) if bounds.overlaps(&b) => {
                return Err(
                    "declared `in_field = false` but it overlaps the recipe's bounds".into(),
                )
            }
            _ => {}
        }
    } else if prim.in_field.is_some() {
        return Err("`in_field` applies to emitters only".into());
    }
    Ok(prim)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> PrimitiveSpec {
        toml::from_str(text).unwrap()
    }

    fn bounds() -> Aabb {
        Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0))
    }

    /// A quad's face is where the scene puts it, faces its normal, and is
    /// the front of its box: the box's surface at the face's centre, its
    /// normal there the face's.
    #[test]
    fn quad_face_is_the_front_of_its_box() {
        let p = parse(
            spec(
                r#"name = "softbox"
                type = "quad"
                center = [0.0, 0.5, -0.8]
                normal = [0.0, -1.0, 1.0]
                width = 0.6
                height = 0.3
                emission = [5.0, 5.0, 5.0]
                in_field = true"#,
            ),
            &bounds(),
        )
        .unwrap();
        let f = p.face.unwrap();
        let n = DVec3::new(0.0, -1.0, 1.0).normalize();
        assert!((f.normal - n).length() < 1e-12);
        assert!((f.area() - 0.18).abs() < 1e-12);
        assert!(p.shape.sdf(f.centre).abs() < 1e-12);
        assert!((p.shape.normal(f.centre + 1e-9 * n) - n).length() < 1e-9);
        for c in f.corners() {
            assert!(p.shape.sdf(c).abs() < 1e-12, "{c}");
        }
        assert_eq!(p.emission_at(n), DVec3::splat(5.0));
        assert_eq!(p.emission_at(-n), DVec3::ZERO);
    }

    #[test]
    fn bad_primitives_are_refused_naming_the_key() {
        let b = bounds();
        let cases = [
            (
                r#"name = "a"
                type = "box"
                center = [0, 0, 0]
                size = [1, 1, 1]
                emission = [1, 1, 1]
                in_field = true"#,
                "a box cannot emit",
            ),
            (
                r#"name = "a"
                type = "quad"
                center = [0, 0, 0]
                normal = [0, 1, 0]
                up = [0, 2, 0]
                width = 1
                height = 1"#,
                "`up`",
            ),
            (
                r#"name = "a"
                type = "sphere"
                center = [0, 0, 0]
                radius = 0.5
                rotation = [0, 10, 0]"#,
                "`rotation` does not apply to a sphere",
            ),
            (
                r#"name = "a"
                type = "box"
                center = [0, 0, 0]
                size = [1, 1, 1]
                checker = { size = 0.0, albedo = [0.1, 0.1, 0.1] }"#,
                "`checker.size`",
            ),
            (
                r#"name = "a"
                type = "quad"
                center = [0, 0, 0]
                normal = [0, 1, 0]
                width = 1
                height = 1
                density = 2.0"#,
                "a quad cannot be a medium",
            ),
        ];
        for (text, want) in cases {
            let err = parse(spec(text), &b).unwrap_err();
            assert!(err.contains(want), "{err} lacks {want}");
        }
    }
}
