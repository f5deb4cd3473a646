//! Getting a scene's field: a field file, or its recipe baked (with a
//! progress bar) and kept in a cache so the next run loads it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use indicatif::{ProgressBar, ProgressStyle};
use inlay_passes::bake::{bake_grid, BakeKnobs};
use inlay_passes::field::{load_field, save_field, GridField, FIELD_VERSION};
use inlay_passes::scene::{FieldSource, Scene};

/// Environment variable naming the directory baked fields are cached in.
pub const CACHE_ENV: &str = "INLAY_CACHE_DIR";

/// A progress bar on stderr for `total` steps of `what` (hidden when stderr
/// is not a terminal).
pub fn progress_bar(what: &str, total: u64) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:>12} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}

/// Bakes a recipe scene's field with `knobs`, showing progress.
pub fn bake_with_progress(scene: &Scene, knobs: &BakeKnobs) -> anyhow::Result<GridField> {
    let recipe = scene.recipe().with_context(|| {
        format!(
            "{}: the scene has no [recipe] to bake",
            scene.path.display()
        )
    })?;
    knobs
        .check()
        .map_err(|(k, m)| anyhow::anyhow!("bake knob `{k}`: {m}"))?;
    let started = Instant::now();
    let res = inlay_passes::bake::grid_resolution(recipe, knobs.resolution);
    let bar = progress_bar("baking", res.z as u64);
    let field = bake_grid(recipe, &scene.environment, knobs, &|done, _| {
        bar.set_position(done)
    });
    bar.finish_and_clear();
    eprintln!(
        "baked {} ({}x{}x{} nodes, {} samples, {} bounces) in {:.2} s",
        scene.name,
        res.x,
        res.y,
        res.z,
        knobs.samples,
        knobs.bounces,
        started.elapsed().as_secs_f64()
    );
    Ok(field)
}

/// The directory baked fields are cached in, if one can be used.
pub(crate) fn cache_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os(CACHE_ENV) {
        return Some(PathBuf::from(d));
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return Some(PathBuf::from(d).join("inlay"));
    }
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache").join("inlay"))
}

/// FNV-1a: a stable hash for cache keys.
pub(crate) fn fnv1a(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

fn cache_path(scene: &Scene, knobs: &BakeKnobs) -> anyhow::Result<Option<PathBuf>> {
    let Some(dir) = cache_dir() else {
        return Ok(None);
    };
    let text = std::fs::read(&scene.path)
        .with_context(|| format!("{}: cannot read", scene.path.display()))?;
    let mut h = fnv1a(&text, 0xcbf29ce484222325);
    let key = format!(
        "{knobs:?} v{FIELD_VERSION} r{} {}",
        inlay_passes::bake::BAKE_REVISION,
        env!("CARGO_PKG_VERSION")
    );
    h = fnv1a(key.as_bytes(), h);
    Ok(Some(
        dir.join(format!("{}-{h:016x}.inlayfield", scene.name)),
    ))
}

/// The scene's field: `override_file` when given, else its field file, else
/// its recipe baked with the scene's knobs (from the cache unless
/// `use_cache` is false).
pub fn scene_field(
    scene: &Scene,
    override_file: Option<&Path>,
    use_cache: bool,
) -> anyhow::Result<GridField> {
    if let Some(f) = override_file {
        return Ok(load_field(f)?);
    }
    match &scene.field {
        FieldSource::File(f) => Ok(load_field(f)?),
        FieldSource::Recipe(_) => {
            let cached = if use_cache {
                cache_path(scene, &scene.bake)?
            } else {
                None
            };
            if let Some(path) = &cached {
                if path.exists() {
                    match load_field(path) {
                        Ok(f) => {
                            log::info!("loaded the baked field from {}", path.display());
                            return Ok(f);
                        }
                        Err(e) => log::warn!("ignoring a bad cached field: {e}"),
                    }
                }
            }
            let field = bake_with_progress(scene, &scene.bake)?;
            if let Some(path) = &cached {
                let saved = std::fs::create_dir_all(path.parent().unwrap_or(Path::new(".")))
                    .map_err(anyhow::Error::from)
                    .and_then(|_| Ok(save_field(path, &field)?));
                if let Err(e) = saved {
                    log::warn!("could not cache the baked field: {e:#}");
                }
            }
            Ok(field)
        }
    }
}
