//! The one-sided rectangle a quad emitter emits from: sampling it by area
//! and its exact solid angle from a point.

use glam::DVec3;

/// A rectangle that faces one way: centre `centre`, half-extent vectors `u`
/// and `v` (perpendicular), and unit `normal` = û × v̂, the side it lights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// Centre.
    pub centre: DVec3,
    /// Half the width, as a vector along the face.
    pub u: DVec3,
    /// Half the height, as a vector along the face.
    pub v: DVec3,
    /// Unit normal of the lit side.
    pub normal: DVec3,
}

impl Face {
    /// Its area.
    pub fn area(&self) -> f64 {
        4.0 * self.u.length() * self.v.length()
    }

    /// The point at (s, t) ∈ [0, 1]²; uniform (s, t) give area-uniform points.
    pub fn point(&self, s: f64, t: f64) -> DVec3 {
        self.centre + (2.0 * s - 1.0) * self.u + (2.0 * t - 1.0) * self.v
    }

    /// Its four corners, counter-clockwise seen from the lit side.
    pub fn corners(&self) -> [DVec3; 4] {
        let (c, u, v) = (self.centre, self.u, self.v);
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }

    /// Whether `x` is on the lit side.
    pub fn lights(&self, x: DVec3) -> bool {
        (x - self.centre).dot(self.normal) > 0.0
    }

    /// The solid angle it subtends from `x` (zero from behind): exact, as
    /// two triangles by Van Oosterom and Strackee's formula.
    pub fn solid_angle(&self, x: DVec3) -> f64 {
        if !self.lights(x) {
            return 0.0;
        }
        let [a, b, c, d] = self.corners().map(|p| p - x);
        triangle_solid_angle(a, b, c) + triangle_solid_angle(a, c, d)
    }
}

/// The solid angle of the triangle with vertices `a`, `b`, `c` (relative to
/// the viewpoint), unsigned.
fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * num.atan2(den).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn square(half: f64) -> Face {
        Face {
            centre: DVec3::ZERO,
            u: DVec3::X * half,
            v: DVec3::Z * -half,
            normal: DVec3::Y,
        }
    }

    /// Closed forms: a face seen from far away subtends A cosθ / d²; from
    /// just in front of its centre it fills a hemisphere (2π); from behind,
    /// nothing; a square of half-side a seen from height h on its axis
    /// subtends 4 asin(a² / (a² + h²)).
    #[test]
    fn solid_angle_matches_closed_forms() {
        let f = square(0.5);
        let far = DVec3::new(0.0, 100.0, 0.0);
        assert!((f.solid_angle(far) / (1.0 / 1e4) - 1.0).abs() < 1e-4);
        let tilted = DVec3::new(60.0, 80.0, 0.0);
        assert!((f.solid_angle(tilted) / (0.8 / 1e4) - 1.0).abs() < 1e-3);
        assert!((f.solid_angle(DVec3::new(0.0, 1e-9, 0.0)) - 2.0 * PI).abs() < 1e-6);
        assert_eq!(f.solid_angle(DVec3::new(0.0, -1.0, 0.0)), 0.0);
        for h in [0.1, 0.5, 2.0] {
            let a: f64 = 0.5;
            let exact = 4.0 * (a * a / (a * a + h * h)).asin();
            assert!((f.solid_angle(DVec3::Y * h) - exact).abs() < 1e-12, "{h}");
        }
        assert!((f.area() - 1.0).abs() < 1e-15);
    }
}
