//! GPU timestamps around every pass, read back without stalling (a frame
//! slot's queries are read when the slot is reused, frames later), and the
//! per-pass timing data exposed to the profiler and the window overlay.

use std::sync::Arc;

use ash::vk;

use crate::context::Context;
use crate::error::{Result, VkContext};

/// Passes a frame slot's query pool times before it grows (it grows to
/// fit any frame's graph, so no graph is refused for its size).
pub const INITIAL_TIMED_PASSES: u32 = 128;

/// One pass's cost in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PassTiming {
    /// The pass name.
    pub name: String,
    /// When the pass started on the GPU, in milliseconds after the frame's
    /// first pass started (for traces).
    pub start_ms: f64,
    /// GPU time between the timestamps around the pass, in milliseconds.
    pub gpu_ms: f64,
    /// CPU time spent recording the pass (barriers and commands), in milliseconds.
    pub cpu_ms: f64,
}

/// The timings of one completed frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrameTimings {
    /// The frame's number (0 = first frame rendered).
    pub frame: u64,
    /// Executed passes in execution order.
    pub passes: Vec<PassTiming>,
    /// Passes declared but culled (nothing consumed their output).
    pub culled: Vec<String>,
    /// Passes the builder did not add because the frame did not need them.
    pub skipped: Vec<crate::graph::SkippedPass>,
    /// GPU time from the first pass's start to the last pass's end, ms.
    pub gpu_total_ms: f64,
}

impl FrameTimings {
    /// GPU milliseconds of the named pass, if it ran.
    pub fn gpu_ms(&self, pass: &str) -> Option<f64> {
        self.passes
            .iter()
            .find(|p| p.name == pass)
            .map(|p| p.gpu_ms)
    }
}

/// A timestamp query pool for one frame slot: query 2i is pass i's start,
/// 2i + 1 its end.
pub(crate) struct PassQueries {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    /// Passes the pool has queries for.
    capacity: u32,
    valid_mask: u64,
}

fn create_pool(ctx: &Context, passes: u32) -> Result<vk::QueryPool> {
    let info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::TIMESTAMP)
        .query_count(2 * passes);
    // SAFETY: a valid create info on the context's live device.
    unsafe { ctx.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")
}

impl PassQueries {
    pub(crate) fn new(ctx: &Arc<Context>) -> Result<Self> {
        let capacity = INITIAL_TIMED_PASSES;
        let pool = create_pool(ctx, capacity)?;
        let bits = unsafe {
            ctx.instance
                .get_physical_device_queue_family_properties(ctx.physical)
        }
        .get(ctx.queue_family as usize)
        .map(|f| f.timestamp_valid_bits)
        .unwrap_or(64);
        let valid_mask = if bits >= 64 {
            u64::MAX
        } else {
            (1u64 << bits) - 1
        };
        Ok(Self {
            ctx: ctx.clone(),
            pool,
            capacity,
            valid_mask,
        })
    }

    /// Makes room for a frame of `passes` passes, replacing the pool with a
    /// larger one when needed. Call only while the slot is idle (its fence
    /// waited on and its last frame's timestamps read).
    pub(crate) fn ensure_capacity(&mut self, passes: u32) -> Result<()> {
        if passes <= self.capacity {
            return Ok(());
        }
        let capacity = passes.next_power_of_two();
        let pool = create_pool(&self.ctx, capacity)?;
        // SAFETY: the slot is idle, so no command buffer uses the old pool.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
        self.pool = pool;
        self.capacity = capacity;
        Ok(())
    }

    /// Resets the queries the frame will write (recorded in the frame's command buffer).
    pub(crate) fn reset(&self, cmd: vk::CommandBuffer, passes: u32) {
        unsafe {
            self.ctx.device.cmd_reset_query_pool(
                cmd,
                self.pool,
                0,
                2 * passes.clamp(1, self.capacity),
            )
        };
    }

    /// Writes pass `index`'s start (`end = false`) or end timestamp once all
    /// earlier commands have completed.
    pub(crate) fn write(&self, cmd: vk::CommandBuffer, index: u32, end: bool) {
        if index < self.capacity {
            unsafe {
                self.ctx.device.cmd_write_timestamp2(
                    cmd,
                    vk::PipelineStageFlags2::ALL_COMMANDS,
                    self.pool,
                    2 * index + end as u32,
                )
            };
        }
    }

    /// Reads the timestamps of `passes` passes; call only after the frame's
    /// fence has signalled (never waits). Returns (start, end) in ms.
    pub(crate) fn read(&self, passes: u32) -> Result<Vec<(f64, f64)>> {
        let n = passes.min(self.capacity);
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut raw = vec![0u64; 2 * n as usize];
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let period = self.ctx.info().timestamp_period_ns;
        let origin = raw[0] & self.valid_mask;
        let ms = |t: u64| ((t & self.valid_mask).wrapping_sub(origin)) as f64 * period * 1e-6;
        Ok(raw.chunks(2).map(|c| (ms(c[0]), ms(c[1]))).collect())
    }
}

impl Drop for PassQueries {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
