//! `inlay bench-shade SCENE --at x,y,z`: the SG shading's error against the
//! brute-force reference (exact BRDF integrated against the probe itself)
//! as the light's lobe count M and the NDF's lobe count change, for a
//! diffuse, a rough and a glossy material. All on the CPU in f64 (the GPU
//! kernel matches this f64 shading to 10⁻⁶, see `tests/object_gpu.rs`), so
//! the figures do not depend on the device. Prints a Markdown table for
//! `docs/benchmarks.md`; pass times come from `inlay render`.

use std::path::PathBuf;

use clap::Args;
use glam::DVec3;
use inlay_passes::brdf::{shade_sg, NdfLobes, SurfaceMaterial};
use inlay_passes::probe::{trace_probe, ProbeKnobs};
use inlay_passes::scene::load_scene;
use inlay_passes::sgfit::{fit_reference, FitKnobs, ProbeSamples, Start};
use inlay_passes::shade::shade_probe_reference;

use crate::commands::probe::PlacementArgs;
use crate::field_source::scene_field;

/// Options of `bench-shade`.
#[derive(Args, Debug)]
pub struct BenchShadeArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Probe position and layout.
    #[command(flatten)]
    pub placement: PlacementArgs,
    /// Light lobe counts M to fit.
    #[arg(long, value_delimiter = ',', default_values = ["4", "8", "16", "32", "64"])]
    pub lobes: Vec<u32>,
    /// NDF lobe counts.
    #[arg(long, value_delimiter = ',', default_values = ["1", "2", "4", "8"])]
    pub ndf_lobes: Vec<u32>,
    /// Surface orientations sampled (Fibonacci normals, each seen 40° off).
    #[arg(long, default_value_t = 48)]
    pub normals: u32,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
}

/// Runs `bench-shade`.
pub fn run(args: &BenchShadeArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let at = args.placement.point()?;
    let field = scene_field(&scene, args.field.as_deref(), true, None)?;
    let probe_knobs = ProbeKnobs {
        map: args.placement.map_or(scene.lighting.probe.map),
        ..scene.lighting.probe
    };
    let map = probe_knobs.direction_map();
    let env = inlay_passes::lighting::object_light_lobes(&scene, at);
    let texels = trace_probe(&field, at, &probe_knobs, &scene.march, &env);
    let samples = ProbeSamples::new(&map, &texels);
    let classes = [
        ("diffuse", DVec3::new(0.8, 0.6, 0.4), 1.0, 0.0),
        ("rough", DVec3::splat(0.5), 0.6, 0.5),
        ("glossy", DVec3::new(1.0, 0.78, 0.34), 0.2, 1.0),
    ];
    // Surface points: Fibonacci normals, viewed 40° off the normal.
    let views: Vec<(DVec3, DVec3)> = (0..args.normals.max(1))
        .map(|k| {
            let n = inlay_passes::sgfit::fibonacci_axis(k, args.normals.max(1));
            let (t, _) = n.any_orthonormal_pair();
            let a = 40f64.to_radians();
            (n, (n * a.cos() + t * a.sin()).normalize())
        })
        .collect();
    let lum = inlay_passes::sgfit::model::luminance;
    let brute: Vec<Vec<f64>> = classes
        .iter()
        .map(|&(_, albedo, roughness, metallic)| {
            let m = SurfaceMaterial {
                albedo,
                roughness,
                metallic,
            };
            views
                .iter()
                .map(|&(n, v)| lum(shade_probe_reference(&map, &texels, n, v, &m, 8)))
                .collect()
        })
        .collect();
    println!(
        "{}: probe at {at} ({} {}×{}), {} surface orientations; relative L1 error of the SG shading against brute force",
        scene.name,
        map.kind.name(),
        map.width,
        map.height,
        views.len()
    );
    println!();
    println!("| M | fit residual | NDF lobes | diffuse | rough | glossy |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for &m_lobes in &args.lobes {
        let knobs = FitKnobs {
            lobes: m_lobes,
            ..scene.lighting.fit
        };
        knobs
            .check()
            .map_err(|(k, m)| anyhow::anyhow!("{k}: {m}"))?;
        let fit = fit_reference(&samples, &knobs, Start::Cold, knobs.cold_iterations);
        for &n_lobes in &args.ndf_lobes {
            let ndf = NdfLobes::new(n_lobes).map_err(|m| anyhow::anyhow!("--ndf-lobes: {m}"))?;
            let errors: Vec<String> = classes
                .iter()
                .zip(&brute)
                .map(|(&(_, albedo, roughness, metallic), reference)| {
                    let m = SurfaceMaterial {
                        albedo,
                        roughness,
                        metallic,
                    };
                    let (mut err, mut sum) = (0.0, 0.0);
                    for (&(n, v), &b) in views.iter().zip(reference) {
                        err += (lum(shade_sg(&fit.lobes, n, v, &m, &ndf)) - b).abs();
                        sum += b;
                    }
                    format!("{:.3}", err / sum.max(1e-30))
                })
                .collect();
            println!(
                "| {m_lobes} | {:.3} | {n_lobes} | {} |",
                fit.relative_residual(),
                errors.join(" | ")
            );
        }
    }
    Ok(())
}
