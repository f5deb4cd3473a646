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
