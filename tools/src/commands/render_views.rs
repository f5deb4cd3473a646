//! `inlay render-views SCENE --views N --size WxH --out DIR`: a training
//! set of a recipe scene, path traced without its objects from cameras
//! spread over a cap around the field, as a capture would be: linear EXR
//! frames and a `transforms.json` in instant-ngp's convention (with the
//! field's bounds as `aabb`), and optionally bracketed sRGB PNGs of the
//! same views with their `exposure_time` in `DIR/brackets/`. With
//! `--sky-behind` what the cameras see past the bounds is the scene's
//! environment, not black. With `--depth` each view also has a depth map,
//! as a capture with a depth sensor would (`depth_file_path`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{ensure, Result};
use clap::Args;
use inlay_engine::HdrImage;
use inlay_passes::bake::{render_reference, PathTracer, ReferenceOptions};
use inlay_passes::camera::CameraFrame;
use inlay_passes::dataset::capture::{
    bracket_png, cap_cameras, recipe_depth_map, transforms_json, Capture, UnrecordedLight,
    WrittenFrame,
};
use inlay_passes::dataset::depth::{depth_png, PNG_DEPTH_UNIT};
use inlay_passes::scene::load_scene;

use crate::field_source::progress_bar;
use crate::outputs::{check_output, Outputs};

/// Arguments of `inlay render-views`.
#[derive(Args, Debug)]
pub struct RenderViewsArgs {
    /// The scene file (TOML with a `[recipe]`).
    pub scene: PathBuf,
    /// Number of views.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=10000))]
    pub views: u32,
    /// Image size, WxH.
    #[arg(long, default_value = "96x96", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The folder to write (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 40.0)]
    pub fov: f64,
    /// Samples per pixel (jittered over the pixel, as a sensor integrates).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub samples: u32,
    /// Indirect bounces (default: the scene's `[bake] bounces`).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Also write bracketed 8-bit sRGB PNGs at these exposure values
    /// (stops; exposure_time = 2^EV), e.g. `-4,-2,0,2`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub brackets: Vec<f64>,
    /// The cap's azimuths, degrees from +x towards +z, e.g. `0,90`: where a
    /// photographer can stand (default: the scene's `[capture] azimuth`,
    /// else all the way round).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "FROM,TO"
    )]
    pub azimuth: Option<Vec<f64>>,
    /// Pixels that see past the field's bounds show the scene's
    /// environment, as a photograph sees past any box (default: black
    /// there). Train such a set with `inlay train --sky`.
    #[arg(long)]
    pub sky_behind: bool,
    /// Also write each view's depth map (`depth-NNN.png`, 16-bit z-depths
    /// in thousandths of the scene's units, its `depth_file_path`): the
    /// recipe's expected depth along each pixel's centre ray where it is
    /// at least half opaque, nothing elsewhere, as a depth sensor records.
    #[arg(long)]
    pub depth: bool,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// `WxH` as a size.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or("expected WxH, e.g. 96x96")?;
    let p = |t: &str| t.trim().parse::<u32>().map_err(|e| format!("{t}: {e}"));
    let (w, h) = (p(w)?, p(h)?);
    if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
        return Err(format!("{w}x{h} is out of range (1..=8192 per side)"));
    }
    Ok((w, h))
}

/// Runs `inlay render-views`.
pub fn run(args: &RenderViewsArgs) -> Result<()> {
    ensure!(
        args.fov > 0.0 && args.fov < 170.0,
        "--fov {} is outside (0, 170) degrees",
        args.fov
    );
    ensure!(
        args.brackets
            .iter()
            .all(|e| e.is_finite() && e.abs() <= 20.0),
        "--brackets: exposure values must be finite stops within ±20"
    );
    let scene = load_scene(&args.scene)?;
    let recipe = scene.recipe().ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the scene's field is a file, not a [recipe]: there is nothing to path trace",
            scene.path.display()
        )
    })?;
    super::crossing_bounds::warn_crossing_bounds(
        &scene.path,
        recipe,
        recipe.bounds,
        "the recipe's",
    );
    let (w, h) = args.size;
    std::fs::create_dir_all(&args.out)?;
    let brackets_dir = args.out.join("brackets");
    if !args.brackets.is_empty() {
        std::fs::create_dir_all(&brackets_dir)?;
    }
    let transforms = args.out.join("transforms.json");
    check_output("--out", &transforms, &["json"])?;
    let capture = match args.azimuth.as_deref() {
        Some(&[azimuth_from, azimuth_to]) => Capture {
            azimuth_from,
            azimuth_to,
        },
        Some(_) => anyhow::bail!("--azimuth takes two angles, FROM,TO"),
        None => scene.capture,
    };
    if let Some(m) = capture.problem() {
        anyhow::bail!("--azimuth {m}");
    }
    let cameras = cap_cameras(
        &recipe.bounds,
        args.views,
        args.fov,
        w as f64 / h as f64,
        &capture,
    );
    let options = ReferenceOptions {
        samples: args.samples,
        bounces: args.bounces.unwrap_or(scene.bake.bounces),
        seed: args.seed,
        antialias: true,
        sky_behind: args.sky_behind,
    };
    // Its nearest_surface alone is used: no bounces.
    let tracer = args
        .depth
        .then(|| PathTracer::new(recipe, &scene.environment, 0));
    let started = Instant::now();
    let bar = progress_bar("views", args.views as u64);
    let mut outputs = Outputs::new();
    let mut frames = Vec::new();
    let mut bracketed = Vec::new();
    let shortest = args.brackets.iter().copied().reduce(f64::min);
    let mut unrecorded = UnrecordedLight::default();
    for (i, camera) in cameras.iter().enumerate() {
        let frame = CameraFrame::new(camera, w, h);
        let pixels = render_reference(
            recipe,
            &scene.environment,
            &[],
            &frame,
            &ReferenceOptions {
                seed: options.seed.wrapping_add(i as u64),
                ..options
            },
            &|_, _| {},
        );
        // Radiance premultiplied by the share of the pixel the field
        // covers, that share as alpha (so a trainer can put any background
        // behind the rest), or with --sky-behind over the environment
        // (opaque).
        let image = HdrImage {
            width: w,
            height: h,
            pixels: pixels.to_vec(),
        };
        let file = format!("view-{i:03}.exr");
        outputs.image(&args.out.join(&file), &image, 1.0)?;
        let depth_file = match &tracer {
            Some(t) => {
                let name = format!("depth-{i:03}.png");
                let z = recipe_depth_map(recipe, t, &frame);
                outputs.bytes(&args.out.join(&name), &depth_png(&z, w, h, PNG_DEPTH_UNIT))?;
                Some(name)
            }
            None => None,
        };
        frames.push(WrittenFrame {
            file,
            camera: camera.clone(),
            exposure_time: None,
            depth_file,
        });
        let rgb: Vec<[f32; 3]> = pixels.iter().map(|p| [p[0], p[1], p[2]]).collect();
        if let Some(ev) = shortest {
            unrecorded.add_view(&rgb, 2f64.powf(ev) as f32);
        }
        for ev in &args.brackets {
            let exposure = 2f64.powf(*ev);
            let file = format!("view-{i:03}-ev{ev:+}.png");
            outputs.bytes(
                &brackets_dir.join(&file),
                &bracket_png(&rgb, w, h, exposure as f32),
            )?;
            bracketed.push(WrittenFrame {
                file,
                camera: camera.clone(),
                exposure_time: Some(exposure),
                depth_file: None,
            });
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    outputs.json(&transforms, &transforms_json(&frames, w, h, &recipe.bounds))?;
    if !bracketed.is_empty() {
        outputs.json(
            &brackets_dir.join("transforms.json"),
            &transforms_json(&bracketed, w, h, &recipe.bounds),
        )?;
    }
    let written = outputs.commit(None)?;
    let arc = if capture.is_full() {
        "all the way round".to_string()
    } else {
        format!(
            "from azimuths {}° to {}°",
            capture.azimuth_from, capture.azimuth_to
        )
    };
    eprintln!(
        "{} views of {w}x{h} {arc} at {} samples per pixel in {:.1} s ({} files)",
        args.views,
        args.samples,
        started.elapsed().as_secs_f64(),
        written.len()
    );
    if let (Some(ev), Some(needed)) = (shortest, unrecorded.stops_needed()) {
        eprintln!(
            "warning: {} pixels of {} views saturate even the shortest bracket (EV {ev:+}), up to \
             {:.1} times its white, with {:.0} % of the views' light: the brackets hold only a \
             lower bound there, so a field trained from them keeps whatever brightness its loss \
             gives those lights; a bracket at EV {needed:+} or below would record them",
            unrecorded.pixels,
            unrecorded.views,
            unrecorded.brightest as f64 * 2f64.powf(ev),
            100.0 * unrecorded.light_share()
        );
    }
    Ok(())
}
