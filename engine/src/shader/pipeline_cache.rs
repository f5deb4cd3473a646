//! Compute pipelines shared by every pass that asks for the same kernel:
//! keyed by device, file, entry point and defines, compiled on first use
//! (naga to SPIR-V, then the driver's own compile, the slow part on
//! lavapipe), then handed out again while any pass still holds it.
//! Sixty-four objects each with its own probe and fit passes share one
//! copy of each kernel. The cache holds its pipelines weakly: it never
//! keeps a device alive after the passes that used it are gone (a window
//! must outlive every Vulkan object made for it).

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, Weak};

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
    compute: Mutex<HashMap<PipelineKey, Weak<ComputePipeline>>>,
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
        if let Some(p) = self.lookup(&key) {
            return Ok(p);
        }
        // Compiled without the lock: other kernels stay available
        // meanwhile. Two threads asking for the same new kernel at once
        // both compile it, and the first one stored is kept.
        let shader = compile(library, file, entry, ShaderStage::Compute, defines)?;
        let pipeline = Arc::new(ComputePipeline::new(ctx, &shader)?.with_defines(defines));
        self.compiled.fetch_add(1, Ordering::Relaxed);
        let mut map = self.lock();
        if let Some(p) = map.get(&key).and_then(Weak::upgrade) {
            return Ok(p);
        }
        map.retain(|_, p| p.strong_count() > 0);
        map.insert(key, Arc::downgrade(&pipeline));
        Ok(pipeline)
    }

    fn lookup(&self, key: &PipelineKey) -> Option<Arc<ComputePipeline>> {
        self.lock().get(key).and_then(Weak::upgrade)
    }

    /// The map; a poisoned lock only means another thread panicked while
    /// using it, and the map itself is whole.
    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<PipelineKey, Weak<ComputePipeline>>> {
        self.compute.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// How many pipelines were compiled (requests the cache could not
    /// answer).
    pub(crate) fn compiled(&self) -> usize {
        self.compiled.load(Ordering::Relaxed)
    }
}
