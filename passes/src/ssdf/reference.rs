//! Brute-force references the shadow passes are judged by: S(d; x) found
//! by ray casting alone, and visibility integrals (the self-shadow factor
//! Γ_k and the cast-shadow factor ρ) by quadrature over directions with a
//! ray cast per direction. None of them uses the SSDF or f_h.

use std::f64::consts::PI;

use glam::DVec3;

use crate::geometry::MeshScene;
use crate::geometry::Ray;

/// Whether the ray from `x` along `d` hits the scene.
pub fn hits(scene: &MeshScene, x: DVec3, d: DVec3) -> bool {
    scene.occluded(&Ray { origin: x, dir: d }, 0.0, f64::INFINITY)
}

/// S(d; x) by ray casting: along `azimuths` great circles through d, walk
/// away from d in steps of `step` radians until the ray's verdict (hit or
/// miss) changes, then bisect the change to 10⁻⁷ rad; the smallest angle
/// found, negative where d hits (±π if nothing changes).
pub fn ssdf_by_ray_casting(scene: &MeshScene, x: DVec3, d: DVec3, azimuths: u32, step: f64) -> f64 {
    let inside = hits(scene, x, d);
    let (t, b) = d.any_orthonormal_pair();
    let mut best = PI;
    for k in 0..azimuths {
        let phi = 2.0 * PI * k as f64 / azimuths as f64;
        let axis = t * phi.cos() + b * phi.sin();
        let at = |psi: f64| d * psi.cos() + axis * psi.sin();
        let mut lo = 0.0;
        while lo < best {
            let hi = (lo + step).min(PI);
            if hits(scene, x, at(hi)) != inside {
                let (mut a, mut c) = (lo, hi);
                while c - a > 1e-7 {
                    let m = 0.5 * (a + c);
                    if hits(scene, x, at(m)) != inside {
                        c = m;
                    } else {
                        a = m;
                    }
                }
                best = best.min(c);
                break;
            }
            if hi >= PI {
                break;
            }
            lo = hi;
        }
    }
    if inside {
        -best
    } else {
        best
    }
}
