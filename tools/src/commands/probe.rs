//! `inlay probe SCENE --at x,y,z`: traces the incident-light probe at a
//! point of a scene's field, fits M spherical Gaussians to it on the GPU,
//! and writes the probe, the fitted lighting and their difference side by
//! side, so a person can look at the fit.

use std::path::PathBuf;
use std::sync::Arc;

use clap::{Args, ValueEnum};
use glam::DVec3;
use inlay_engine::{Context, HdrImage, ImageDesc, Readback, Renderer, SubmitSync};
use inlay_passes::field::GpuGridField;
use inlay_passes::lighting::{sharp_limit, split_environment, IncidentLight, LocalLight};
use inlay_passes::march::MarchKnobs;
use inlay_passes::probe::{
    lobes_irradiance, probe_irradiance, DirectionMap, MapKind, ProbeKnobs, AXES, PROBE_FORMAT,
};
use inlay_passes::scene::load_scene;
use inlay_passes::sg::Sg32;
use inlay_passes::sg::Sg64;
use inlay_passes::sgfit::{fit_reference, FitKnobs, FitReport, FitStart, ProbeSamples, Start};

use crate::field_source::scene_field;
use crate::outputs::{check_image_output, Outputs};

/// The probe layout on the command line.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MapArg {
    /// n × n octahedral map.
    Octahedral,
    /// 2n × n latitude–longitude map.
    Equirect,
}

impl MapArg {
    /// The layout it names.
    pub fn kind(self) -> MapKind {
        match self {
            MapArg::Octahedral => MapKind::Octahedral,
            MapArg::Equirect => MapKind::Equirect,
        }
    }
}

/// Where a probe is traced and how it is laid out (shared by `probe` and `bench-sg`).
#[derive(Args, Debug)]
pub struct PlacementArgs {
    /// Where the object's centre is: x,y,z in scene units.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        required = true
    )]
    pub at: Vec<f64>,
    /// Probe layout (overrides `[lighting] probe_map`; default octahedral).
    #[arg(long, value_enum)]
    pub map: Option<MapArg>,
}

impl PlacementArgs {
    /// The point given by `--at`.
    pub fn point(&self) -> anyhow::Result<DVec3> {
        anyhow::ensure!(
            self.at.len() == 3 && self.at.iter().all(|v| v.is_finite()),
            "--at needs three finite numbers x,y,z, got {:?}",
            self.at
        );
        Ok(DVec3::new(self.at[0], self.at[1], self.at[2]))
    }

    /// The layout: `--map`, else the scene's.
    pub fn map_or(&self, scene: MapKind) -> MapKind {
        self.map.map_or(scene, MapArg::kind)
    }
}

/// Options of `probe`.
#[derive(Args, Debug)]
pub struct ProbeArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Probe position and layout.
    #[command(flatten)]
    pub placement: PlacementArgs,
    /// Probe resolution n: n × n octahedral, 2n × n equirect (overrides `[lighting] probe_resolution`).
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Rays per texel side s, s × s per texel (overrides `[lighting] probe_supersampling`).
    #[arg(long)]
    pub supersampling: Option<u32>,
    /// Number of SG lobes M (overrides `[lighting] lobes`).
    #[arg(long)]
    pub lobes: Option<u32>,
    /// Levenberg–Marquardt iterations from the cold start (overrides `[lighting] cold_iterations`).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Initial damping (overrides `[lighting] damping`).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Output image: probe | fit | |fit − probe|; .exr is linear, .png tonemapped. Repeatable.
    #[arg(long, default_values = ["inlay-probe.exr"])]
    pub out: Vec<PathBuf>,
    /// Exposure multiplier for PNG output.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Texels are drawn as zoom × zoom pixel blocks.
    #[arg(long, default_value_t = 4)]
    pub zoom: u32,
    /// Also fit the same probe with the f64 CPU reference and print its residual.
    #[arg(long)]
    pub cpu_check: bool,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Segments across the field's diagonal (overrides `[march] samples_per_ray`).
    #[arg(long)]
    pub samples_per_ray: Option<u32>,
    /// Bake the recipe again even if a cached field exists.
    #[arg(long)]
    pub no_cache: bool,
}

/// Runs `probe`.
pub fn run(ctx: &Arc<Context>, args: &ProbeArgs) -> anyhow::Result<()> {
    anyhow::ensure!((1..=64).contains(&args.zoom), "--zoom must be in 1..=64");
    for out in &args.out {
        check_image_output("--out", out)?;
    }
    let scene = load_scene(&args.scene)?;
    let at = args.placement.point()?;
    let knobs = scene.lighting;
    let probe_knobs = ProbeKnobs {
        map: args.placement.map_or(knobs.probe.map),
        resolution: args.resolution.unwrap_or(knobs.probe.resolution),
        supersampling: args.supersampling.unwrap_or(knobs.probe.supersampling),
        stride: knobs.probe.stride,
    };
    let fit_knobs = FitKnobs {
        lobes: args.lobes.unwrap_or(knobs.fit.lobes),
        cold_iterations: args.iterations.unwrap_or(knobs.fit.cold_iterations),
        damping: args.damping.unwrap_or(knobs.fit.damping),
        ..knobs.fit
    };
    let iterations = fit_knobs.cold_iterations;
    let mut march = scene.march;
    march.samples_per_ray = args.samples_per_ray.unwrap_or(march.samples_per_ray);
    for (what, checked) in [
        ("probe", probe_knobs.check()),
        ("fit", fit_knobs.check()),
        ("march", march.check()),
    ] {
        checked.map_err(|(k, m)| anyhow::anyhow!("{what} knob `{k}`: {m}"))?;
    }
    let field = scene_field(
        &scene,
        args.field.as_deref(),
        !args.no_cache,
        Some(ctx.info()),
    )?;
    let centre = 0.5 * (field.bounds.min + field.bounds.max);
    let diagonal = field.bounds.diagonal();
    anyhow::ensure!(
        (at - centre).length() <= 1e3 * diagonal,
        "--at {at} is {:.3e} scene units from the field (diagonal {diagonal:.3}): the probe would see nothing of it",
        (at - centre).length()
    );
    let env = inlay_passes::lighting::object_light_lobes(&scene, at);
    let gpu_field = GpuGridField::upload(ctx, &field)?;
    let traced = trace_and_fit(ctx, &gpu_field, at, probe_knobs, fit_knobs, march, &env)?;
    let map = probe_knobs.direction_map();
    print_report(
        ctx,
        &scene.name,
        at,
        &probe_knobs,
        &fit_knobs,
        &env,
        &traced,
    );
    let (probe_image, report) = (&traced.probe, &traced.report);
    let texels: Vec<[f64; 4]> = probe_image
        .pixels
        .iter()
        .map(|p| p.map(|v| v as f64))
        .collect();
    print_irradiance(&map, &texels, &traced);
    if args.cpu_check {
        let cpu = fit_reference(
            &ProbeSamples::new(&map, &texels),
            &fit_knobs,
            Start::Cold,
            iterations,
        );
        println!(
            "CPU reference (f64, same start and rule): relative residual {:.5}, {} of {} steps accepted",
            cpu.relative_residual(),
            cpu.accepted,
            iterations
        );
    }
    let panels = side_by_side(probe_image, &report.lobes, &map, args.zoom);
    anyhow::ensure!(
        panels.non_finite_count() == 0,
        "the fit produced non-finite values"
    );
    let mut outputs = Outputs::new();
    for out in &args.out {
        outputs.image(out, &panels, args.exposure)?;
    }
    if !outputs.commit(Some(ctx))?.is_empty() {
        println!("(each image: probe | SG fit | |fit − probe|)");
    }
    Ok(())
}

/// A probe traced and fitted cold on the GPU.
pub struct TracedProbe {
    /// The probe image (rgb radiance, alpha opacity) of L_env's broad
    /// lobes and the field.
    pub probe: HdrImage,
    /// The fit's report, the fitted lobes included.
    pub report: FitReport,
    /// The lobes shading receives: the fitted ones, then L_env's sharp
    /// lobes attenuated by the field (`inlay_passes::lighting::sharp`).
    pub lights: Vec<Sg64>,
    /// The renderer that ran it (for its timings).
    pub renderer: Renderer,
}

impl TracedProbe {
    /// The sharp lobes shaded directly (after the fitted ones).
    pub fn direct(&self) -> &[Sg64] {
        &self.lights[self.report.lobes.len().min(self.lights.len())..]
    }
}

/// Traces the probe at `at` through `field` with L_env `env` and fits it
/// from a cold start for the knobs' cold iterations; L_env's lobes too
/// sharp for the fit are attenuated by the field and kept as they are.
pub fn trace_and_fit(
    ctx: &Arc<Context>,
    field: &GpuGridField,
    at: DVec3,
    probe_knobs: ProbeKnobs,
    fit_knobs: FitKnobs,
    march: MarchKnobs,
    env: &[Sg64],
) -> anyhow::Result<TracedProbe> {
    let knobs = (probe_knobs, fit_knobs, march);
    trace_and_fit_with_local(ctx, field, at, knobs, env, &[], 1)
}

/// As [`trace_and_fit`], with `local` lights left out of the probe and
/// appended to the lights as `at` sees them (`local_side`² rays each), as
/// the frame lights an object ([`inlay_passes::lighting::local`]).
pub fn trace_and_fit_with_local(
    ctx: &Arc<Context>,
    field: &GpuGridField,
    at: DVec3,
    (probe_knobs, fit_knobs, march): (ProbeKnobs, FitKnobs, MarchKnobs),
    env: &[Sg64],
    local: &[LocalLight],
    local_side: u32,
) -> anyhow::Result<TracedProbe> {
    let library = field.library(&inlay_passes::shaders::library()?);
    let light = IncidentLight::new(
        ctx,
        &library,
        probe_knobs,
        fit_knobs,
        march,
        env,
        local,
        local_side,
    )?;
    let map = light.probe.map();
    let readback = Readback::new(
        ctx,
        ImageDesc {
            width: map.width,
            height: map.height,
            format: PROBE_FORMAT,
        },
    )?;
    let mut renderer = Renderer::new(ctx, 1)?;
    renderer.begin_frame()?;
    let mut graph = inlay_engine::graph::FrameGraph::new();
    let image = light.probe.add(&mut graph, field, at);
    let lobes = light
        .fit
        .add(&mut graph, image, FitStart::Cold, fit_knobs.cold_iterations)?;
    if let Some(d) = &light.direct {
        d.add(&mut graph, field, at, lobes, true);
    }
    readback.add_to_graph(&mut graph, image);
    light.add_readback(&mut graph);
    renderer.submit(graph, &SubmitSync::none())?;
    renderer.finish()?;
    Ok(TracedProbe {
        probe: readback.read()?,
        report: light.fit.read_report()?,
        lights: light.read_lights()?.iter().map(|g| g.to_f64()).collect(),
        renderer,
    })
}

/// The irradiance at the probe's centre from each axis' hemisphere, from
/// the probe's texels (with the directly shaded lobes) and from all the
/// lobes shading receives: the figures an independent renderer's
/// irradiance sensors measure.
fn print_irradiance(map: &DirectionMap, texels: &[[f64; 4]], traced: &TracedProbe) {
    println!("irradiance E(n) at the centre (rgb):");
    for (name, n) in AXES {
        let p = probe_irradiance(map, texels, n) + lobes_irradiance(traced.direct(), n);
        let f = lobes_irradiance(&traced.lights, n);
        println!(
            "  {name}: probe [{:.5}, {:.5}, {:.5}]  fit [{:.5}, {:.5}, {:.5}]",
            p.x, p.y, p.z, f.x, f.y, f.z
        );
    }
}

#[allow(clippy::too_many_arguments)]
fn print_report(
    ctx: &Context,
    scene: &str,
    at: DVec3,
    probe: &ProbeKnobs,
    fit: &FitKnobs,
    env: &[inlay_passes::sg::Sg64],
    traced: &TracedProbe,
) {
    let (report, renderer) = (&traced.report, &traced.renderer);
    let map = probe.direction_map();
    println!(
        "{scene}: probe at {at}, {} {}×{} ({} texels, {}×{} rays each), environment: {}",
        probe.map.name(),
        map.width,
        map.height,
        map.texels(),
        probe.supersampling,
        probe.supersampling,
        if env.is_empty() {
            "none (L_env not evaluated)".to_string()
        } else {
            match traced.direct().len() {
                0 => format!("{} SG lobes", env.len()),
                k => format!(
                    "{} SG lobes, {k} of them too sharp for the fit and shaded directly \
                     (attenuated by the field to {})",
                    env.len(),
                    transmittances(env, traced.direct(), sharp_limit(probe))
                ),
            }
        }
    );
    if report.invalid > 0 {
        println!(
            "warning: {} probe texels were NaN, infinite or negative and were ignored",
            report.invalid
        );
    }
    let first = inlay_passes::sgfit::relative_residual(report.costs[0], report.energy);
    println!(
        "fit: {} lobes, {} iterations ({} steps accepted), relative residual {:.5} at the cold start → {:.5}",
        fit.lobes,
        report.costs.len() - 1,
        report.accepted,
        first,
        report.relative_residual()
    );
    if let Some(t) = renderer.latest_timings() {
        for name in [
            inlay_passes::probe::PROBE_TRACE,
            inlay_passes::sgfit::SG_FIT,
            inlay_passes::lighting::DIRECT_LIGHT,
        ] {
            if let Some(ms) = t.gpu_ms(name) {
                println!("{name}: {ms:.3} ms GPU on {}", ctx.info().name);
            }
        }
    }
}

/// The field's transmittance towards each sharp lobe of `env` (sharper
/// than `limit`), read off the `direct` lobes it left: "0.98, 0.41".
fn transmittances(env: &[Sg64], direct: &[Sg64], limit: f64) -> String {
    split_environment(env, limit)
        .sharp
        .iter()
        .zip(direct)
        .map(|(g, d)| {
            format!(
                "{:.2}",
                d.amplitude.max_element() / g.amplitude.max_element()
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// probe | fit | |fit − probe| in one image, each texel a zoom × zoom block.
fn side_by_side(
    probe: &HdrImage,
    lobes: &[Sg32],
    map: &inlay_passes::probe::DirectionMap,
    zoom: u32,
) -> HdrImage {
    let (w, h) = (map.width, map.height);
    let width = 3 * w * zoom;
    let mut pixels = vec![[0.0f32, 0.0, 0.0, 1.0]; (width * h * zoom) as usize];
    for y in 0..h {
        for x in 0..w {
            let d = map.direction(x, y).as_vec3();
            let fit: glam::Vec3 = lobes.iter().map(|g| g.eval(d)).sum();
            let p = probe.at(x, y);
            let panels = [
                [p[0], p[1], p[2], 1.0],
                [fit.x, fit.y, fit.z, 1.0],
                [
                    (fit.x - p[0]).abs(),
                    (fit.y - p[1]).abs(),
                    (fit.z - p[2]).abs(),
                    1.0,
                ],
            ];
            for (k, value) in panels.into_iter().enumerate() {
                for dy in 0..zoom {
                    for dx in 0..zoom {
                        let px = (k as u32 * w + x) * zoom + dx;
                        let py = y * zoom + dy;
                        pixels[(py * width + px) as usize] = value;
                    }
                }
            }
        }
    }
    HdrImage {
        width,
        height: h * zoom,
        pixels,
    }
}
