//! The set of WGSL files shaders are composed from, embedded in the binary or
//! read from a directory (for editing shaders without rebuilding).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use super::compose::Define;
use super::pipeline_cache::PipelineCache;
use crate::context::Context;
use crate::error::{EngineError, Result};
use crate::pipeline::ComputePipeline;

/// WGSL source files by path relative to the library root (`common/x.wgsl`),
/// the compute pipelines compiled from them that are still in use (shared
/// by the library's clones until one of them changes a file), and defines
/// every pipeline of this library gets ([`Self::with_defines`]).
#[derive(Debug, Clone, Default)]
pub struct ShaderLibrary {
    files: BTreeMap<String, String>,
    pipelines: Arc<PipelineCache>,
    defines: Vec<Define>,
}

impl ShaderLibrary {
    /// A library from `(path, source)` pairs, e.g. embedded with `include_str!`.
    pub fn from_pairs<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> Self {
        Self {
            files: pairs
                .into_iter()
                .map(|(p, s)| (p.to_owned(), s.to_owned()))
                .collect(),
            pipelines: Arc::default(),
            defines: Vec::new(),
        }
    }

    /// The same library (its files and pipeline cache shared) with
    /// `defines` given to every pipeline it compiles, replacing its own of
    /// the same names; a pipeline's own defines replace these in turn. For
    /// a constant that depends on data every pass of a frame shares (so a
    /// shader can leave out code that data never needs).
    pub fn with_defines(&self, defines: &[Define]) -> Self {
        let mut out = self.clone();
        out.defines
            .retain(|d| defines.iter().all(|n| n.name() != d.name()));
        out.defines.extend_from_slice(defines);
        out
    }

    /// The library's own define of `name`, if any.
    pub fn define(&self, name: &str) -> Option<&Define> {
        self.defines.iter().find(|d| d.name() == name)
    }

    /// Every `.wgsl` file below `root`, keyed by its path relative to `root`.
    pub fn from_dir(root: &Path) -> Result<Self> {
        let mut files = BTreeMap::new();
        let mut stack = vec![root.to_path_buf()];
        while let Some(dir) = stack.pop() {
            let entries = std::fs::read_dir(&dir).map_err(|e| EngineError::File {
                path: dir.display().to_string(),
                message: e.to_string(),
            })?;
            for entry in entries {
                let path = entry
                    .map_err(|e| EngineError::File {
                        path: dir.display().to_string(),
                        message: e.to_string(),
                    })?
                    .path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "wgsl") {
                    let text = std::fs::read_to_string(&path).map_err(|e| EngineError::File {
                        path: path.display().to_string(),
                        message: e.to_string(),
                    })?;
                    let key = path
                        .strip_prefix(root)
                        .unwrap_or(&path)
                        .to_string_lossy()
                        .replace('\\', "/");
                    files.insert(key, text);
                }
            }
        }
        Ok(Self {
            files,
            pipelines: Arc::default(),
            defines: Vec::new(),
        })
    }

    /// Adds or replaces one file (and forgets the pipelines compiled so
    /// far: they may include it).
    pub fn insert(&mut self, path: &str, source: &str) {
        self.files.insert(path.to_owned(), source.to_owned());
        self.pipelines = Arc::default();
    }

    /// The compute pipeline of `entry` in `file` with the library's defines
    /// and `defines` on `ctx`'s device: compiled on first use, the same
    /// pipeline for every later request with the same key (device, file,
    /// entry point, defines) as long as someone still holds it (the library
    /// does not keep a device alive).
    pub fn compute_pipeline(
        &self,
        ctx: &Arc<Context>,
        file: &str,
        entry: &str,
        defines: &[Define],
    ) -> Result<Arc<ComputePipeline>> {
        let all = self.merged_defines(defines);
        self.pipelines.compute(self, ctx, file, entry, &all)
    }

    /// The library's defines that `defines` do not name, then `defines`:
    /// what a shader of this library is compiled with.
    pub fn merged_defines(&self, defines: &[Define]) -> Vec<Define> {
        let mut all: Vec<Define> = self
            .defines
            .iter()
            .filter(|d| defines.iter().all(|n| n.name() != d.name()))
            .cloned()
            .collect();
        all.extend_from_slice(defines);
        all
    }

    /// How many compute pipelines [`Self::compute_pipeline`] has compiled
    /// (requests it could not answer from the ones it had).
    pub fn compiled_pipelines(&self) -> usize {
        self.pipelines.compiled()
    }

    /// The source of one file.
    pub fn get(&self, path: &str) -> Option<&str> {
        self.files.get(path).map(String::as_str)
    }

    /// All file paths, sorted.
    pub fn paths(&self) -> impl Iterator<Item = &str> {
        self.files.keys().map(String::as_str)
    }
}
