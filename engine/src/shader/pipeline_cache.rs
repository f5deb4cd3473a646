//! Compute pipelines shared by every pass that asks for the same kernel:
//! keyed by device, file, entry point and defines, compiled on first use
//! (naga to SPIR-V, then the driver's own compile, the slow part on
//! lavapipe), then handed out again. Sixty-four objects each with its own
//! probe and fit passes share one copy of each kernel.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use ash::vk::Handle;

use super::compile::{compile, ShaderStage};
use super::compose::Define;
use super::library::ShaderLibrary;
use crate::context::Context;
use crate::error::Result;
use crate::pipeline::ComputePipeline;

/// What makes two requests the same pipeline.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct PipelineKey {
    device: u64,
    file: String,
    entry: String,
    defines: String,
}

/// The pipelines compiled so far.
#[derive(Default)]
pub(crate) struct PipelineCache {
    compute: Mutex<HashMap<PipelineKey, Arc<ComputePipeline>>>,
    compiled: AtomicUsize,
}

impl std::fmt::Debug for PipelineCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PipelineCache")
            .field("compiled", &self.compiled.load(Ordering::Relaxed))
            .finish()
    }
}

impl PipelineCache {
    /// The pipeline for `entry` of `file` with `defines`, from `library`.
    pub(crate) fn compute(
        &self,
        library: &ShaderLibrary,
        ctx: &Arc<Context>,
        file: &str,
        entry: &str,
        defines: &[Define],
    ) -> Result<Arc<ComputePipeline>> {
        let key = PipelineKey {
            device: ctx.device.handle().as_raw(),
            file: file.to_owned(),
            entry: entry.to_owned(),
            defines: format!("{defines:?}"),
        };
        // A poisoned lock only means another thread panicked while
        // compiling: the map itself is whole.
        let mut map = self.compute.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(p) = map.get(&key) {
            return Ok(p.clone());
        }
        let shader = compile(library, file, entry, ShaderStage::Compute, defines)?;
        let pipeline = Arc::new(ComputePipeline::new(ctx, &shader)?);
        self.compiled.fetch_add(1, Ordering::Relaxed);
        map.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    /// How many pipelines were compiled (requests the cache could not
    /// answer).
    pub(crate) fn compiled(&self) -> usize {
        self.compiled.load(Ordering::Relaxed)
    }
}
