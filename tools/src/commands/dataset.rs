//! `inlay dataset`: reads a dataset of posed photographs (`transforms.json`
//! in the Blender synthetic, instant-ngp or nerfstudio dialect) as a
//! trainer will, and says what it found: the dialect, frames, cameras,
//! the field's bounds and where they came from, and the pixels that are
//! not values. Every frame that cannot be used is listed.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use glam::DVec3;
use inlay_passes::dataset::{load_dataset, Distortion, LoadOptions};
use inlay_passes::geometry::Aabb;

/// Arguments of `inlay dataset`.
#[derive(Args, Debug)]
pub struct DatasetArgs {
    /// The dataset: a transforms.json, or a folder holding one (or
    /// `transforms_<split>.json`).
    pub path: PathBuf,
    /// The field's bounds, min x,y,z then max x,y,z (overrides the file's).
    #[arg(long, value_parser = parse_bounds, allow_hyphen_values = true)]
    pub bounds: Option<Aabb>,
    /// Linear RGB that transparent pixels are composited over (black, as
    /// `inlay train` reads them by default).
    #[arg(long, value_parser = parse_rgb, default_value = "0,0,0")]
    pub background: [f32; 3],
    /// The Blender synthetic split to read.
    #[arg(long, default_value = "train")]
    pub split: String,
    /// Leave out the frames that cannot be used instead of failing.
    #[arg(long)]
    pub skip_bad_frames: bool,
    /// Read each photograph at 1/N of its width and height (each N x N
    /// block one pixel), as `inlay train --downscale N` does.
    #[arg(long, default_value_t = 1)]
    pub downscale: u32,
}

/// The memory this machine has available, in bytes (Linux's
/// `MemAvailable`); None where it cannot be read, and then a dataset is
/// read whatever it holds.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// `x,y,z,X,Y,Z` as a box.
pub fn parse_bounds(s: &str) -> Result<Aabb, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|e| format!("{t}: {e}")))
        .collect::<Result<_, _>>()?;
    if v.len() != 6 {
        return Err("expected six numbers: min x,y,z,max x,y,z".into());
    }
    let b = Aabb::new(DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]));
    if !b.is_valid() {
        return Err("each max must exceed its min, all finite".into());
    }
    Ok(b)
}

/// `r,g,b` as linear RGB.
pub fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>().map_err(|e| format!("{t}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [r, g, b] if v.iter().all(|c| c.is_finite() && *c >= 0.0) => Ok([r, g, b]),
        _ => Err("expected three finite, non-negative numbers r,g,b".into()),
    }
}

/// Runs `inlay dataset`.
pub fn run(args: &DatasetArgs) -> Result<()> {
    let options = LoadOptions {
        bounds: args.bounds,
        background: args.background,
        split: args.split.clone(),
        skip_bad_frames: args.skip_bad_frames,
        downscale: args.downscale,
        memory_available: available_memory(),
    };
    let mut d = load_dataset(&args.path, &options)?;
    println!("{}: {} dialect", d.file.display(), d.dialect);
    println!(
        "frames: {} usable{}",
        d.frames.len(),
        if d.skipped.is_empty() {
            String::new()
        } else {
            format!(", {} left out:", d.skipped.len())
        }
    );
    for p in &d.skipped {
        println!("  {}: {}", p.key, p.problem);
    }
    let mut sizes: Vec<(u32, u32)> = d
        .frames
        .iter()
        .map(|f| (f.intrinsics.width, f.intrinsics.height))
        .collect();
    sizes.sort_unstable();
    sizes.dedup();
    let sizes: Vec<String> = sizes.iter().map(|(w, h)| format!("{w}x{h}")).collect();
    let (fmin, fmax) = d.frames.iter().fold((f64::MAX, 0.0f64), |(a, b), f| {
        (a.min(f.intrinsics.fx), b.max(f.intrinsics.fx))
    });
    let distorted = d
        .frames
        .iter()
        .filter(|f| f.intrinsics.distortion != Distortion::None)
        .count();
    println!(
        "images: {}{}; focal length fx {fmin:.1}–{fmax:.1} px; {distorted} with lens distortion (undistorted exactly)",
        sizes.join(", "),
        if args.downscale > 1 {
            format!(" (read at 1/{} of their size)", args.downscale)
        } else {
            String::new()
        }
    );
    let timed = d
        .frames
        .iter()
        .filter(|f| f.exposure_time.is_some())
        .count();
    if timed > 0 {
        let exif = d
            .frames
            .iter()
            .filter(|f| f.exif_exposure.is_some())
            .count();
        println!("exposure_time given for {timed} frames ({exif} from the images' EXIF, scaled by their ISO and f-number where recorded)");
    }
    let b = d.bounds;
    println!(
        "bounds: {:.3} {:.3} {:.3} to {:.3} {:.3} {:.3}, from {}",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z, d.bounds_source
    );
    if let Some(w) = d.blind_frames_warning() {
        println!("warning: {w}");
    }
    if let Some(w) = d.dark_frames_warning() {
        println!("warning: {w}");
    }
    if let Some(w) = d.turned_frames_warning() {
        println!("warning: {w}");
    }
    let total: usize = d.frames.iter().map(|f| f.image.state.len()).sum();
    let c = d.counts;
    println!(
        "pixels: {total}; masked: {} NaN or infinite, {} negative, {} by masks; {} saturated (lower bounds); {} with alpha below 1",
        c.non_finite, c.negative, c.masked, c.saturated, c.transparent
    );
    let depth = inlay_passes::dataset::depth::DepthCounts::of(&d.frames);
    if let Some(line) = depth.line(d.frames.len()) {
        println!("{line}");
    }
    if let Some(w) = inlay_passes::train::pixels::saturated_in_every_bracket(&d).warning() {
        println!("warning: {w}");
    }
    let every: Vec<u32> = (0..d.frames.len() as u32).collect();
    let lum = luminance_quantiles(&d);
    // The lights past the bounds, found and left out as training finds and
    // leaves them, before the share of light past the bounds is read.
    let lights = report_seen_lights(&d, &every);
    let masked = inlay_passes::train::seen_lights::mask_seen_lights(&mut d, &lights, &every);
    let past = inlay_passes::train::past_bounds::light_past_bounds(&d, &every, &d.bounds);
    println!(
        "past the bounds: {} of {} pixels, {:.1} % of the views' light{}",
        past.pixels,
        past.of,
        100.0 * past.share,
        if masked > 0 {
            format!(" (the lights' {masked} pixels left out, as training leaves them)")
        } else {
            String::new()
        }
    );
    if let Some(w) = past.warning() {
        println!("warning: {w}");
    }
    if let Some([median, p99, max]) = lum {
        println!(
            "radiance (luminance): median {median:.4}, 99th percentile {p99:.4}, max {max:.4}"
        );
    }
    Ok(())
}

/// Prints the lights past the bounds `inlay train` would find in `d`'s
/// frames `frames` (all of them: `--hold-out` is the trainer's), and those
/// it would leave to the field inside them; returns the lights past them.
fn report_seen_lights(
    d: &inlay_passes::dataset::Dataset,
    frames: &[u32],
) -> Vec<inlay_passes::train::seen_lights::SeenLight> {
    use inlay_passes::train::seen_lights::{find_seen_lights, LIGHT_RATIO, MIN_VIEWS};
    let scale = inlay_passes::train::trainer::radiance_scale(d, frames, &d.bounds);
    let found = find_seen_lights(d, frames, &d.bounds, scale);
    for (l, &saturated) in found.lights.iter().zip(&found.saturated) {
        for line in super::seen_lights::light_lines(l, saturated, "views", scale) {
            println!("{line}");
        }
    }
    if found.lights.is_empty() {
        println!(
            "lights past the bounds: none (no spot over {LIGHT_RATIO:.0}x the photographs' scale \
             {scale:.3e} seen from {MIN_VIEWS} views or more)"
        );
    }
    if !found.inside.is_empty() {
        let at: Vec<String> = found
            .inside
            .iter()
            .map(|c| format!("({:.3}, {:.3}, {:.3})", c.x, c.y, c.z))
            .collect();
        println!(
            "lights inside the bounds, the field's to hold: {}",
            at.join(", ")
        );
    }
    found.lights
}

/// The median, 99th percentile and largest luminance of `d`'s pixels that
/// are not masked; None where every pixel is.
fn luminance_quantiles(d: &inlay_passes::dataset::Dataset) -> Option<[f32; 3]> {
    let mut lum: Vec<f32> = d
        .frames
        .iter()
        .flat_map(|f| {
            f.image
                .radiance
                .iter()
                .zip(&f.image.state)
                .filter(|(_, s)| **s != inlay_passes::dataset::PixelState::Masked)
                .map(|(p, _)| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        })
        .collect();
    if lum.is_empty() {
        return None;
    }
    lum.sort_by(f32::total_cmp);
    let q = |f: f64| lum[((lum.len() - 1) as f64 * f) as usize];
    Some([q(0.5), q(0.99), q(1.0)])
}
