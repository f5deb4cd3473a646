//! The SG shading against the exact BRDF integrated by adaptive quadrature
//! under analytic SG lighting: the error of the BRDF's SG form alone
//! (no probe, no fit), per material class and NDF lobe count.

use glam::DVec3;

use super::disney::{self, SurfaceMaterial};
use super::{shade_sg, NdfLobes};
use crate::sg::quadrature::integrate_sphere;
use crate::sg::Sg64;

pub(crate) fn materials() -> [(&'static str, SurfaceMaterial); 3] {
    [
        (
            "diffuse",
            SurfaceMaterial {
                albedo: DVec3::new(0.8, 0.6, 0.4),
                roughness: 1.0,
                metallic: 0.0,
            },
        ),
        (
            "rough",
            SurfaceMaterial {
                albedo: DVec3::new(0.5, 0.5, 0.5),
                roughness: 0.6,
                metallic: 0.5,
            },
        ),
        (
            "glossy",
            SurfaceMaterial {
                albedo: DVec3::new(1.0, 0.78, 0.34),
                roughness: 0.2,
                metallic: 1.0,
            },
        ),
    ]
}

fn lighting() -> Vec<Sg64> {
    let lobe = |d: DVec3, s: f64, a: f64| Sg64 {
        direction: d.normalize(),
        sharpness: s,
        amplitude: DVec3::splat(a),
    };
    vec![
        lobe(DVec3::new(0.0, 1.0, 0.2), 2.0, 1.0),
        lobe(DVec3::new(0.6, 0.7, 0.1), 12.0, 4.0),
        lobe(DVec3::new(-0.5, 0.6, 0.6), 40.0, 10.0),
    ]
}

/// ∫ f_r(l, v) (n·l) L(l) dl by quadrature (luminance-free: green channel).
fn exact(light: &[Sg64], n: DVec3, v: DVec3, m: &SurfaceMaterial) -> f64 {
    let r = 2.0 * n.dot(v) * n - v;
    integrate_sphere(
        |l| {
            let cos = n.dot(l);
            if cos <= 0.0 {
                return 0.0;
            }
            let radiance: f64 = light.iter().map(|g| g.eval(l).y).sum();
            disney::eval(m, n, v, l).y * cos * radiance
        },
        r,
        1e-7,
    )
}

/// Bounds on the SG form's worst relative error for the diffuse, rough and
/// glossy materials under [`lighting`] (measured 0.014, 0.201 and 0.107
/// with one NDF lobe, plus 10–40 % headroom). The diffuse term takes each
/// lobe's irradiance from Hill's fitted curve (`Sg64::diffuse_irradiance`);
/// with the paper's one-lobe clamped cosine it was 0.110 (that lobe's L2
/// error is 19 %, and the sharpest light lobe sees it pointwise) and the
/// rough material's 0.278. The rough error comes from grazing views,
/// where the isotropic warp λ/(4 n·v) of a broad lobe puts the product
/// axis near the horizon (at 70° the specular part is half the exact
/// one); the glossy one from Fresnel and visibility taken at the product
/// axis.
pub(crate) const SG_FORM_ERROR: [f64; 3] = [0.02, 0.23, 0.12];

/// Worst relative error of the SG shading over views at 0°, 40° and 70°
/// from the normal, turned about it.
pub(crate) fn worst_error(m: &SurfaceMaterial, ndf: &NdfLobes) -> f64 {
    let light = lighting();
    let n = DVec3::Y;
    let mut worst = 0.0f64;
    for deg in [0.0f64, 40.0, 70.0] {
        for phi in [0.0f64, 2.0, 4.0] {
            let t = deg.to_radians();
            let v = DVec3::new(t.sin() * phi.cos(), t.cos(), t.sin() * phi.sin());
            let e = exact(&light, n, v, m);
            let s = shade_sg(&light, n, v, m, ndf).y;
            worst = worst.max((s - e).abs() / e);
        }
    }
    worst
}

/// The SG form's error for each material class, with one NDF lobe: the
/// bounds the GPU end-to-end test builds its tolerances on.
#[test]
fn sg_shading_error_is_bounded_per_material() {
    let ndf = NdfLobes::new(1).unwrap();
    for ((name, m), bound) in materials().into_iter().zip(SG_FORM_ERROR) {
        let e = worst_error(&m, &ndf);
        eprintln!("{name}: worst relative error {e:.4} (bound {bound})");
        assert!(e < bound, "{name}: {e} ≥ {bound}");
    }
}

/// More NDF lobes change the glossy error (measured, printed) and never
/// break the shading (finite, non-negative).
#[test]
fn more_ndf_lobes_stay_finite() {
    let (_, glossy) = materials()[2];
    for n in 1..=super::MAX_NDF_LOBES {
        let e = worst_error(&glossy, &NdfLobes::new(n).unwrap());
        eprintln!("glossy, {n} NDF lobes: worst relative error {e:.4}");
        assert!(e.is_finite() && e < 0.5, "{n}: {e}");
    }
}
