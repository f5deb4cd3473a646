//! Lobes of the distant light L_env sharper than the SG fit can hold (a
//! ceiling bulb seen from the object has sharpness ~10⁴; the fit stops at
//! about 140 on a 32 × 32 probe, [`crate::sgfit::model::max_sharpness`]).
//! Traced into the probe and refitted, such a lobe comes out as a broad
//! one: its highlight spreads over a mirror, its shadow over the floor.
//! Instead it skips the probe and is shaded as it is, with its amplitude
//! scaled by the field's transmittance towards it (what the probe would
//! have weighted it by): the "direct" lobes, appended after the fitted
//! ones. This goes beyond the paper, which refits all of L_env.

use glam::DVec3;

use crate::sg::Sg64;

/// L_env split at the fit's sharpness limit.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SplitEnvironment {
    /// Lobes the probe traces and the fit holds (sharpness ≤ the limit).
    pub broad: Vec<Sg64>,
    /// Lobes shaded directly (sharper than the limit, with some light).
    pub sharp: Vec<Sg64>,
}

/// Splits `environment` at sharpness `limit`: lobes sharper than it, and
/// not black, are shaded directly; the rest go through the probe.
pub fn split_environment(environment: &[Sg64], limit: f64) -> SplitEnvironment {
    let mut split = SplitEnvironment::default();
    for g in environment {
        if g.sharpness > limit && g.amplitude.max_element() > 0.0 {
            split.sharp.push(*g);
        } else {
            split.broad.push(*g);
        }
    }
    split
}

/// The `side`² directions along which a sharp lobe's transmittance is
/// averaged: stratified cell centres of the lobe's own distribution
/// (∝ exp(λ(v·p − 1)), [`Sg64::sample`]), so each carries the same share of
/// its light; one ray (`side` = 1) is the axis. The directions depend on
/// the lobe alone, not on where the object stands.
pub fn lobe_rays(lobe: &Sg64, side: u32) -> Vec<DVec3> {
    if side <= 1 {
        return vec![lobe.direction.normalize()];
    }
    let unit = Sg64 {
        direction: lobe.direction.normalize(),
        ..*lobe
    };
    let n = side as f64;
    (0..side)
        .flat_map(|j| (0..side).map(move |i| (i, j)))
        .map(|(i, j)| unit.sample([(j as f64 + 0.5) / n, (i as f64 + 0.5) / n]))
        .collect()
}

/// `lobe` as seen through a field of transmittance `transmittance` along
/// it (in [0, 1]): the same lobe, its amplitude scaled.
pub fn attenuated(lobe: &Sg64, transmittance: f64) -> Sg64 {
    Sg64 {
        amplitude: lobe.amplitude * transmittance.clamp(0.0, 1.0),
        ..*lobe
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lobe(sharpness: f64) -> Sg64 {
        Sg64 {
            direction: DVec3::new(0.3, 1.0, -0.2).normalize(),
            sharpness,
            amplitude: DVec3::new(5.0, 4.0, 3.0),
        }
    }

    #[test]
    fn the_split_keeps_every_lobe_once() {
        let black = Sg64 {
            amplitude: DVec3::ZERO,
            ..lobe(1e4)
        };
        let env = [lobe(10.0), lobe(1e4), lobe(140.0), black];
        let s = split_environment(&env, 140.0);
        assert_eq!(s.sharp, vec![lobe(1e4)]);
        assert_eq!(s.broad, vec![lobe(10.0), lobe(140.0), black]);
    }

    /// The rays spread as the lobe does: their mean cosine to the axis is
    /// the lobe's (1 − 1/λ for a sharp lobe; 6 × 6 cell centres put 1 − cos
    /// 5.7 % short, the midpoint rule on its exponential tail), and they
    /// stay within a few widths of the axis.
    #[test]
    fn rays_follow_the_lobe() {
        for l in [200.0, 1e3, 1e4, 1e5] {
            let g = lobe(l);
            let rays = lobe_rays(&g, 6);
            assert_eq!(rays.len(), 36);
            let mean: f64 = rays.iter().map(|r| r.dot(g.direction)).sum::<f64>() / 36.0;
            let expected = 1.0 - 1.0 / l;
            assert!(
                ((1.0 - mean) - (1.0 - expected)).abs() < 0.07 * (1.0 - expected),
                "λ {l}: 1 − mean cos {} vs {}",
                1.0 - mean,
                1.0 - expected
            );
            for r in &rays {
                assert!((r.length() - 1.0).abs() < 1e-12);
                assert!(r.dot(g.direction) > 1.0 - 8.0 / l);
            }
        }
        assert_eq!(lobe_rays(&lobe(1e4), 1), vec![lobe(1e4).direction]);
    }

    #[test]
    fn attenuation_scales_the_amplitude_only() {
        let g = lobe(1e4);
        let a = attenuated(&g, 0.25);
        assert_eq!(a.direction, g.direction);
        assert_eq!(a.sharpness, g.sharpness);
        assert_eq!(a.amplitude, g.amplitude * 0.25);
        assert_eq!(attenuated(&g, 2.0).amplitude, g.amplitude);
        assert_eq!(attenuated(&g, -1.0).amplitude, DVec3::ZERO);
    }
}
