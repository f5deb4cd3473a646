//! Getting an object's SSDF field: a `.inlayssdf` file, or a bake on the
//! GPU (with a progress bar and a report of its size) kept in the cache so
//! the next run loads it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use inlay_engine::shader::ShaderLibrary;
use inlay_engine::Context;
use inlay_passes::object::{gltf_files, ObjectMesh};
use inlay_passes::ssdf::{
    check_ssdf_object, load_ssdf, ssdf_bytes, SsdfBaker, SsdfField, SsdfKnobs, SSDF_VERSION,
};

use crate::cache::{entry_path, load_or_make, CacheKey};
use crate::field_source::progress_bar;

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
    let samples = baker.bake(ctx, mesh, knobs, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    })?;
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
    eprintln!(
        "  {} of {} nodes blended from coarser lattices (coarse angle {} rad), the rest baked",
        samples.blended,
        knobs.grid.pow(3),
        knobs.coarse_angle
    );
    let kernels: Vec<String> = samples
        .kernel_seconds
        .iter()
        .map(|(name, s)| format!("{} {s:.2} s", name.trim_start_matches("ssdf-")))
        .collect();
    eprintln!("  GPU time by kernel: {}", kernels.join(", "));
    Ok((field, report))
}

/// The cache entry of the SSDF baked from `object_file` with `knobs`: its
/// key hashes the object file and every buffer and image it refers to, the
/// knobs and the SSDF format's version.
fn cache_entry(object_file: &Path, knobs: &SsdfKnobs) -> anyhow::Result<Option<PathBuf>> {
    let files = gltf_files(object_file)?;
    let key = CacheKey::new("ssdf")
        .files(&files)?
        .text("knobs", &format!("{knobs:?}"))
        .text("revision", &format!("v{SSDF_VERSION}"))
        .text(
            "bake",
            &format!("r{}", inlay_passes::ssdf::bake::BAKE_REVISION),
        );
    let stem = object_file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(entry_path(&stem, key, "inlayssdf"))
}

/// An object's SSDF field: `file` when the scene names one, else baked
/// from `mesh` (loaded from `object_file`) with `knobs`, through the cache
/// when `use_cache` (keyed by content: an edited object, its `.bin` or its
/// textures included, is baked again).
pub fn object_ssdf(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    mesh: &Arc<ObjectMesh>,
    object_file: &Path,
    file: Option<&Path>,
    knobs: &SsdfKnobs,
    use_cache: bool,
) -> anyhow::Result<SsdfField> {
    let load_for_mesh = |path: &Path| -> anyhow::Result<SsdfField> {
        let field = load_ssdf(path)?;
        check_ssdf_object(&field, path, mesh)?;
        Ok(field)
    };
    if let Some(f) = file {
        return load_for_mesh(f);
    }
    let entry = if use_cache {
        cache_entry(object_file, knobs)?
    } else {
        None
    };
    load_or_make(
        entry.as_deref(),
        "SSDF field",
        load_for_mesh,
        || Ok(bake_ssdf_with_progress(ctx, lib, mesh, knobs)?.0),
        ssdf_bytes,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An edit to a glTF's `.bin` (or a texture) changes the SSDF's cache
    /// entry, so the stale SSDF is not loaded.
    #[test]
    fn editing_the_buffer_file_misses_the_cache() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/objects");
        let dir = std::env::temp_dir().join(format!("inlay-ssdf-key-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for f in [
            "checker-cube.gltf",
            "checker-cube.bin",
            "checker.png",
            "checker-mr.png",
        ] {
            std::fs::copy(src.join(f), dir.join(f)).unwrap();
        }
        let gltf = dir.join("checker-cube.gltf");
        let files = gltf_files(&gltf).unwrap();
        assert_eq!(files.len(), 4, "{files:?}");
        let knobs = SsdfKnobs::default();
        let before = cache_entry(&gltf, &knobs).unwrap();
        let mut bin = std::fs::read(dir.join("checker-cube.bin")).unwrap();
        bin[0] ^= 1;
        std::fs::write(dir.join("checker-cube.bin"), &bin).unwrap();
        let after = cache_entry(&gltf, &knobs).unwrap();
        assert!(before.is_some());
        assert_ne!(before, after);
        std::fs::write(dir.join("checker.png"), b"edited").unwrap();
        assert_ne!(after, cache_entry(&gltf, &knobs).unwrap());
        std::fs::remove_file(dir.join("checker-cube.bin")).unwrap();
        let missing = cache_entry(&gltf, &knobs).unwrap_err();
        assert!(
            format!("{missing:#}").contains("checker-cube.bin"),
            "{missing:#}"
        );
    }
}
