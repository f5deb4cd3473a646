//! Getting an object's SSDF field: a `.inlayssdf` file, or a bake on the
//! GPU (with a progress bar and a report of its size) kept in the cache so
//! the next run loads it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context as _;
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::Context;
use inlay_passes::object::ObjectMesh;
use inlay_passes::ssdf::{load_ssdf, save_ssdf, SsdfBaker, SsdfField, SsdfKnobs, SSDF_VERSION};

use crate::field_source::{cache_dir, fnv1a, progress_bar};

/// What a bake measured.
#[derive(Debug, Clone, Copy)]
pub struct SsdfBakeReport {
    /// Seconds of the GPU bake (ray casts and silhouettes).
    pub bake_seconds: f64,
    /// Seconds of the PCA.
    pub pca_seconds: f64,
    /// Bytes of the raw samples (f32).
    pub raw_bytes: u64,
    /// Bytes of the compressed field.
    pub compressed_bytes: u64,
    /// RMS of the compression's error over all samples (radians).
    pub rms_error: f64,
    /// Largest compression error (radians).
    pub max_error: f64,
}

impl std::fmt::Display for SsdfBakeReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "bake {:.2} s + PCA {:.2} s; raw {:.2} MB, compressed {:.1} kB ({:.2} % of raw); PCA error rms {:.4} rad, max {:.3} rad",
            self.bake_seconds,
            self.pca_seconds,
            self.raw_bytes as f64 / 1e6,
            self.compressed_bytes as f64 / 1e3,
            100.0 * self.compressed_bytes as f64 / self.raw_bytes as f64,
            self.rms_error,
            self.max_error
        )
    }
}

/// Bakes and compresses `mesh`'s SSDF field with `knobs`, showing progress.
pub fn bake_ssdf_with_progress(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    mesh: &Arc<ObjectMesh>,
    knobs: &SsdfKnobs,
) -> anyhow::Result<(SsdfField, SsdfBakeReport)> {
    let baker = SsdfBaker::new(ctx, lib)?;
    let bar = progress_bar("ssdf", knobs.grid.pow(3) as u64);
    let samples = baker.bake(ctx, mesh, knobs, &|done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let started = std::time::Instant::now();
    let field = SsdfField::compress(&samples, knobs.components);
    let pca_seconds = started.elapsed().as_secs_f64();
    let texels = field.texels();
    let (mut sum, mut max) = (0.0f64, 0.0f64);
    for (i, v) in samples.values.iter().enumerate() {
        let e = field.node_value(i / texels, i % texels) - *v as f64;
        sum += e * e;
        max = max.max(e.abs());
    }
    let report = SsdfBakeReport {
        bake_seconds: samples.seconds,
        pca_seconds,
        raw_bytes: field.raw_bytes(),
        compressed_bytes: field.compressed_bytes(),
        rms_error: (sum / samples.values.len() as f64).sqrt(),
        max_error: max,
    };
    eprintln!(
        "baked the SSDF field of {} ({}³ nodes, {}² directions, {} components): {report}",
        mesh.name, knobs.grid, knobs.directions, field.components
    );
    Ok((field, report))
}

fn cache_path(object_file: &Path, knobs: &SsdfKnobs) -> anyhow::Result<Option<PathBuf>> {
    let Some(dir) = cache_dir() else {
        return Ok(None);
    };
    let bytes = std::fs::read(object_file)
        .with_context(|| format!("{}: cannot read", object_file.display()))?;
    let mut h = fnv1a(&bytes, 0xcbf29ce484222325);
    let key = format!(
        "{knobs:?} ssdf v{SSDF_VERSION} {}",
        env!("CARGO_PKG_VERSION")
    );
    h = fnv1a(key.as_bytes(), h);
    let stem = object_file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(Some(dir.join(format!("{stem}-{h:016x}.inlayssdf"))))
}

/// An object's SSDF field: `file` when the scene names one, else baked
/// from `mesh` (loaded from `object_file`) with `knobs`, through the cache
/// when `use_cache`. The cache key hashes the object file's bytes, so an
/// edited object is baked again.
pub fn object_ssdf(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    mesh: &Arc<ObjectMesh>,
    object_file: &Path,
    file: Option<&Path>,
    knobs: &SsdfKnobs,
    use_cache: bool,
) -> anyhow::Result<SsdfField> {
    if let Some(f) = file {
        return Ok(load_ssdf(f)?);
    }
    let cached = if use_cache {
        cache_path(object_file, knobs)?
    } else {
        None
    };
    if let Some(path) = &cached {
        if path.exists() {
            match load_ssdf(path) {
                Ok(f) => {
                    log::info!("loaded the SSDF field from {}", path.display());
                    return Ok(f);
                }
                Err(e) => log::warn!("ignoring a bad cached SSDF field: {e}"),
            }
        }
    }
    let (field, _) = bake_ssdf_with_progress(ctx, lib, mesh, knobs)?;
    if let Some(path) = &cached {
        let saved = std::fs::create_dir_all(path.parent().unwrap_or(Path::new(".")))
            .map_err(anyhow::Error::from)
            .and_then(|_| Ok(save_ssdf(&field, path)?));
        if let Err(e) = saved {
            log::warn!("could not cache the SSDF field: {e:#}");
        }
    }
    Ok(field)
}
