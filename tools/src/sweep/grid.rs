//! The configurations a sweep runs: the quality knobs' values, expanded
//! one knob at a time around a base (`axes`) or as their full product.

use clap::ValueEnum;
use serde::Serialize;

/// One configuration of the costly knobs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct Knobs {
    /// Render width in pixels.
    pub width: u32,
    /// Render height in pixels.
    pub height: u32,
    /// March segments across the field's diagonal.
    pub samples_per_ray: u32,
    /// Probe side n (n × n texels).
    pub probe: u32,
    /// SG lobes M.
    pub lobes: u32,
    /// LM iterations of a cold fit (warm fits run a fifth, at least 1).
    pub iterations: u32,
    /// SSDF nodes per axis.
    pub ssdf_grid: u32,
    /// SSDF PCA components.
    pub components: u32,
}

impl Knobs {
    /// Warm-start iterations for `iterations` cold ones (the paper's 40/8).
    pub fn warm_iterations(&self) -> u32 {
        self.iterations.div_ceil(5).max(1)
    }

    /// A short label, e.g. `320x180 s128 p16 M8 it20 g16 k8`.
    pub fn label(&self) -> String {
        format!(
            "{}x{} s{} p{} M{} it{} g{} k{}",
            self.width,
            self.height,
            self.samples_per_ray,
            self.probe,
            self.lobes,
            self.iterations,
            self.ssdf_grid,
            self.components
        )
    }
}

/// The values each knob takes.
#[derive(Debug, Clone)]
pub struct KnobValues {
    /// Render sizes.
    pub sizes: Vec<(u32, u32)>,
    /// Samples per ray.
    pub samples_per_ray: Vec<u32>,
    /// Probe sides.
    pub probe: Vec<u32>,
    /// Lobe counts.
    pub lobes: Vec<u32>,
    /// Cold LM iterations.
    pub iterations: Vec<u32>,
    /// SSDF grids.
    pub ssdf_grid: Vec<u32>,
    /// PCA components.
    pub components: Vec<u32>,
}

/// How the values combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GridMode {
    /// The base configuration, then each knob over its values with the
    /// others at the base (the trade of each knob on its own).
    Axes,
    /// Every combination (the product of the value counts).
    Full,
}

/// The configurations of `values` combined by `mode` around `base`, with
/// no configuration twice (the base first in `axes` mode).
pub fn configurations(values: &KnobValues, base: Knobs, mode: GridMode) -> Vec<Knobs> {
    let mut out: Vec<Knobs> = Vec::new();
    let mut push = |k: Knobs| {
        if !out.contains(&k) {
            out.push(k);
        }
    };
    match mode {
        GridMode::Axes => {
            push(base);
            for &(width, height) in &values.sizes {
                push(Knobs {
                    width,
                    height,
                    ..base
                });
            }
            for &samples_per_ray in &values.samples_per_ray {
                push(Knobs {
                    samples_per_ray,
                    ..base
                });
            }
            for &probe in &values.probe {
                push(Knobs { probe, ..base });
            }
            for &lobes in &values.lobes {
                push(Knobs { lobes, ..base });
            }
            for &iterations in &values.iterations {
                push(Knobs { iterations, ..base });
            }
            for &ssdf_grid in &values.ssdf_grid {
                push(Knobs { ssdf_grid, ..base });
            }
            for &components in &values.components {
                push(Knobs { components, ..base });
            }
        }
        GridMode::Full => {
            for &(width, height) in &values.sizes {
                for &samples_per_ray in &values.samples_per_ray {
                    for &probe in &values.probe {
                        for &lobes in &values.lobes {
                            for &iterations in &values.iterations {
                                for &ssdf_grid in &values.ssdf_grid {
                                    for &components in &values.components {
                                        push(Knobs {
                                            width,
                                            height,
                                            samples_per_ray,
                                            probe,
                                            lobes,
                                            iterations,
                                            ssdf_grid,
                                            components,
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Knobs {
        Knobs {
            width: 160,
            height: 90,
            samples_per_ray: 128,
            probe: 16,
            lobes: 8,
            iterations: 20,
            ssdf_grid: 8,
            components: 8,
        }
    }

    fn values() -> KnobValues {
        KnobValues {
            sizes: vec![(160, 90), (320, 180)],
            samples_per_ray: vec![64, 128, 256],
            probe: vec![16],
            lobes: vec![4, 8],
            iterations: vec![10, 20],
            ssdf_grid: vec![8],
            components: vec![4, 8],
        }
    }

    #[test]
    fn axes_vary_one_knob_at_a_time_without_repeats() {
        let c = configurations(&values(), base(), GridMode::Axes);
        assert_eq!(c[0], base());
        // base + one new value per axis: 320x180, s64, s256, M4, it10, k4.
        assert_eq!(c.len(), 7, "{c:#?}");
        for k in &c[1..] {
            let b = base();
            let differs = [
                k.width != b.width,
                k.samples_per_ray != b.samples_per_ray,
                k.probe != b.probe,
                k.lobes != b.lobes,
                k.iterations != b.iterations,
                k.ssdf_grid != b.ssdf_grid,
                k.components != b.components,
            ];
            assert_eq!(differs.iter().filter(|&&d| d).count(), 1, "{k:?}");
        }
    }

    #[test]
    fn full_is_the_product() {
        let c = configurations(&values(), base(), GridMode::Full);
        assert_eq!(c.len(), 2 * 3 * 2 * 2 * 2);
        assert!(c.contains(&base()));
    }

    #[test]
    fn warm_iterations_are_a_fifth_of_the_cold_ones() {
        let k = |iterations| Knobs {
            iterations,
            ..base()
        };
        assert_eq!(k(40).warm_iterations(), 8);
        assert_eq!(k(1).warm_iterations(), 1);
        assert_eq!(k(12).warm_iterations(), 3);
    }
}
