//! Irradiance from a probe, the figure an independent renderer can measure
//! at the object's centre: E(n) = ∫ L(ω) max(0, n·ω) dω over the texels'
//! solid angles, and the same from SG lobes (what the fit hands to shading)
//! by adaptive quadrature.

use glam::DVec3;

use super::direction_map::DirectionMap;
use crate::sg::quadrature::integrate_sphere;
use crate::sg::Sg64;

/// E(n) from probe texels laid out by `map` (rgb of each texel, row by
/// row), each texel's mean radiance times its solid angle and the cosine at
/// its centre.
pub fn probe_irradiance(map: &DirectionMap, texels: &[[f64; 4]], n: DVec3) -> DVec3 {
    texels
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (x, y) = (i as u32 % map.width, i as u32 / map.width);
            let cos = map.direction(x, y).dot(n).max(0.0);
            DVec3::new(t[0], t[1], t[2]) * cos * map.solid_angle(x, y)
        })
        .sum()
}

/// E(n) from SG lobes, each integrated around its own axis to a relative
/// tolerance of about 1e-6 of its energy.
pub fn lobes_irradiance(lobes: &[Sg64], n: DVec3) -> DVec3 {
    lobes
        .iter()
        .map(|g| {
            let tol = 1e-6 * Sg64::sphere_factor(g.sharpness);
            let e = integrate_sphere(|v| g.weight(v) * v.dot(n).max(0.0), g.direction, tol);
            g.amplitude * e
        })
        .sum()
}

/// The six axis directions ±x, ±y, ±z with their names.
pub const AXES: [(&str, DVec3); 6] = [
    ("+x", DVec3::X),
    ("-x", DVec3::NEG_X),
    ("+y", DVec3::Y),
    ("-y", DVec3::NEG_Y),
    ("+z", DVec3::Z),
    ("-z", DVec3::NEG_Z),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::probe::MapKind;
    use std::f64::consts::PI;

    #[test]
    fn a_uniform_sky_gives_pi_and_a_lobe_its_closed_form() {
        let map = DirectionMap::new(MapKind::Octahedral, 32);
        let texels = vec![[1.0, 2.0, 3.0, 0.0]; map.texels()];
        let e = probe_irradiance(&map, &texels, DVec3::Y);
        assert!(
            (e / DVec3::new(PI, 2.0 * PI, 3.0 * PI) - DVec3::ONE)
                .abs()
                .max_element()
                < 5e-3
        );
        // A lobe on the normal: E = 2π μ (λ − 1 + e^{−λ}) / λ².
        for l in [0.5, 10.0, 1e4] {
            let g = Sg64 {
                direction: DVec3::Y,
                sharpness: l,
                amplitude: DVec3::ONE,
            };
            let want = 2.0 * PI * (l - 1.0 + (-l).exp()) / (l * l);
            let got = lobes_irradiance(&[g], DVec3::Y).x;
            assert!((got / want - 1.0).abs() < 1e-5, "λ {l}: {got} vs {want}");
        }
    }
}
