//! Runs frame graphs: frames in flight (each with its command buffer, fence,
//! descriptor arena, timestamp queries and transient pool), submission, and
//! collection of each frame's timings once its fence has signalled — never a
//! device-wide wait per frame.

use std::sync::Arc;

use ash::vk;

use crate::context::Context;
use crate::descriptors::{DescriptorArena, Samplers};
use crate::error::{Result, VkContext};
use crate::graph::{record_graph, BufferBacking, FrameGraph, ImageBacking, Plan, Target};
use crate::graph::{RecordEnv, Resolved, ResolvedBuffer, ResolvedImage};
use crate::memory::{Buffer, Image};
use crate::timing::{FrameTimings, PassQueries, PassTiming};
use crate::transient_pool::{SlotResource, TransientPool};

/// Default number of frames the CPU may record ahead of the GPU.
pub const DEFAULT_FRAMES_IN_FLIGHT: usize = 2;

/// Semaphores a submission waits on and signals (swapchain acquire/present).
#[derive(Debug, Clone, Default)]
pub struct SubmitSync {
    pub(crate) wait: Vec<(vk::Semaphore, vk::PipelineStageFlags2)>,
    pub(crate) signal: Vec<vk::Semaphore>,
}

impl SubmitSync {
    /// No semaphores: an offscreen frame.
    pub fn none() -> Self {
        Self::default()
    }
}

/// The frame being prepared: which slot it uses and its number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameToken {
    /// Frame-in-flight slot index.
    pub slot: usize,
    /// Frame number (0-based).
    pub frame: u64,
}

struct InFlight {
    frame: u64,
    passes: Vec<(String, f64)>,
    culled: Vec<String>,
    skipped: Vec<crate::graph::SkippedPass>,
    // Keeps imported and transient resources alive until the GPU is done.
    _keep_images: Vec<Arc<Image>>,
    _keep_buffers: Vec<Arc<Buffer>>,
}

struct FrameSlot {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    descriptors: DescriptorArena,
    queries: PassQueries,
    transients: TransientPool,
    in_flight: Option<InFlight>,
}

/// What running one frame's graph did.
#[derive(Debug, Clone)]
pub struct FrameReport {
    /// The frame's number.
    pub frame: u64,
    /// Executed passes in order.
    pub executed: Vec<String>,
    /// Culled passes.
    pub culled: Vec<String>,
    /// Passes the builder skipped, with why.
    pub skipped: Vec<crate::graph::SkippedPass>,
}

/// Executes frame graphs with several frames in flight.
pub struct Renderer {
    ctx: Arc<Context>,
    slots: Vec<FrameSlot>,
    samplers: Samplers,
    next_frame: u64,
    begun: Option<FrameToken>,
    completed: Vec<FrameTimings>,
}

/// How many completed frames' timings are kept.
const KEPT_TIMINGS: usize = 256;

impl Renderer {
    /// A renderer with `frames_in_flight` (at least 1) frame slots.
    pub fn new(ctx: &Arc<Context>, frames_in_flight: usize) -> Result<Self> {
        let mut slots = Vec::new();
        for _ in 0..frames_in_flight.max(1) {
            let pool_info = vk::CommandPoolCreateInfo::default()
                .queue_family_index(ctx.queue_family)
                .flags(vk::CommandPoolCreateFlags::TRANSIENT);
            let pool = unsafe { ctx.device.create_command_pool(&pool_info, None) }
                .vk("vkCreateCommandPool")?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = unsafe { ctx.device.allocate_command_buffers(&alloc) }
                .vk("vkAllocateCommandBuffers")?[0];
            let fence = unsafe {
                ctx.device.create_fence(
                    &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                    None,
                )
            }
            .vk("vkCreateFence")?;
            slots.push(FrameSlot {
                pool,
                cmd,
                fence,
                descriptors: DescriptorArena::new(ctx),
                queries: PassQueries::new(ctx)?,
                transients: TransientPool::new(ctx),
                in_flight: None,
            });
        }
        Ok(Self {
            ctx: ctx.clone(),
            slots,
            samplers: Samplers::new(ctx)?,
            next_frame: 0,
            begun: None,
            completed: Vec::new(),
        })
    }

    /// The context this renderer draws with.
    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// Number of frame slots.
    pub fn frames_in_flight(&self) -> usize {
        self.slots.len()
    }

    /// Waits until the slot of the next frame is free (its previous frame,
    /// `frames_in_flight` frames ago, has finished), collects that frame's
    /// timings, and returns the token for the new frame.
    pub fn begin_frame(&mut self) -> Result<FrameToken> {
        if let Some(t) = self.begun {
            return Ok(t);
        }
        let frame = self.next_frame;
        let slot = (frame % self.slots.len() as u64) as usize;
        self.retire(slot)?;
        let token = FrameToken { slot, frame };
        self.begun = Some(token);
        Ok(token)
    }

    fn retire(&mut self, slot: usize) -> Result<()> {
        let s = &mut self.slots[slot];
        unsafe { self.ctx.device.wait_for_fences(&[s.fence], true, u64::MAX) }
            .vk("vkWaitForFences")?;
        if let Some(done) = s.in_flight.take() {
            let stamps = s.queries.read(done.passes.len() as u32)?;
            let passes: Vec<PassTiming> = done
                .passes
                .iter()
                .zip(&stamps)
                .map(|((name, cpu), (t0, t1))| PassTiming {
                    name: name.clone(),
                    start_ms: *t0,
                    gpu_ms: (t1 - t0).max(0.0),
                    cpu_ms: *cpu,
                })
                .collect();
            let gpu_total_ms = match (stamps.first(), stamps.last()) {
                (Some(a), Some(b)) => (b.1 - a.0).max(0.0),
                _ => 0.0,
            };
            if self.completed.len() == KEPT_TIMINGS {
                self.completed.remove(0);
            }
            self.completed.push(FrameTimings {
                frame: done.frame,
                passes,
                culled: done.culled,
                skipped: done.skipped,
                gpu_total_ms,
            });
        }
        s.descriptors.reset()?;
        Ok(())
    }

    /// Plans, records and submits `graph` as the frame begun with
    /// [`Self::begin_frame`] (begun implicitly if not).
    pub fn submit(&mut self, graph: FrameGraph, sync: &SubmitSync) -> Result<FrameReport> {
        let token = self.begin_frame()?;
        self.begun = None;
        self.next_frame += 1;
        let plan = Plan::new(&graph)?;
        let slot = &mut self.slots[token.slot];
        slot.queries.ensure_capacity(plan.order.len() as u32)?;
        let physical = slot.transients.acquire(&plan.slots, token.frame)?;
        let mut keep_images = Vec::new();
        let mut keep_buffers = Vec::new();
        let resolved = resolve(
            &graph,
            &plan,
            &physical,
            &mut keep_images,
            &mut keep_buffers,
        );
        let device = &self.ctx.device;
        unsafe {
            device
                .reset_command_pool(slot.pool, vk::CommandPoolResetFlags::empty())
                .vk("vkResetCommandPool")?;
            device
                .begin_command_buffer(
                    slot.cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
                .vk("vkBeginCommandBuffer")?;
        }
        // Carry the end states of imported engine-owned resources into the next frame.
        for &(id, state) in &plan.image_end_states {
            if let Some(ImageBacking::Owned(i)) = graph.images[id as usize]
                .import
                .as_ref()
                .map(|i| &i.backing)
            {
                i.set_sync_state(state);
            }
        }
        for &(id, state) in &plan.buffer_end_states {
            if let Some(BufferBacking::Owned(b)) = graph.buffers[id as usize]
                .import
                .as_ref()
                .map(|i| &i.backing)
            {
                b.set_sync_state(state);
            }
        }
        let env = RecordEnv {
            ctx: &self.ctx,
            cmd: slot.cmd,
            descriptors: &mut slot.descriptors,
            samplers: &self.samplers,
            queries: &slot.queries,
        };
        let recorded = record_graph(env, graph, &plan, &resolved);
        unsafe { device.end_command_buffer(slot.cmd) }.vk("vkEndCommandBuffer")?;
        let recorded = recorded?;
        let waits: Vec<vk::SemaphoreSubmitInfo> = sync
            .wait
            .iter()
            .map(|&(s, stage)| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(s)
                    .stage_mask(stage)
            })
            .collect();
        let signals: Vec<vk::SemaphoreSubmitInfo> = sync
            .signal
            .iter()
            .map(|&s| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(s)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            })
            .collect();
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        unsafe {
            device.reset_fences(&[slot.fence]).vk("vkResetFences")?;
            let _queue = self.ctx.lock_queue();
            device
                .queue_submit2(self.ctx.queue, &submit, slot.fence)
                .vk("vkQueueSubmit2")?;
        }
        let executed = recorded.passes.iter().map(|(n, _)| n.clone()).collect();
        let culled = recorded.culled.clone();
        let skipped = recorded.skipped.clone();
        slot.in_flight = Some(InFlight {
            frame: token.frame,
            passes: recorded.passes,
            culled: recorded.culled,
            skipped: recorded.skipped.clone(),
            _keep_images: keep_images,
            _keep_buffers: keep_buffers,
        });
        Ok(FrameReport {
            frame: token.frame,
            executed,
            culled,
            skipped,
        })
    }

    /// Waits for every submitted frame and collects their timings (for the
    /// end of a run, a readback, or a resize; not per frame).
    pub fn finish(&mut self) -> Result<()> {
        let n = self.slots.len() as u64;
        for k in 0..n {
            // Retire in submission order so timings stay ordered.
            let slot = ((self.next_frame + k) % n) as usize;
            self.retire(slot)?;
        }
        Ok(())
    }

    /// Timings of completed frames, oldest first (the last few hundred).
    pub fn timings(&self) -> &[FrameTimings] {
        &self.completed
    }

    /// The most recent completed frame's timings.
    pub fn latest_timings(&self) -> Option<&FrameTimings> {
        self.completed.last()
    }

    /// Transient resources created so far across slots (reuse shows as a
    /// count that stops growing).
    pub fn transients_created(&self) -> u64 {
        self.slots.iter().map(|s| s.transients.created()).sum()
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        unsafe {
            let fences: Vec<vk::Fence> = self.slots.iter().map(|s| s.fence).collect();
            let _ = self.ctx.device.wait_for_fences(&fences, true, u64::MAX);
            for s in &self.slots {
                self.ctx.device.destroy_fence(s.fence, None);
                self.ctx.device.destroy_command_pool(s.pool, None);
            }
        }
    }
}

fn resolve(
    graph: &FrameGraph,
    plan: &Plan,
    physical: &[SlotResource],
    keep_images: &mut Vec<Arc<Image>>,
    keep_buffers: &mut Vec<Arc<Buffer>>,
) -> Resolved {
    let images = plan
        .image_targets
        .iter()
        .enumerate()
        .map(|(id, t)| {
            let decl = &graph.images[id];
            match t {
                None => None,
                Some(Target::Transient(s)) => match &physical[*s] {
                    SlotResource::Image(i) => {
                        keep_images.push(i.clone());
                        Some(ResolvedImage {
                            image: i.raw,
                            view: i.view,
                            desc: decl.desc,
                        })
                    }
                    SlotResource::Buffer(_) => None,
                },
                Some(Target::Imported(_)) => match decl.import.as_ref().map(|i| &i.backing) {
                    Some(ImageBacking::Owned(i)) => {
                        keep_images.push(i.clone());
                        Some(ResolvedImage {
                            image: i.raw,
                            view: i.view,
                            desc: decl.desc,
                        })
                    }
                    Some(ImageBacking::External { image, view }) => Some(ResolvedImage {
                        image: *image,
                        view: *view,
                        desc: decl.desc,
                    }),
                    None => None,
                },
            }
        })
        .collect();
    let buffers = plan
        .buffer_targets
        .iter()
        .enumerate()
        .map(|(id, t)| {
            let decl = &graph.buffers[id];
            match t {
                None => None,
                Some(Target::Transient(s)) => match &physical[*s] {
                    SlotResource::Buffer(b) => {
                        keep_buffers.push(b.clone());
                        Some(ResolvedBuffer {
                            buffer: b.raw,
                            size: decl.size,
                        })
                    }
                    SlotResource::Image(_) => None,
                },
                Some(Target::Imported(_)) => match decl.import.as_ref().map(|i| &i.backing) {
                    Some(BufferBacking::Owned(b)) => {
                        keep_buffers.push(b.clone());
                        Some(ResolvedBuffer {
                            buffer: b.raw,
                            size: decl.size,
                        })
                    }
                    Some(BufferBacking::External(b)) => Some(ResolvedBuffer {
                        buffer: *b,
                        size: decl.size,
                    }),
                    None => None,
                },
            }
        })
        .collect();
    Resolved { images, buffers }
}
