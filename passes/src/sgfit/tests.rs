//! The CPU fit on probes of known content.

use glam::DVec3;

use super::*;
use crate::probe::{DirectionMap, MapKind};
use crate::sg::Sg64;

/// A probe holding exactly these lobes (plus `extra` per texel).
fn probe_of(map: &DirectionMap, lobes: &[Sg64], extra: impl Fn(usize) -> [f64; 4]) -> ProbeSamples {
    let texels: Vec<[f64; 4]> = (0..map.texels())
        .map(|i| {
            let d = map.direction(i as u32 % map.width, i as u32 / map.width);
            let l = model::model(lobes, d);
            let e = extra(i);
            [l.x + e[0], l.y + e[1], l.z + e[2], 1.0]
        })
        .collect();
    ProbeSamples::new(map, &texels)
}

fn sky_and_sun() -> Vec<Sg64> {
    vec![
        Sg64 {
            direction: DVec3::new(0.3, 1.0, 0.2).normalize(),
            sharpness: 60.0,
            amplitude: DVec3::new(50.0, 45.0, 40.0),
        },
        Sg64 {
            direction: DVec3::Y,
            sharpness: 1.5,
            amplitude: DVec3::new(0.3, 0.5, 0.9),
        },
        Sg64 {
            direction: DVec3::new(-1.0, -0.2, 0.4).normalize(),
            sharpness: 8.0,
            amplitude: DVec3::new(2.0, 1.0, 0.5),
        },
    ]
}

#[test]
fn fit_recovers_a_sum_of_lobes() {
    let map = DirectionMap::new(MapKind::Octahedral, 24);
    let probe = probe_of(&map, &sky_and_sun(), |_| [0.0; 4]);
    let knobs = FitKnobs {
        lobes: 8,
        ..FitKnobs::default()
    };
    let fit = fit_reference(&probe, &knobs, Start::Cold, 40);
    let first = relative_residual(fit.costs[0], fit.energy);
    let last = fit.relative_residual();
    assert!(
        last < 0.05 && last < 0.3 * first,
        "{first} → {last}: {:?}",
        fit.costs
    );
    // Costs never rise (rejected steps keep the previous lobes).
    assert!(fit.costs.windows(2).all(|w| w[1] <= w[0]));
    for g in &fit.lobes {
        assert!((g.direction.length() - 1.0).abs() < 1e-9);
        assert!(g.sharpness > 0.0 && g.amplitude.min_element() >= 0.0);
    }
}

/// The normal equations from the features' Gram matrix equal JᵀJ and Jᵀr
/// summed from the explicit Jacobian rows (f64, relative 1e-12), on a
/// probe with noise and an invalid texel and lobes of unequal channels.
#[test]
fn gram_normal_equations_match_the_explicit_jacobian() {
    let map = DirectionMap::new(MapKind::Octahedral, 12);
    let probe = probe_of(&map, &sky_and_sun(), |i| {
        if i == 7 {
            [f64::NAN, 0.0, 0.0, 1.0]
        } else {
            [0.01 * (i % 5) as f64, 0.02 * (i % 3) as f64, 0.0, 0.0]
        }
    });
    assert_eq!(probe.invalid, 1);
    let lobes = model::cold_start(&probe, 5);
    let (a, b) = reference::normal_equations(&probe, &lobes);
    let p = model::PARAMS_PER_LOBE * lobes.len();
    let (mut a0, mut b0) = (vec![0.0; p * p], vec![0.0; p]);
    let mut rows = [Vec::new(), Vec::new(), Vec::new()];
    for t in 0..probe.directions.len() {
        model::jacobian_rows(&probe, &lobes, t, &mut rows);
        for row in &rows {
            for i in 0..p {
                b0[i] += row[i] * row[p];
                for j in 0..p {
                    a0[i * p + j] += row[i] * row[j];
                }
            }
        }
    }
    let scale = a0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (x, y) in a.iter().zip(&a0) {
        assert!((x - y).abs() <= 1e-12 * scale, "{x} vs {y}");
    }
    let scale = b0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 0.0);
    for (x, y) in b.iter().zip(&b0) {
        assert!((x - y).abs() <= 1e-12 * scale, "{x} vs {y}");
    }
}
