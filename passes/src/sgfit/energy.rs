//! The fit's last step, beyond the paper: the lobes' amplitudes set so that
//! they hold the probe's energy. A least-squares fit is not energy-true
//! where the light's shape is not a lobe's: a disc-shaped lamp or a
//! needle fitted by lobes of bounded sharpness comes out with 5–25 % more
//! energy than the probe holds (measured against Blender Cycles on CUPS and
//! DOG), and shading integrates energy. Each texel's energy Ω_t L_t is
//! shared out among the lobes in proportion to their values there, and
//! each lobe's amplitude is set to its share over its integral; the lobes'
//! total then equals the probe's, channel by channel, and where one lobe
//! dominates it keeps the energy of the light it stands for. Mirrored by
//! the `conserve_energy` kernel of `shaders/sgfit/fit.wgsl`.

use glam::DVec3;

use super::model::ProbeSamples;
use crate::sg::Sg64;

/// `lobes` with their amplitudes set to their shares of the probe's energy.
pub fn conserve_energy(probe: &ProbeSamples, lobes: &[Sg64]) -> Vec<Sg64> {
    let mut share = vec![DVec3::ZERO; lobes.len()];
    for ((d, w), l) in probe
        .directions
        .iter()
        .zip(&probe.weights)
        .zip(&probe.radiance)
    {
        if *w == 0.0 {
            continue;
        }
        let values: Vec<DVec3> = lobes.iter().map(|g| g.eval(*d)).collect();
        let sum: DVec3 = values.iter().sum();
        for (s, v) in share.iter_mut().zip(&values) {
            *s += DVec3::select(sum.cmpgt(DVec3::ZERO), *w * *l * *v / sum, DVec3::ZERO);
        }
    }
    lobes
        .iter()
        .zip(share)
        .map(|(g, s)| Sg64 {
            amplitude: s / Sg64::sphere_factor(g.sharpness),
            ..*g
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::probe::{DirectionMap, MapKind};

    #[test]
    fn the_lobes_hold_the_probes_energy_and_keep_an_exact_fit() {
        let map = DirectionMap::new(MapKind::Octahedral, 16);
        let lobes = vec![
            Sg64 {
                direction: DVec3::Y,
                sharpness: 3.0,
                amplitude: DVec3::new(1.0, 2.0, 0.5),
            },
            Sg64 {
                direction: DVec3::X,
                sharpness: 20.0,
                amplitude: DVec3::new(4.0, 0.0, 1.0),
            },
        ];
        // A probe that is not a sum of lobes: a bright disc and a sky.
        let texels: Vec<[f64; 4]> = (0..map.texels() as u32)
            .map(|i| {
                let d = map.direction(i % 16, i / 16);
                let disc = if d.dot(DVec3::new(0.6, 0.8, 0.0)) > 0.97 {
                    30.0
                } else {
                    0.0
                };
                [0.2 + disc, 0.3, 0.4 + 0.5 * disc, 0.0]
            })
            .collect();
        let probe = ProbeSamples::new(&map, &texels);
        let scaled = conserve_energy(&probe, &lobes);
        let total: DVec3 = scaled.iter().map(|g| g.integral()).sum();
        let energy: DVec3 = probe
            .weights
            .iter()
            .zip(&probe.radiance)
            .map(|(w, l)| *w * *l)
            .sum();
        assert!(
            (total / energy - DVec3::ONE).abs().max_element() < 1e-9,
            "{total} vs {energy}"
        );
        // A probe that is exactly the lobes (on texel centres, with their
        // integral for energy) keeps amplitudes within the quadrature's error.
        let exact: Vec<[f64; 4]> = (0..map.texels() as u32)
            .map(|i| {
                let l: DVec3 = lobes
                    .iter()
                    .map(|g| g.eval(map.direction(i % 16, i / 16)))
                    .sum();
                [l.x, l.y, l.z, 0.0]
            })
            .collect();
        let kept = conserve_energy(&ProbeSamples::new(&map, &exact), &lobes);
        for (a, b) in kept.iter().zip(&lobes) {
            let r = a.amplitude / b.amplitude.max(DVec3::splat(1e-30));
            for c in 0..3 {
                if b.amplitude[c] > 0.0 {
                    assert!((r[c] - 1.0).abs() < 0.05, "{a:?} vs {b:?}");
                }
            }
        }
    }
}
