//! `inlay estimate-env SCENE --out ENV`: estimates the distant environment
//! light the field does not show (METHOD.md eq. 3-4) and writes it as an
//! environment file scenes can name (`[lighting] environment`), with an
//! equirectangular picture of it. On a recipe scene it also checks the
//! estimate against the recipe's hidden lights; `--compare` renders the
//! scene's objects lit by the true hidden light and by the estimate, side by
//! side, and reports their difference.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args;
use glam::DVec3;
use inlay_engine::{Context, HdrImage};
use inlay_passes::envest::known_lights::as_point_lights;
use inlay_passes::envest::recovery::SEARCH_CONE_DEGREES;
use inlay_passes::envest::PointLight;
use inlay_passes::envest::{
    emitter_recovery, environment_file_text, estimate_environment, field_light_irradiance,
    hidden_light_lobes, EnvEstimateKnobs, EstimatedLight, Stage, Validation, ViewSource,
};
use inlay_passes::envest::{SurfaceNormals, SurfaceTest, Witness, Witnesses};
use inlay_passes::field::{perturb, GpuGridField, Perturbation};
use inlay_passes::march::MarchPass;
use inlay_passes::scene::{load_scene, ObjectEnvironment, Scene};
use inlay_passes::sg::Sg64;
use inlay_passes::sgfit::model::luminance;

use crate::field_source::{progress_bar, scene_field, scene_seen_lights};
use crate::headless::run_headless;
use crate::insertion_view::InsertionView;
use crate::outputs::{check_image_output, check_output, Outputs};

/// Options of `estimate-env`.
#[derive(Args, Debug)]
pub struct EstimateEnvArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The environment file to write (default: `<scene name>-env.toml`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Equirectangular picture of the estimate (.png tonemapped, .exr linear; default: `<out>.png`).
    #[arg(long)]
    pub picture: Option<PathBuf>,
    /// Use this field file instead of the scene's field or recipe.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Bake the recipe again even if a cached field exists.
    #[arg(long)]
    pub no_cache: bool,
    /// Estimate on the field made worse as a trainer's can be, e.g.
    /// `noise=0.2,floaters=40,see-through=0.3,seed=1` (any subset; see
    /// `field::Perturbation`): to test the estimate on fields it did not make.
    #[arg(long, value_parser = Perturbation::parse)]
    pub perturb: Option<Perturbation>,
    /// Where the views come from: `sphere` (random directions around the
    /// field, the paper's), `scene` (the scene's cameras), or a dataset's
    /// transforms.json (its photographs' cameras, views a trained field is
    /// right from; on DOG, whose photographs all look down, they
    /// constrained the light less than the sphere).
    #[arg(long, default_value = "sphere")]
    pub views_from: String,
    /// Keep only surface points these cameras saw (facing one, inside its
    /// view, nothing opaque between): a dataset's transforms.json, for a
    /// field trained from it (the sphere's views see sides of it no
    /// photograph did, such as a floor's underside), or `scene` for the
    /// scene's cameras (at 16:9). A dataset's photographs also judge
    /// each point (`--max-photo-spread`).
    #[arg(long)]
    pub seen_from: Option<String>,
    /// With `--seen-from DATASET`, the most the photographs that saw a
    /// surface point may disagree there for it to be kept: the
    /// interquartile range of their readings' luminance over their median
    /// plus a quarter of the view's median pixel (a point a trainer left
    /// in haze in front of a surface reads a different part of it in
    /// each; a point only one or two photographs saw is left out; 0 turns
    /// the test off).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().max_photo_spread)]
    pub max_photo_spread: f64,
    /// Read each surface point's radiance from the photographs of
    /// `--seen-from DATASET` that saw it (the median of their readings),
    /// not from the field: a trained field's colour is a reconstruction of
    /// them, with its errors.
    #[arg(long)]
    pub radiance_from_photos: bool,
    /// Read the photographs of `--seen-from DATASET` at 1/N of their width
    /// and height, as `inlay train --downscale N` does (photographs too
    /// many or too large for memory are refused before any pixel is read,
    /// naming the N that fits).
    #[arg(long, default_value_t = 1)]
    pub downscale: u32,
    /// Leave out the frames of `--seen-from DATASET` that cannot be used
    /// instead of failing.
    #[arg(long)]
    pub skip_bad_frames: bool,
    /// Views kept after the quality check (paper: 100).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().views)]
    pub views: u32,
    /// Side of each view's render in pixels.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().view_size)]
    pub view_size: u32,
    /// Surface points per view (paper: 64).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().pixels_per_view)]
    pub pixels: u32,
    /// Near-field rays per point (paper: 32768).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().rays_per_point)]
    pub rays: u32,
    /// Side of each point's cached opacity map.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().opacity_map)]
    pub opacity_map: u32,
    /// Quality score (0 best .. 100 worst) above which a view is rejected.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().quality_threshold)]
    pub quality_threshold: f64,
    /// SG lobes (paper: 32).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().lobes)]
    pub lobes: u32,
    /// A surface point brighter than this multiple of the median surface
    /// point over all the views is taken for a light source and left out.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().emitter_ratio)]
    pub emitter_ratio: f64,
    /// How surface points are told from points inside a medium: `gradient`
    /// (the density rises steeply; for baked fields) or `weight` (65 % of the
    /// pixel's opacity within two node spacings of its depth, at least
    /// 1/64 of the field's extent, and the density rising at least a
    /// fiftieth as steeply as a bake's, which refuses a trainer's haze;
    /// for trained fields, whose surfaces are as opaque with a hundredth
    /// of a bake's gradient, and whose normals it reads over two spacings).
    #[arg(long, value_enum, default_value = "gradient")]
    pub surface_test: SurfaceTestArg,
    /// With `--surface-test weight`, the largest bend of the surface, in
    /// degrees, within a node spacing (at least 1/128 of the field's
    /// extent) of a surface point for it to be
    /// used: on an edge a trained field has rounded, a point's normal is a
    /// blend of two faces' and its colour the brighter face's (180 keeps
    /// every point).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().max_crease)]
    pub max_crease: f64,
    /// With `--surface-test weight` (refused without it), where a point's
    /// normal is read:
    /// `at-point` (the density's gradient at its depth) or `along-ray`
    /// (summed along the pixel's ray through the surface, and the crease
    /// test on the rays beside it): for fields trained into thin shells
    /// (`inlay train --tv-edge`), not for foliage (docs/fidelity.md,
    /// "Thirty-fourth pass").
    #[arg(long, value_enum, default_value = "at-point")]
    pub normals: NormalsArg,
    /// Point lights near the field fitted beside the lobes (0: the paper's
    /// distant model alone).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().near_lights)]
    pub near_lights: u32,
    /// Width of the albedo MLP's hidden layers.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().albedo_width)]
    pub albedo_width: u32,
    /// Octaves of Fourier encoding on the albedo MLP's input (0: position
    /// alone).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().albedo_octaves)]
    pub albedo_octaves: u32,
    /// Adam steps .
    #[arg(long, default_value_t = EnvEstimateKnobs::default().iterations)]
    pub iterations: u32,
    /// Surface points per step.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().batch)]
    pub batch: u32,
    /// Directions sampled from the SG mixture per point and step.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().env_samples)]
    pub env_samples: u32,
    /// Weight κ of the prior on the environment's share of the points'
    /// irradiance, which keeps out light only the model's misfit asks for
    /// (0 turns it off).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().share_prior)]
    pub share_prior: f64,
    /// Keep the estimated light only when the points' loss without it
    /// (the albedo fitted alone under the field's light) is at least this
    /// many times the loss with it; otherwise the environment is black (0
    /// keeps it always).
    #[arg(long, default_value_t = EnvEstimateKnobs::default().min_loss_gain)]
    pub min_loss_gain: f64,
    /// Seed of every random choice.
    #[arg(long, default_value_t = EnvEstimateKnobs::default().seed)]
    pub seed: u64,
    /// Take the lights the field's photographs saw past its bounds
    /// (FIELD.lights.toml beside a trained field, `inlay train`) as known
    /// (`on`): the estimate fits only the light no photograph saw, and the
    /// environment file carries them with it. `off` estimates all the light
    /// from outside the field, those lights included.
    #[arg(long, value_parser = super::train::parse_on_off, default_value = "on", action = clap::ArgAction::Set)]
    pub seen_lights: bool,
    /// Render the objects lit by the true hidden light and by the estimate, side by side, to this image.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// Width of each half of the comparison.
    #[arg(long, default_value_t = 320)]
    pub compare_width: u32,
    /// Height of the comparison.
    #[arg(long, default_value_t = 180)]
    pub compare_height: u32,
    /// Camera of the comparison (index or name).
    #[arg(long, default_value = "0")]
    pub camera: String,
}

impl EstimateEnvArgs {
    fn knobs(&self) -> EnvEstimateKnobs {
        EnvEstimateKnobs {
            views: self.views,
            view_size: self.view_size,
            pixels_per_view: self.pixels,
            rays_per_point: self.rays,
            opacity_map: self.opacity_map,
            quality_threshold: self.quality_threshold,
            lobes: self.lobes,
            near_lights: self.near_lights,
            emitter_ratio: self.emitter_ratio,
            surface_test: match self.surface_test {
                SurfaceTestArg::Gradient => SurfaceTest::Gradient,
                SurfaceTestArg::Weight => SurfaceTest::Weight,
            },
            albedo_width: self.albedo_width,
            albedo_octaves: self.albedo_octaves,
            iterations: self.iterations,
            batch: self.batch,
            env_samples: self.env_samples,
            share_prior: self.share_prior,
            min_loss_gain: self.min_loss_gain,
            max_crease: self.max_crease,
            normals: match self.normals {
                NormalsArg::AtPoint => SurfaceNormals::AtPoint,
                NormalsArg::AlongRay => SurfaceNormals::AlongRay,
            },
            max_photo_spread: self.max_photo_spread,
            radiance_from_photos: self.radiance_from_photos,
            seed: self.seed,
            ..EnvEstimateKnobs::default()
        }
    }
}

/// `--surface-test`'s values ([`SurfaceTest`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SurfaceTestArg {
    /// The density's gradient (baked fields).
    Gradient,
    /// Where the ray's weight lies (trained fields).
    Weight,
}

/// `--normals`' values ([`SurfaceNormals`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NormalsArg {
    /// The density's gradient at the point.
    AtPoint,
    /// Summed along the pixel's ray through the surface.
    AlongRay,
}

/// The views `--views-from` asks for, and words saying what they are.
fn view_source(scene: &Scene, views_from: &str) -> anyhow::Result<(ViewSource, String)> {
    match views_from {
        "sphere" => Ok((
            ViewSource::Sphere,
            "random directions around the field".into(),
        )),
        "scene" => Ok((
            ViewSource::Cameras(scene.cameras.clone()),
            format!("the scene's {} cameras", scene.cameras.len()),
        )),
        path => {
            let cameras = inlay_passes::dataset::scene_cameras(Path::new(path), "train")
                .map_err(|e| anyhow::anyhow!("--views-from: {e}"))?;
            let words = format!("the {} cameras of {path}", cameras.len());
            Ok((
                ViewSource::Cameras(cameras.into_iter().map(|c| c.spec).collect()),
                words,
            ))
        }
    }
}

/// The cameras `--seen-from` names, with a dataset's photographs' pixels
/// when `photos` (to judge the points by, or to read their radiance from;
/// the latter, `radiance_from_photos`, needs a dataset).
fn witnesses(
    scene: &Scene,
    args: &EstimateEnvArgs,
    seen_from: &str,
    photos: bool,
) -> anyhow::Result<Witnesses> {
    let radiance_from_photos = args.radiance_from_photos;
    let cameras = match seen_from {
        "scene" if radiance_from_photos => anyhow::bail!(
            "--radiance-from-photos reads the photographs of a dataset: give --seen-from DATASET/transforms.json, not `scene`"
        ),
        "scene" => scene
            .cameras
            .iter()
            .map(|c| Witness::new(c, 16, 9))
            .collect(),
        path if photos => {
            // Transparent pixels read as the light they hold: none behind
            // the part no surface covers.
            let options = inlay_passes::dataset::LoadOptions {
                background: [0.0; 3],
                downscale: args.downscale,
                skip_bad_frames: args.skip_bad_frames,
                memory_available: crate::commands::dataset::available_memory(),
                ..Default::default()
            };
            let hint = if radiance_from_photos {
                ""
            } else {
                " (its photographs judge the surface points; --max-photo-spread 0 takes its cameras alone)"
            };
            let dataset = inlay_passes::dataset::load_dataset(Path::new(path), &options)
                .map_err(|e| anyhow::anyhow!("--seen-from: {e}{hint}"))?;
            if let Some(r) = dataset.skipped_report() {
                eprintln!("--seen-from {r}");
            }
            dataset
                .frames
                .into_iter()
                .map(Witness::photographed)
                .collect()
        }
        path => inlay_passes::dataset::scene_cameras(Path::new(path), "train")
            .map_err(|e| anyhow::anyhow!("--seen-from: {e}"))?
            .iter()
            .map(|c| Witness::new(&c.spec, c.size.0, c.size.1))
            .collect(),
    };
    Ok(Witnesses { cameras })
}

/// Runs `estimate-env`.
pub fn run(ctx: &Arc<Context>, args: &EstimateEnvArgs) -> anyhow::Result<()> {
    let knobs = args.knobs();
    if let Some((k, m)) = knobs.problem() {
        anyhow::bail!("--{}: {m}", k.replace('_', "-"));
    }
    let reads_photos = matches!(&args.seen_from, Some(s) if s != "scene")
        && (args.radiance_from_photos || knobs.max_photo_spread > 0.0);
    if !reads_photos {
        let flag = if args.downscale != 1 {
            Some(format!("--downscale {}", args.downscale))
        } else {
            args.skip_bad_frames
                .then(|| "--skip-bad-frames".to_string())
        };
        if let Some(flag) = flag {
            anyhow::bail!(
                "{flag}: it applies to the photographs of --seen-from DATASET/transforms.json, and \
                 none are read (they are with --max-photo-spread above 0 or --radiance-from-photos)"
            );
        }
    }
    let scene = load_scene(&args.scene)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}-env.toml", scene.name)));
    let picture = args
        .picture
        .clone()
        .unwrap_or_else(|| out.with_extension("png"));
    check_output("--out", &out, &["toml"])?;
    check_image_output("--picture", &picture)?;
    if let Some(compare) = &args.compare {
        check_image_output("--compare", compare)?;
    }
    let (source, source_words) = view_source(&scene, &args.views_from)?;
    let seen_from = match &args.seen_from {
        Some(s) => Some(witnesses(
            &scene,
            args,
            s,
            args.radiance_from_photos || knobs.max_photo_spread > 0.0,
        )?),
        None if args.radiance_from_photos => anyhow::bail!(
            "--radiance-from-photos needs the photographs: give --seen-from DATASET/transforms.json"
        ),
        None => None,
    };
    let mut field = scene_field(
        &scene,
        args.field.as_deref(),
        !args.no_cache,
        Some(ctx.info()),
    )?;
    if let Some(p) = args.perturb.filter(|p| !p.is_none()) {
        field = perturb(&field, &p);
        println!(
            "perturbed the field: noise {}, {} floaters, see-through {} (seed {})",
            p.noise, p.floaters, p.see_through, p.seed
        );
    }
    let seen = if args.seen_lights {
        scene_seen_lights(&scene, args.field.as_deref())?
    } else {
        Vec::new()
    };
    let known = as_point_lights(&seen);
    for l in &known {
        println!(
            "known light (seen past the field's bounds) at {:.3} {:.3} {:.3}, intensity {:.4} {:.4} {:.4}: \
             its light is given to the fit, not estimated (--seen-lights off estimates it too)",
            l.position.x, l.position.y, l.position.z, l.intensity.x, l.intensity.y, l.intensity.z
        );
    }
    let lib = inlay_passes::shaders::library()?;
    let bars = [
        progress_bar("views", knobs.views as u64),
        progress_bar("near field", knobs.points() as u64),
        progress_bar("fit", knobs.iterations as u64),
    ];
    let progress = |stage: Stage, done: usize, total: usize, loss: Option<f64>| {
        let bar = &bars[stage as usize];
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        if let Some(l) = loss {
            bar.set_message(format!("fit {l:.3e}"));
        }
    };
    println!("views from {source_words}");
    if let Some(w) = &seen_from {
        println!(
            "surface points only where one of {} cameras saw them",
            w.cameras.len()
        );
    }
    let estimate = estimate_environment(
        ctx,
        &lib,
        &field,
        scene.march,
        &knobs,
        &source,
        seen_from.as_ref(),
        &known,
        &progress,
    )?;
    bars.iter().for_each(|b| b.finish_and_clear());
    let s = &estimate.surface;
    println!(
        "views: {} kept of {} rendered ({} rejected by the quality score); {} surface points ({} pixels left out as light sources, {} as mixed, {} on creases, {} as seen by no camera, {} as where the photographs disagree)",
        s.views_kept,
        s.views_tried,
        s.scores.iter().filter(|(_, k)| !k).count(),
        s.points.len(),
        s.emitters,
        s.mixed,
        s.creased,
        s.unseen,
        s.inconsistent
    );
    // Few points leave most directions of the light to the prior and the
    // noise: on PLANTS trained at 128 nodes from 64 views of 256^2 the
    // surface test passed 2 % of the covered pixels, 264-299 points were
    // drawn of 1920, and the estimate read 0.3-1.0 x the scene's light
    // where the answer is black (docs/fidelity.md, twenty-seventh pass).
    let asked = s.views_kept as usize * knobs.pixels_per_view as usize;
    if s.points.len() * 4 < asked {
        println!(
            "warning: {} surface points of the {asked} asked for ({} of {} covered pixels were not on a surface under the surface test {:?}; {} candidates where the photographs disagree): the estimate rests on few points and may be far off",
            s.points.len(),
            s.not_surface,
            s.covered,
            knobs.surface_test,
            s.inconsistent
        );
    }
    // Where the photographs refuse most of what the field calls surface,
    // the field is hazy, and its near-field light is read through the
    // haze: ROOM trained with issue 23's knobs refused 6540 candidates
    // and kept 1045 (the estimate 2 x the light); DOG's trained field
    // refused about as many as it kept, the bakes 4-18 %
    // (docs/fidelity.md, thirty-first pass).
    if s.inconsistent > 2 * s.points.len() {
        println!(
            "warning: the photographs disagree at {} of the {} candidate points they judged: much of what the field calls surface is haze in front of the surfaces the photographs show, and the light the field lends the points is read through it; the estimate may be far off",
            s.inconsistent,
            s.inconsistent + s.points.len()
        );
    }
    if let Some(r) = s.photo_ratio {
        println!("radiance read from the photographs: at the median point {r:.3}× the field's own");
    }
    println!(
        "time: views {:.1} s, near field {:.1} s ({} rays per point), fit {:.1} s ({} steps); final loss {:.4e} ({:.4e} without E_env's sampling noise)",
        estimate.seconds[0],
        estimate.seconds[1],
        knobs.rays_per_point,
        estimate.seconds[2],
        knobs.iterations,
        estimate.fit.final_loss,
        estimate.fit.exact_loss
    );
    let outside = &estimate.outside;
    match (outside.gain(), outside.kept) {
        (Some(g), true) => println!(
            "light from outside the field: needed (the points' loss without it, the albedo fitted alone, is {g:.3}× the estimate's; kept from {}×)",
            knobs.min_loss_gain
        ),
        (Some(g), false) => println!(
            "light from outside the field: not needed (the points' loss without it, the albedo fitted alone, is {g:.3}× the estimate's, under {}×): the environment is black{}",
            knobs.min_loss_gain,
            match seen.len() {
                0 => String::new(),
                n => format!(" beyond the {n} known light(s)"),
            }
        ),
        (None, _) => println!("light from outside the field: kept without asking (--min-loss-gain 0)"),
    }
    let lobes = &estimate.fit.lobes;
    if outside.kept {
        println!(
            "kept {} of {} lobes (the others send the points under {:.0} % of their light)",
            lobes.len(),
            knobs.lobes,
            100.0 * inlay_passes::envest::prune::MIN_LOBE_REACH
        );
    }
    let record = vec![
        ("views".to_string(), s.views_kept.to_string()),
        ("points".to_string(), s.points.len().to_string()),
        (
            "rays_per_point".to_string(),
            knobs.rays_per_point.to_string(),
        ),
        ("iterations".to_string(), knobs.iterations.to_string()),
        ("seed".to_string(), knobs.seed.to_string()),
        (
            "radiance_from".to_string(),
            if s.photo_ratio.is_some() {
                "\"photographs\"".to_string()
            } else {
                "\"field\"".to_string()
            },
        ),
        ("lobes_kept".to_string(), lobes.len().to_string()),
        ("seen_lights_known".to_string(), seen.len().to_string()),
        (
            "loss_gain_of_outside_light".to_string(),
            outside
                .gain()
                .map_or("\"not asked\"".to_string(), |g| format!("{g:e}")),
        ),
        (
            "final_loss".to_string(),
            format!("{:e}", estimate.fit.final_loss),
        ),
        (
            "seconds".to_string(),
            format!("{:.1}", estimate.seconds.iter().sum::<f64>()),
        ),
    ];
    let mut outputs = Outputs::new();
    let light = EstimatedLight {
        lobes: lobes.clone(),
        lights: estimate.fit.lights.clone(),
        seen_lights: seen.clone(),
    };
    let text = environment_file_text(&light, &scene.name, &record);
    outputs.bytes(&out, text.as_bytes())?;
    let (image, exposure) = equirect_picture(lobes, 256, 128);
    outputs.image(&picture, &image, exposure)?;
    for l in &estimate.fit.lights {
        println!(
            "near light at {:.2} {:.2} {:.2}, intensity {:.4} {:.4} {:.4}",
            l.position.x, l.position.y, l.position.z, l.intensity.x, l.intensity.y, l.intensity.z
        );
    }
    if let Some(recipe) = scene.recipe() {
        // The known lights stand in the estimate beside its own.
        let lights: Vec<PointLight> = estimate.fit.lights.iter().chain(&known).copied().collect();
        let v = Validation::with_lights(&scene, recipe, lobes, &lights, 4096, knobs.seed);
        println!(
            "against the recipe's lights at {} test points: hidden-light irradiance error {:.1} %, \
             estimate = {:.2} % of all the lights' irradiance",
            v.points.len(),
            100.0 * v.hidden_error(),
            100.0 * v.fraction_of_lights()
        );
        let at = scene
            .objects
            .first()
            .map_or(0.5 * (recipe.bounds.min + recipe.bounds.max), |o| {
                o.sphere().0
            });
        print_true_light_loss(&estimate, &field, &knobs, recipe, &scene, at);
        // The near and known lights count as lobes seen from the object.
        let as_lobes: Vec<Sg64> = lobes
            .iter()
            .copied()
            .chain(lights.iter().map(|l| l.lobe_from(at, 1e4)))
            .collect();
        for r in emitter_recovery(recipe, &as_lobes, at) {
            let here = format!(
                "hidden light `{}` seen from {:.2} {:.2} {:.2}",
                r.name, at.x, at.y, at.z
            );
            match (r.angle_degrees, r.centroid_degrees) {
                (Some(a), Some(c)) => println!(
                    "{here}: the lobes within {:.0}° carry {:.2}× its light, their centre {c:.1}° off; the strongest of them is {a:.1}° off with {:.2}×",
                    SEARCH_CONE_DEGREES, r.cone_energy_ratio, r.energy_ratio
                ),
                _ => println!(
                    "{here}: no lobe within {:.0}° (missed)",
                    SEARCH_CONE_DEGREES
                ),
            }
        }
        if !scene.objects.is_empty() {
            // The first test point is the first object's centre, facing up.
            let (e, h, a) = (v.estimated[0], v.hidden[0], v.all[0]);
            let ratio = |x: DVec3| {
                let y = luminance(x);
                if y > 1e-9 * luminance(a).max(1e-300) {
                    format!("{:.3}", luminance(e) / y)
                } else {
                    "— (none there)".to_string()
                }
            };
            // What the object's probe carries: the field's light with its
            // bounces (behind foliage, direct light is a small part of it).
            let field = field_light_irradiance(
                recipe,
                v.points[0].0,
                v.points[0].1,
                4096,
                scene.bake.bounces.max(1),
                knobs.seed,
            );
            println!(
                "at the object, facing up: estimate / hidden light = {}, estimate / all lights' direct light = {}, \
                 estimate / the field's light (all bounces) = {}",
                ratio(h),
                ratio(a),
                ratio(field)
            );
        }
        println!(
            "  point                 normal        hidden (rgb)                   estimated (rgb)"
        );
        for (i, (x, n)) in v.points.iter().enumerate() {
            let f = |c: DVec3| format!("{:8.4} {:8.4} {:8.4}", c.x, c.y, c.z);
            println!(
                "  {:6.2} {:6.2} {:6.2}  {:4.1} {:4.1} {:4.1}  {}   {}",
                x.x,
                x.y,
                x.z,
                n.x,
                n.y,
                n.z,
                f(v.hidden[i]),
                f(v.estimated[i])
            );
        }
    }
    if let Some(path) = &args.compare {
        let image = compare(ctx, args, &scene, &field, light, path)?;
        outputs.image(path, &image, 1.0)?;
    }
    outputs.commit(Some(ctx))?;
    Ok(())
}

/// An equirectangular picture of `lobes` (+Y up, as scene maps) and the
/// exposure that brings its mean to 0.18.
pub fn equirect_picture(lobes: &[Sg64], width: u32, height: u32) -> (HdrImage, f32) {
    let mut pixels = Vec::with_capacity((width * height) as usize);
    let mut sum = 0.0;
    for y in 0..height {
        let theta = std::f64::consts::PI * (y as f64 + 0.5) / height as f64;
        for x in 0..width {
            let phi = 2.0 * std::f64::consts::PI * (x as f64 + 0.5) / width as f64;
            let d = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let l: DVec3 = lobes.iter().map(|g| g.eval(d)).sum();
            sum += inlay_passes::sgfit::model::luminance(l);
            pixels.push([l.x as f32, l.y as f32, l.z as f32, 1.0]);
        }
    }
    let mean = sum / (width * height) as f64;
    let exposure = if mean > 1e-12 {
        (0.18 / mean) as f32
    } else {
        1.0
    };
    (
        HdrImage {
            width,
            height,
            pixels,
        },
        exposure,
    )
}

/// The scene rendered with its objects lit by `lobes` (the field's light
/// through the probe plus these as the distant light).
fn render_with(
    ctx: &Arc<Context>,
    args: &EstimateEnvArgs,
    scene: &Scene,
    field: &inlay_passes::field::GridField,
    light: EstimatedLight,
    what: &str,
) -> anyhow::Result<HdrImage> {
    let mut scene = scene.clone();
    scene.object_environment = Some(ObjectEnvironment::new(PathBuf::from(what), light));
    let gpu_field = GpuGridField::upload(ctx, field)?;
    let library = gpu_field.library(&inlay_passes::shaders::library()?);
    let camera = scene.camera(&args.camera)?.clone();
    let mut view = InsertionView::new(
        ctx,
        &library,
        &scene,
        MarchPass::new(ctx, &library, scene.march)?,
        gpu_field,
        camera,
        !args.no_cache,
    )?;
    Ok(run_headless(
        ctx,
        &mut view,
        args.compare_width,
        args.compare_height,
        1,
        0.0,
    )?
    .image)
}

/// The picture true | estimated | |difference| for `path`; prints how far
/// apart they are.
fn compare(
    ctx: &Arc<Context>,
    args: &EstimateEnvArgs,
    scene: &Scene,
    field: &inlay_passes::field::GridField,
    estimate: EstimatedLight,
    path: &Path,
) -> anyhow::Result<HdrImage> {
    let recipe = scene.recipe().ok_or_else(|| {
        anyhow::anyhow!(
            "{}: --compare needs a recipe scene (its hidden lights are the truth)",
            scene.path.display()
        )
    })?;
    anyhow::ensure!(
        !scene.objects.is_empty(),
        "{}: --compare needs objects to light",
        scene.path.display()
    );
    let at = scene.objects.iter().map(|o| o.sphere().0).sum::<DVec3>() / scene.objects.len() as f64;
    let truth = hidden_light_lobes(recipe, &scene.environment, at, 1e4);
    let truth = EstimatedLight {
        lobes: truth,
        ..Default::default()
    };
    let a = render_with(ctx, args, scene, field, truth, "the recipe's hidden light")?;
    let b = render_with(ctx, args, scene, field, estimate, "the estimate")?;
    let (w, h) = (a.width, a.height);
    let mut pixels = Vec::with_capacity((3 * w * h) as usize);
    let (mut diff, mut total, mut sq) = (0.0f64, 0.0f64, 0.0f64);
    for y in 0..h {
        let row = |img: &HdrImage| (0..w).map(move |x| img.at(x, y)).collect::<Vec<_>>();
        let (ra, rb) = (row(&a), row(&b));
        let rd: Vec<[f32; 4]> = ra
            .iter()
            .zip(&rb)
            .map(|(p, q)| {
                let d = [
                    (p[0] - q[0]).abs(),
                    (p[1] - q[1]).abs(),
                    (p[2] - q[2]).abs(),
                    1.0,
                ];
                for c in 0..3 {
                    diff += d[c] as f64;
                    sq += (d[c] as f64).powi(2);
                    total += p[c] as f64;
                }
                d
            })
            .collect();
        pixels.extend(ra);
        pixels.extend(rb);
        pixels.extend(rd);
    }
    let n = (3 * w * h) as f64;
    let image = HdrImage {
        width: 3 * w,
        height: h,
        pixels,
    };
    println!(
        "{} (true hidden light | estimate | |difference|): mean relative difference {:.2} %, rms {:.4e}",
        path.display(),
        100.0 * diff / total.max(1e-30),
        (sq / n).sqrt()
    );
    Ok(image)
}

/// Says how well the recipe's hidden light explains the estimate's points
/// against the estimate's own light, each with the albedo fitted alone
/// (`envest::outside_light::loss_under`): which of the data and the fit
/// an error comes from.
fn print_true_light_loss(
    estimate: &inlay_passes::envest::EnvEstimate,
    field: &inlay_passes::field::GridField,
    knobs: &EnvEstimateKnobs,
    recipe: &inlay_passes::scene::Recipe,
    scene: &inlay_passes::scene::Scene,
    at: DVec3,
) {
    use inlay_passes::envest::outside_light::loss_under;
    use inlay_passes::envest::{hidden_light_model, FitData};
    // The recipe's hidden light stands alone; the estimate's beside the
    // known lights it was given.
    let bare = FitData {
        points: &estimate.surface.points,
        near: &estimate.near,
        known: &[],
        bounds: field.bounds,
    };
    let given = FitData {
        known: &estimate.known,
        ..bare
    };
    let (lobes, lights) = hidden_light_model(recipe, &scene.environment, at, knobs.max_sharpness);
    let truth = loss_under(&bare, knobs, &lobes, &lights);
    let own = loss_under(&given, knobs, &estimate.fit.lobes, &estimate.fit.lights);
    // The exact losses are unbiased estimates and can dip below zero on a
    // near-exact fit; the two within 5 % are read as alike.
    let ratio = truth / own;
    let verdict = if !(truth > 0.0 && own > 0.0) {
        "one fits the points exactly"
    } else if (ratio - 1.0).abs() <= 0.05 {
        "the two explain the points alike"
    } else if ratio < 1.0 {
        "the fit fell short of a light the points prefer"
    } else {
        "the points ask for another light than the recipe's"
    };
    println!(
        "the points' loss under the recipe's hidden light {truth:.4e}, under the estimate's {own:.4e} ({ratio:.2}×; the albedo fitted alone under each): {verdict}"
    );
}
