//! A command's output files: their paths checked before any work, their
//! contents staged while the command runs, and all of them put in place
//! together at the end, after the validation layer (when on) has had its
//! say. A command that fails, is interrupted or trips the validation layer
//! leaves every earlier output as it was (see `inlay_engine::output`).

use std::path::{Path, PathBuf};

use inlay_engine::output::{check_output_path, OutputBatch};
use inlay_engine::{Context, HdrImage};

/// Checks before any work that the path given to `flag` can take an output
/// with one of `extensions` (empty: any); the error names the flag, the
/// path and what to change.
pub fn check_output(flag: &str, path: &Path, extensions: &[&str]) -> anyhow::Result<()> {
    check_output_path(path, extensions).map_err(|e| anyhow::anyhow!("{flag}: {e}"))
}

/// [`check_output`] for an image (`.exr` or `.png`).
pub fn check_image_output(flag: &str, path: &Path) -> anyhow::Result<()> {
    HdrImage::check_output(path).map_err(|e| anyhow::anyhow!("{flag}: {e}"))
}

/// A command's outputs, staged until [`Outputs::commit`].
#[derive(Debug, Default)]
pub struct Outputs {
    batch: OutputBatch,
}

impl Outputs {
    /// No outputs yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Stages an image (`.exr` linear, `.png` tonemapped with `exposure`).
    pub fn image(&mut self, path: &Path, image: &HdrImage, exposure: f32) -> anyhow::Result<()> {
        Ok(self
            .batch
            .write_with(path, |temp| image.write_file(temp, exposure))?)
    }

    /// Stages a file's bytes.
    pub fn bytes(&mut self, path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
        Ok(self.batch.write_bytes(path, bytes)?)
    }

    /// Stages a JSON document, pretty-printed.
    pub fn json(&mut self, path: &Path, value: &serde_json::Value) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(value)?;
        self.bytes(path, text.as_bytes())
    }

    /// Puts every staged output in place and prints `wrote PATH` for each;
    /// first, with `ctx` given, fails if the validation layer reported an
    /// error (then nothing is replaced).
    pub fn commit(self, ctx: Option<&Context>) -> anyhow::Result<Vec<PathBuf>> {
        if let Some(ctx) = ctx {
            ctx.check_validation()?;
        }
        let written = self.batch.commit()?;
        for p in &written {
            println!("wrote {}", p.display());
        }
        Ok(written)
    }
}
