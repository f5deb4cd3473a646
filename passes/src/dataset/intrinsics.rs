//! Pinhole intrinsics with the OpenCV lens distortion (k1, k2, p1, p2), and
//! the exact inverse of that distortion, so that each pixel's ray is the
//! one the lens bent into it.
//!
//! Normalised image coordinates (x, y) are OpenCV's: x right, y down, the
//! camera looking along +z. A point (x, y) lands at
//! x_d = x·(1 + k1 r² + k2 r⁴) + 2 p1 x y + p2 (r² + 2x²),
//! y_d = y·(1 + k1 r² + k2 r⁴) + p1 (r² + 2y²) + 2 p2 x y, r² = x² + y²,
//! and at pixel (fx x_d + cx, fy y_d + cy).

use glam::DVec3;

/// Lens distortion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distortion {
    /// An ideal pinhole.
    None,
    /// OpenCV's radial (k1, k2) and tangential (p1, p2) model.
    OpenCv {
        /// Radial, r².
        k1: f64,
        /// Radial, r⁴.
        k2: f64,
        /// Tangential.
        p1: f64,
        /// Tangential.
        p2: f64,
    },
}

/// Newton steps [`Distortion::undistort`] takes at most.
pub const UNDISTORT_STEPS: usize = 40;

/// How close (in normalised coordinates) the distorted estimate must come
/// to the observed point for the inverse to count as found.
pub const UNDISTORT_TOLERANCE: f64 = 1e-14;

impl Distortion {
    /// Where the lens puts the normalised point (x, y).
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        match *self {
            Distortion::None => (x, y),
            Distortion::OpenCv { k1, k2, p1, p2 } => {
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + k2 * r2);
                (
                    x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                    y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
                )
            }
        }
    }

    /// The 2 × 2 Jacobian of [`Self::distort`] at (x, y), row-major.
    fn jacobian(&self, x: f64, y: f64) -> [f64; 4] {
        match *self {
            Distortion::None => [1.0, 0.0, 0.0, 1.0],
            Distortion::OpenCv { k1, k2, p1, p2 } => {
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + k2 * r2);
                // ∂radial/∂x = (2k1 + 4k2 r²)·x.
                let dr = 2.0 * k1 + 4.0 * k2 * r2;
                [
                    radial + x * dr * x + 2.0 * p1 * y + 6.0 * p2 * x,
                    x * dr * y + 2.0 * p1 * x + 2.0 * p2 * y,
                    y * dr * x + 2.0 * p1 * x + 2.0 * p2 * y,
                    radial + y * dr * y + 6.0 * p1 * y + 2.0 * p2 * x,
                ]
            }
        }
    }

    /// The normalised point the lens moved to (xd, yd): Newton's method from
    /// (xd, yd), to [`UNDISTORT_TOLERANCE`]. None where it does not converge
    /// (a point beyond where the model folds back on itself).
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        if *self == Distortion::None {
            return Some((xd, yd));
        }
        let (mut x, mut y) = (xd, yd);
        for _ in 0..UNDISTORT_STEPS {
            let (fx, fy) = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex.hypot(ey) <= UNDISTORT_TOLERANCE * (1.0 + xd.hypot(yd)) {
                return Some((x, y));
            }
            let [a, b, c, d] = self.jacobian(x, y);
            let det = a * d - b * c;
            if !det.is_finite() || det.abs() < 1e-12 {
                return None;
            }
            x -= (d * ex - b * ey) / det;
            y -= (a * ey - c * ex) / det;
            if !(x.is_finite() && y.is_finite()) {
                return None;
            }
        }
        None
    }
}

/// A camera's intrinsics for one image size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length in pixels, horizontally.
    pub fx: f64,
    /// Focal length in pixels, vertically.
    pub fy: f64,
    /// Principal point, pixels from the left edge.
    pub cx: f64,
    /// Principal point, pixels from the top edge.
    pub cy: f64,
    /// The lens' distortion.
    pub distortion: Distortion,
}

impl Intrinsics {
    /// An ideal pinhole of `width` × `height` square pixels, centred, whose
    /// vertical field of view is `fov_y` degrees (a scene camera's).
    pub fn centred(width: u32, height: u32, fov_y: f64) -> Self {
        let f = 0.5 * height as f64 / (0.5 * fov_y.to_radians()).tan();
        Self {
            width,
            height,
            fx: f,
            fy: f,
            cx: 0.5 * width as f64,
            cy: 0.5 * height as f64,
            distortion: Distortion::None,
        }
    }

    /// The unit direction, in the OpenGL camera frame the transforms use
    /// (x right, y up, looking along −z), of the ray through image position
    /// (u, v) in pixels (pixel centres at +0.5, v downwards); None where
    /// the distortion cannot be inverted.
    pub fn direction(&self, u: f64, v: f64) -> Option<DVec3> {
        let xd = (u - self.cx) / self.fx;
        let yd = (v - self.cy) / self.fy;
        let (x, y) = self.distortion.undistort(xd, yd)?;
        Some(DVec3::new(x, -y, -1.0).normalize())
    }

    /// Where a camera-frame direction (OpenGL frame) lands, in pixels; None
    /// behind the camera. The inverse of [`Self::direction`].
    pub fn project(&self, d: DVec3) -> Option<(f64, f64)> {
        if d.z >= 0.0 {
            return None;
        }
        let (x, y) = (d.x / -d.z, -d.y / -d.z);
        let (xd, yd) = self.distortion.distort(x, y);
        Some((self.fx * xd + self.cx, self.fy * yd + self.cy))
    }

    /// Why these intrinsics cannot be used, if they cannot.
    pub fn problem(&self) -> Option<String> {
        if self.width == 0 || self.height == 0 {
            return Some(format!("image size {}x{}", self.width, self.height));
        }
        let finite = [self.fx, self.fy, self.cx, self.cy]
            .iter()
            .all(|v| v.is_finite());
        if !finite || self.fx <= 0.0 || self.fy <= 0.0 {
            return Some(format!(
                "focal lengths {} {} and principal point {} {} must be finite, the focal lengths positive",
                self.fx, self.fy, self.cx, self.cy
            ));
        }
        if let Distortion::OpenCv { k1, k2, p1, p2 } = self.distortion {
            if ![k1, k2, p1, p2].iter().all(|v| v.is_finite()) {
                return Some("distortion coefficients must be finite".into());
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Undistortion inverts distortion to 1e-12 over the image of a strong
    /// barrel and a strong pincushion lens with tangential terms.
    #[test]
    fn undistortion_inverts_the_lens_exactly() {
        for d in [
            Distortion::OpenCv {
                k1: -0.28,
                k2: 0.07,
                p1: 1e-3,
                p2: -5e-4,
            },
            Distortion::OpenCv {
                k1: 0.12,
                k2: 0.02,
                p1: -2e-3,
                p2: 1e-3,
            },
        ] {
            for i in 0..=20 {
                for j in 0..=20 {
                    let (x, y) = (-0.8 + 0.08 * i as f64, -0.6 + 0.06 * j as f64);
                    let (xd, yd) = d.distort(x, y);
                    let (u, w) = d.undistort(xd, yd).expect("converges");
                    assert!(
                        (u - x).abs() < 1e-12 && (w - y).abs() < 1e-12,
                        "{d:?} {x} {y}: {u} {w}"
                    );
                }
            }
        }
    }

    /// The Jacobian matches central differences.
    #[test]
    fn jacobian_matches_finite_differences() {
        let d = Distortion::OpenCv {
            k1: -0.2,
            k2: 0.05,
            p1: 3e-3,
            p2: -2e-3,
        };
        let (x, y, h) = (0.3, -0.45, 1e-6);
        let j = d.jacobian(x, y);
        let (a, b) = (d.distort(x + h, y), d.distort(x - h, y));
        let (c, e) = (d.distort(x, y + h), d.distort(x, y - h));
        let num = [
            (a.0 - b.0) / (2.0 * h),
            (c.0 - e.0) / (2.0 * h),
            (a.1 - b.1) / (2.0 * h),
            (c.1 - e.1) / (2.0 * h),
        ];
        for k in 0..4 {
            assert!((num[k] - j[k]).abs() < 1e-8, "{k}: {} vs {}", num[k], j[k]);
        }
    }

    /// A pixel's ray projects back onto the pixel, through the lens.
    #[test]
    fn a_pixel_ray_projects_back_to_its_pixel() {
        let k = Intrinsics {
            width: 640,
            height: 480,
            fx: 500.0,
            fy: 510.0,
            cx: 322.5,
            cy: 237.0,
            distortion: Distortion::OpenCv {
                k1: -0.1,
                k2: 0.01,
                p1: 1e-3,
                p2: 2e-3,
            },
        };
        for (u, v) in [(0.5, 0.5), (639.5, 479.5), (320.0, 240.0), (10.0, 400.0)] {
            let d = k.direction(u, v).unwrap();
            let (pu, pv) = k.project(d).unwrap();
            assert!(
                (pu - u).abs() < 1e-8 && (pv - v).abs() < 1e-8,
                "{u} {v}: {pu} {pv}"
            );
        }
        // The principal point looks straight down −z.
        let d = k.direction(322.5, 237.0).unwrap();
        assert!((d - DVec3::NEG_Z).length() < 1e-12);
    }
}
