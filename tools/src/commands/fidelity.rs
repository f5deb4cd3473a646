//! `inlay fidelity SCENE --cycles DIR`: inlay measured against an
//! independent renderer. DIR holds what `tools/cycles/render_cycles.py`
//! rendered with Blender Cycles for the scene (two seeds of each image, so
//! its noise is known). For each camera it compares, against Cycles:
//! `inlay reference` (the recipe path tracer) without and with the
//! objects, the field's render, and the insertion (the object's brightness
//! and error inside its mask, the cast shadow as the ratio of the images
//! with and without the object); and for each object, the irradiance at
//! its centre from the probe and from the fitted lobes against Cycles'
//! irradiance sensors. Writes a markdown report and side-by-side images.
//! With `--field`, a field trained from photographs stands in for the
//! recipe's baked one: the whole method from photographs alone, against
//! Cycles ([`trained_scene`]).

use std::cell::RefCell;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args;
use glam::DVec3;
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{Context, HdrImage};
use inlay_passes::bake::{render_reference, ReferenceOptions};
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::field::{sky_path, GpuGridField};
use inlay_passes::probe::{lobes_irradiance, probe_irradiance, AXES};
use inlay_passes::scene::{load_scene, Scene};

use crate::fidelity::{
    block_means, box_shadow_ratio, coverage, far_pixels, luminance, mean_ratio,
    median_relative_error, median_seed_noise, psnr, relative_l1, shadow_figures, side_by_side, Rgb,
    AREA_THRESHOLDS, FAR_RADII, SHADOW_EDGE, UMBRA,
};
use crate::field_source::{scene_field, scene_seen_lights, scene_sky};
use crate::headless::run_headless;
use crate::outputs::{check_output, Outputs};
use crate::scene_view::view_over_gpu_field;

/// Options of `fidelity`.
#[derive(Args, Debug)]
pub struct FidelityArgs {
    /// The scene file (a recipe: Cycles renders the recipe).
    pub scene: PathBuf,
    /// The directory `tools/cycles/render_cycles.py` wrote for this scene.
    #[arg(long)]
    pub cycles: PathBuf,
    /// Samples per pixel of `inlay reference`, per seed (two seeds).
    #[arg(long, default_value_t = 64)]
    pub samples: u32,
    /// Exposure for PSNR and the PNG pictures.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f64,
    /// The markdown report.
    #[arg(long, default_value = "inlay-fidelity.md")]
    pub out: PathBuf,
    /// Directory for side-by-side pictures (Cycles | inlay | difference).
    #[arg(long)]
    pub images: Option<PathBuf>,
    /// Leave out the path-traced reference (the slowest part).
    #[arg(long)]
    pub no_reference: bool,
    /// Rays a side per tile for the field's light at the object's surface
    /// (overrides `[shading] field_light`; 0: off).
    #[arg(long)]
    pub field_light: Option<u32>,
    /// A field trained from photographs of the scene (`inlay train`) to
    /// measure in place of the recipe's baked field. Its objects are lit
    /// by what the photographs show: the field, and as the distant light
    /// the sky learnt with it (FIELD.sky.exr beside it, also drawn behind
    /// the frame), not the recipe's known lights.
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// An environment file (`inlay estimate-env`'s) to light the objects
    /// with as their distant light, in place of the scene's (with
    /// `--field`: of the sky's).
    #[arg(long)]
    pub environment: Option<PathBuf>,
}

/// `scene` with the trained field `file` in place of its recipe's, lit as
/// a user of that field alone would light it: the recipe's hidden lights
/// and known environment give way to `sky` (the one learnt with the field)
/// as the distant light, or none without one; an estimated `[lighting]
/// environment` the scene names stays.
pub fn trained_scene(
    scene: &Scene,
    file: &Path,
    sky: Option<&inlay_passes::field::Sky>,
) -> anyhow::Result<Scene> {
    use inlay_passes::scene::{Environment, FieldSource};
    let mut lit = scene.clone();
    lit.field = FieldSource::File(file.to_path_buf());
    lit.environment = match sky {
        Some(s) => s
            .to_environment()
            .map_err(|e| anyhow::anyhow!("{}: {e}", sky_path(file).display()))?,
        None => Environment::Black,
    };
    lit.environment_file = sky.map(|_| sky_path(file));
    Ok(lit)
}

fn load(path: &Path) -> anyhow::Result<Rgb> {
    let image = HdrImage::load_exr(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(Rgb::of(&image))
}

/// The two seeds of a Cycles image and their mean.
struct CyclesPair {
    mean: Rgb,
    seeds: (Rgb, Rgb),
}

/// Averaging `BLOCK` × `BLOCK` pixels cuts the noise by `BLOCK`.
const BLOCK: u32 = 8;

/// Both seeds of a Cycles image, if present.
fn cycles_pair(dir: &Path, stem: &str) -> anyhow::Result<Option<CyclesPair>> {
    let (a, b) = (
        dir.join(format!("{stem}-s1.exr")),
        dir.join(format!("{stem}-s2.exr")),
    );
    if !a.exists() || !b.exists() {
        return Ok(None);
    }
    let (a, b) = (load(&a)?, load(&b)?);
    Ok(Some(CyclesPair {
        mean: Rgb::mean(&a, &b),
        seeds: (a, b),
    }))
}

/// A figure over `pixels` pixels, or a dash when there are none.
fn figure(value: f64, pixels: usize) -> String {
    if pixels == 0 || !value.is_finite() {
        "—".into()
    } else {
        format!("{value:.3}")
    }
}

/// One frame of `scene`'s field from `camera` at `size`, as `inlay render`
/// and the viewer draw it: with the scene's objects inserted (their SSDFs
/// baked or read through the cache) or, with `objects` false, the field
/// alone.
pub fn render_over_field(
    ctx: &Arc<Context>,
    library: &ShaderLibrary,
    scene: &Scene,
    field: &GpuGridField,
    camera: &CameraSpec,
    (w, h): (u32, u32),
    objects: bool,
) -> anyhow::Result<Rgb> {
    let mut view_scene = scene.clone();
    if !objects {
        view_scene.objects.clear();
    }
    let mut view = view_over_gpu_field(
        ctx,
        library,
        &view_scene,
        scene.march,
        field.clone(),
        camera.clone(),
        true,
    )?;
    Ok(Rgb::of(&run_headless(ctx, &mut view, w, h, 1, 0.0)?.image))
}

/// Runs `fidelity`.
pub fn run(ctx: &Arc<Context>, args: &FidelityArgs) -> anyhow::Result<()> {
    let mut scene = load_scene(&args.scene)?;
    scene.shading.field_light = args.field_light.unwrap_or(scene.shading.field_light);
    let recipe = scene
        .recipe()
        .ok_or_else(|| {
            anyhow::anyhow!(
                "{}: Cycles renders recipes; this scene's field is a file",
                scene.path.display()
            )
        })?
        .clone();
    anyhow::ensure!(
        args.cycles.is_dir(),
        "--cycles {}: no such directory (render it with tools/cycles/render_cycles.py)",
        args.cycles.display()
    );
    check_output("--out", &args.out, &["md"])?;
    if let Some(dir) = &args.images {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("--images: {}: {e}", dir.display()))?;
        check_output("--images", &dir.join("x.png"), &[])?;
    }
    let outputs = RefCell::new(Outputs::new());
    let mut md = String::new();
    writeln!(md, "## {}\n", scene.name)?;
    let trained = args.field.as_deref();
    let field = scene_field(&scene, trained, true, Some(ctx.info()))?;
    let sky = scene_sky(&scene, trained)?;
    let seen = scene_seen_lights(&scene, trained)?;
    // The scene the field is rendered and lit with.
    let lit = match trained {
        Some(f) => {
            writeln!(
                md,
                "The field trained from photographs, `{}`; its objects lit by the field and, as the distant light, {}{} (not the recipe's known lights).\n",
                f.display(),
                if sky.is_some() {
                    "the sky learnt with it (also drawn behind it)"
                } else {
                    "nothing: no sky was learnt with it"
                },
                match seen.len() {
                    0 => String::new(),
                    n => format!(
                        ", with the {n} light{} its photographs saw past its bounds (`{}`, also drawn with it) unless an environment file is given",
                        if n == 1 { "" } else { "s" },
                        inlay_passes::field::seen_lights_path(f).display()
                    ),
                }
            )?;
            let mut lit = trained_scene(&scene, f, sky.as_ref())?;
            lit.seen_lights = seen.clone();
            lit
        }
        None => scene.clone(),
    };
    let mut lit = lit;
    if let Some(file) = &args.environment {
        let light = inlay_passes::envest::load_environment_file(file)
            .map_err(|e| anyhow::anyhow!("--environment: {e}"))?;
        writeln!(
            md,
            "The objects' distant light: `{}` ({} lobes, {} point lights, {} lights seen past the bounds).\n",
            file.display(),
            light.lobes.len(),
            light.lights.len(),
            light.seen_lights.len()
        )?;
        lit.object_environment = Some(inlay_passes::scene::ObjectEnvironment::new(
            file.clone(),
            light,
        ));
    }
    let library = inlay_passes::shaders::library()?;
    // Probe irradiance per object.
    let gpu_field = GpuGridField::upload(ctx, &field)?
        .with_sky(sky.map(Arc::new))
        .with_seen_lights(seen);
    let library = gpu_field.library(&library);
    writeln!(md, "Irradiance at each object's centre (luminance; Cycles: a 1 mm white sensor per axis, two seeds):\n")?;
    writeln!(
        md,
        "| object | axis | Cycles | ± | probe | probe / Cycles | lobes | lobes / Cycles |"
    )?;
    writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- |")?;
    for object in &scene.objects {
        let path = args.cycles.join(format!("irradiance-{}.json", object.name));
        if !path.exists() {
            continue;
        }
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path)?)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        let (centre, _) = object.sphere();
        let env = inlay_passes::lighting::object_light_lobes(&lit, centre);
        let traced = crate::commands::probe::trace_and_fit(
            ctx,
            &gpu_field,
            centre,
            scene.lighting.probe,
            scene.lighting.fit,
            scene.march,
            &env,
        )?;
        let map = scene.lighting.probe.direction_map();
        let texels: Vec<[f64; 4]> = traced
            .probe
            .pixels
            .iter()
            .map(|p| p.map(f64::from))
            .collect();
        let lobes = &traced.lights;
        for (axis, n) in AXES {
            let seeds: Vec<f64> = ["s1", "s2"]
                .iter()
                .filter_map(|s| json["irradiance"][s][axis].as_array())
                .map(|v| {
                    let c: Vec<f64> = v.iter().filter_map(|x| x.as_f64()).collect();
                    luminance(DVec3::new(c[0], c[1], c[2]))
                })
                .collect();
            if seeds.len() != 2 {
                anyhow::bail!("{}: `irradiance.s1/s2.{axis}` missing", path.display());
            }
            let cycles = 0.5 * (seeds[0] + seeds[1]);
            let noise = 0.5 * (seeds[0] - seeds[1]).abs();
            // The probe holds L_env's broad lobes; its sharp ones are
            // shaded directly and count with it.
            let p = luminance(
                probe_irradiance(&map, &texels, n) + lobes_irradiance(traced.direct(), n),
            );
            let l = luminance(lobes_irradiance(lobes, n));
            writeln!(
                md,
                "| {} | {axis} | {cycles:.4} | {noise:.4} | {p:.4} | {:.3} | {l:.4} | {:.3} |",
                object.name,
                p / cycles,
                l / cycles
            )?;
        }
    }
    writeln!(md)?;
    // Images per camera, compared where the field covers the whole pixel
    // (inlay draws nothing outside the field's bounds; Cycles draws the
    // sky there) and, for the insertion's figures, the objects' pixels.
    writeln!(md, "Images against Cycles over the pixels the field covers (relative L1 in luminance per pixel and over {BLOCK}×{BLOCK} blocks, which averages Monte-Carlo noise away and leaves bias; mean luminance ratio; PSNR on sRGB values clamped at exposure {}). Cycles' own seed-to-seed figures give the noise's scale:\n", args.exposure)?;
    writeln!(md, "| camera | image | rel. L1 | rel. L1 {BLOCK}×{BLOCK} | mean ratio | PSNR dB | Cycles seeds rel. L1 | Cycles seeds {BLOCK}×{BLOCK} |")?;
    writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- |")?;
    let mut insertion = String::new();
    for (ci, camera) in scene.cameras.iter().enumerate() {
        let name = camera.name.clone().unwrap_or_else(|| ci.to_string());
        let Some(bare) = cycles_pair(&args.cycles, &format!("{name}-bare-full"))? else {
            continue;
        };
        let with = cycles_pair(&args.cycles, &format!("{name}-objects-full"))?;
        let (w, h) = (bare.mean.width, bare.mean.height);
        let frame = CameraFrame::new(camera, w, h);
        let bare_cover = coverage(&recipe, &[], &frame, 4);
        let object_cover = coverage(&recipe, &scene.objects, &frame, 4).object;
        let field_px = |i: usize| bare_cover.field[i] >= 1.0;
        let object_px = |i: usize| object_cover[i] >= 1.0;
        // Far from every object: the surface seen lies more than
        // FAR_RADII bounding radii from each object's centre.
        let spheres: Vec<(DVec3, f64)> = scene.objects.iter().map(|o| o.sphere()).collect();
        let far = far_pixels(&bare_cover, &spheres);
        let far_px = |i: usize| far[i];
        let reference = |objects: bool| -> Rgb {
            let run = |seed| {
                render_reference(
                    &recipe,
                    &scene.environment,
                    if objects { &scene.objects[..] } else { &[][..] },
                    &frame,
                    &ReferenceOptions {
                        samples: args.samples,
                        bounces: scene.bake.bounces,
                        seed,
                        antialias: true,
                        sky_behind: false,
                    },
                    &|_, _| {},
                )
            };
            let to = |p: Vec<[f32; 4]>| {
                Rgb::of(&HdrImage {
                    width: w,
                    height: h,
                    pixels: p,
                })
            };
            Rgb::mean(&to(run(1)), &to(run(2)))
        };
        let row = |md: &mut String,
                   what: &str,
                   img: &Rgb,
                   truth: &CyclesPair,
                   mask: &dyn Fn(usize) -> bool|
         -> anyhow::Result<()> {
            let blocks = |x: &Rgb| block_means(x, BLOCK, mask);
            writeln!(
                md,
                "| {name} | {what} | {:.4} | {:.4} | {:.3} | {:.2} | {:.4} | {:.4} |",
                relative_l1(img, &truth.mean, mask),
                relative_l1(&blocks(img), &blocks(&truth.mean), |_| true),
                mean_ratio(img, &truth.mean, mask),
                psnr(img, &truth.mean, args.exposure, mask),
                relative_l1(&truth.seeds.0, &truth.seeds.1, mask),
                relative_l1(&blocks(&truth.seeds.0), &blocks(&truth.seeds.1), |_| true),
            )?;
            if let Some(dir) = &args.images {
                let file = dir.join(format!(
                    "{}-{name}-{}.png",
                    scene.name,
                    what.replace([' ', ','], "-")
                ));
                let picture = side_by_side(&truth.mean, img).to_hdr();
                outputs
                    .borrow_mut()
                    .image(&file, &picture, args.exposure as f32)?;
            }
            Ok(())
        };
        let field_only = |i: usize| field_px(i) && object_cover[i] == 0.0;
        let object_count = (0..object_cover.len()).filter(|&i| object_px(i)).count();
        // The path tracer's image with the objects, when rendered: its
        // error on the objects is the two renderers' material models',
        // which the insertion cannot be expected to beat.
        let mut traced_objects = None;
        if !args.no_reference {
            let traced = reference(false);
            row(&mut md, "reference, bare", &traced, &bare, &field_px)?;
            if bare_cover.medium.iter().any(|&m| m > 0.0) {
                let clear = |i: usize| field_px(i) && bare_cover.medium[i] == 0.0;
                row(&mut md, "reference, bare, no media", &traced, &bare, &clear)?;
            }
            if let Some(with) = &with {
                let traced = reference(true);
                row(&mut md, "reference, objects", &traced, with, &|i| {
                    field_px(i) || object_px(i)
                })?;
                traced_objects = Some(traced);
            }
        }
        let field_image =
            render_over_field(ctx, &library, &lit, &gpu_field, camera, (w, h), false)?;
        row(&mut md, "field, bare", &field_image, &bare, &field_px)?;
        if gpu_field.sky.is_some() {
            row(
                &mut md,
                "field, bare, every pixel",
                &field_image,
                &bare,
                &|_| true,
            )?;
        }
        let Some(with) = with else {
            continue;
        };
        let inserted = render_over_field(ctx, &library, &lit, &gpu_field, camera, (w, h), true)?;
        row(&mut md, "insertion", &inserted, &with, &|i| {
            field_px(i) || object_px(i)
        })?;
        let ratio = |with: &Rgb, bare: &Rgb| box_shadow_ratio(with, bare, field_only);
        let (ours, theirs) = (
            ratio(&inserted, &field_image),
            ratio(&with.mean, &bare.mean),
        );
        let seeds = shadow_figures(
            &ratio(&with.seeds.0, &bare.seeds.0),
            &ratio(&with.seeds.1, &bare.seeds.1),
            field_only,
            far_px,
        );
        if let Some(dir) = &args.images {
            // Cycles' ratio | inlay's | difference, over the field's own
            // pixels (elsewhere 1): where each darkens the field.
            let ratio_image = |r: &[f64]| Rgb {
                width: w,
                height: h,
                pixels: (0..r.len())
                    .map(|i| DVec3::splat(if field_only(i) { r[i] } else { 1.0 }))
                    .collect(),
            };
            let picture = side_by_side(&ratio_image(&theirs), &ratio_image(&ours)).to_hdr();
            // The PNG to look at, the EXR to measure (its ratios unclamped).
            for ext in ["png", "exr"] {
                let file = dir.join(format!("{}-{name}-shadow-ratio.{ext}", scene.name));
                outputs.borrow_mut().image(&file, &picture, 1.0)?;
            }
        }
        let shadow = shadow_figures(&ours, &theirs, field_only, far_px);
        // Cycles with glTF's own Lambertian diffuse in place of the
        // Principled BSDF's Burley (`render_cycles.py --object-diffuse
        // lambert`), where rendered: how much of the error is that model.
        let lambert_median = cycles_pair(&args.cycles, &format!("{name}-objects-full-lambert"))?
            .map_or("—".to_string(), |l| {
                figure(
                    median_relative_error(&inserted, &l.mean, object_px),
                    object_count,
                )
            });
        let traced_median = traced_objects.as_ref().map_or("—".to_string(), |t| {
            figure(
                median_relative_error(t, &with.mean, object_px),
                object_count,
            )
        });
        writeln!(
            insertion,
            "| {name} | {} | {} | {lambert_median} | {traced_median} | {} | {object_count} | {:.3} | {:.2} ({} px) | {} | {:.3} | {:.2} % | {:.2} % ({} px) | {:.2} / {:.2} ({} px) | {:.3}, {:.2} |",
            figure(mean_ratio(&inserted, &with.mean, object_px), object_count),
            figure(median_relative_error(&inserted, &with.mean, object_px), object_count),
            figure(median_seed_noise(&with.seeds.0, &with.seeds.1, object_px), object_count),
            shadow.correlation,
            shadow.area_ratio,
            shadow.truth_area,
            shadow
                .area_ratios
                .map(|a| format!("{a:.2}"))
                .join(", "),
            shadow.darkening_ratio,
            100.0 * shadow.far_darkening,
            100.0 * shadow.truth_far_darkening,
            shadow.far_pixels,
            shadow.truth_umbra,
            shadow.umbra,
            shadow.umbra_pixels,
            seeds.correlation,
            seeds.area_ratio,
        )?;
    }
    writeln!(md)?;
    if !insertion.is_empty() {
        writeln!(md, "The insertion against Cycles with the objects (object mask: pixels whose 16 rays all hit an object first; the same against Cycles with glTF's Lambertian diffuse for the objects' Principled (Burley) one, where rendered (`*-objects-full-lambert-*.exr`); median relative error of inlay's path tracer with the objects, where rendered: the two renderers' material models; of Cycles' noise: the median |s₀ − s₁| / (s₀ + s₁) of its two seeds, what a noise-free renderer scores against their mean; shadow: the luminance ratio of the images with and without the objects, each a mean over 3 × 3 pixels of the field alone, inlay's against Cycles', over the pixels the field alone covers; area at several ratios, and the total darkening Σ max(1 − ratio, 0) over the pixels either darkens below {SHADOW_EDGE}; far: surface points more than {FAR_RADII} bounding radii from every object; Cycles' two seeds against each other give the noise's scale):\n")?;
        writeln!(md, "| camera | object brightness inlay / Cycles | median relative error | the same, Cycles with Lambert's diffuse | median relative error, path tracer | median error of Cycles' noise | mask px | shadow correlation | shadow area (< 0.9) inlay / Cycles | area at {} | total darkening inlay / Cycles | far darkening, inlay | far darkening, Cycles | umbra (Cycles < {UMBRA}): Cycles / inlay mean ratio | Cycles seeds: correlation, area |", AREA_THRESHOLDS.map(|t| t.to_string()).join(", "))?;
        writeln!(
            md,
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
        )?;
        md.push_str(&insertion);
        writeln!(md)?;
    }
    print!("{md}");
    let mut outputs = outputs.into_inner();
    outputs.bytes(&args.out, md.as_bytes())?;
    outputs.commit(Some(ctx))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use inlay_passes::field::Sky;
    use inlay_passes::scene::{Environment, FieldSource};

    /// A trained field's scene is lit by its sky (or nothing), never by the
    /// recipe's known lights; an estimate the scene names stays.
    #[test]
    fn a_trained_field_is_lit_by_its_sky_not_the_recipes_lights() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cups.toml");
        let scene = load_scene(&path).unwrap();
        assert!(scene.recipe().is_some() && !scene.environment.is_black());
        let file = Path::new("/nowhere/cups.inlayfield");
        let sky = Sky::uniform(4, DVec3::new(0.5, 1.0, 2.0));
        let lit = trained_scene(&scene, file, Some(&sky)).unwrap();
        assert!(matches!(&lit.field, FieldSource::File(f) if f == file));
        assert!(lit.recipe().is_none());
        assert_eq!(lit.environment.eval(DVec3::Y), sky.eval(DVec3::Y));
        assert_eq!(
            lit.environment_file.as_deref(),
            Some(Path::new("/nowhere/cups.sky.exr"))
        );
        // The lobes the objects are lit with come from the sky alone.
        let lobes = inlay_passes::lighting::object_light_lobes(&lit, DVec3::ZERO);
        let up: DVec3 = lobes.iter().map(|l| l.eval(DVec3::Y)).sum();
        assert!((up - sky.eval(DVec3::Y)).abs().max_element() < 0.2, "{up}");
        let dark = trained_scene(&scene, file, None).unwrap();
        assert!(matches!(dark.environment, Environment::Black));
        assert!(inlay_passes::lighting::object_light_lobes(&dark, DVec3::ZERO).is_empty());
    }
}
