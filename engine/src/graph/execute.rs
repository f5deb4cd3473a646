//! Recording a planned graph: barriers from the plan, dynamic rendering for
//! raster passes, timestamps around each pass (its barriers included), and each pass's callback
//! run through its [`PassContext`].

use std::time::Instant;

use ash::vk;

use super::builder::{FrameGraph, PassDecl};
use super::context::{PassContext, PassView, Resolved};
use super::plan::{Barrier, BarrierResource, Plan};
use super::{ImageAccess, LoadOp, PassKind};
use crate::context::Context;
use crate::descriptors::{DescriptorArena, Samplers};
use crate::error::Result;
use crate::memory::whole;
use crate::timing::PassQueries;

/// What recording produced: the executed pass names with their CPU time.
pub(crate) struct RecordOutput {
    pub passes: Vec<(String, f64)>,
    pub culled: Vec<String>,
    pub skipped: Vec<super::SkippedPass>,
}

fn record_barriers(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    graph: &FrameGraph,
    resolved: &Resolved,
    barriers: &[Barrier],
) {
    if barriers.is_empty() {
        return;
    }
    let mut images = Vec::new();
    let mut buffers = Vec::new();
    for b in barriers {
        match b.resource {
            BarrierResource::Image(id) => {
                let Some(r) = resolved.images[id as usize] else {
                    continue;
                };
                images.push(
                    vk::ImageMemoryBarrier2::default()
                        .src_stage_mask(b.src_stage)
                        .src_access_mask(b.src_access)
                        .dst_stage_mask(b.dst_stage)
                        .dst_access_mask(b.dst_access)
                        .old_layout(b.old_layout)
                        .new_layout(b.new_layout)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .image(r.image)
                        .subresource_range(
                            whole(r.desc.format).aspect_mask(Plan::aspect(graph, id)),
                        ),
                );
            }
            BarrierResource::Buffer(id) => {
                let Some(r) = resolved.buffers[id as usize] else {
                    continue;
                };
                buffers.push(
                    vk::BufferMemoryBarrier2::default()
                        .src_stage_mask(b.src_stage)
                        .src_access_mask(b.src_access)
                        .dst_stage_mask(b.dst_stage)
                        .dst_access_mask(b.dst_access)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .buffer(r.buffer)
                        .size(vk::WHOLE_SIZE),
                );
            }
        }
    }
    let info = vk::DependencyInfo::default()
        .image_memory_barriers(&images)
        .buffer_memory_barriers(&buffers);
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &info) };
}

fn begin_rendering(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    pass: &PassDecl,
    resolved: &Resolved,
) -> vk::Extent2D {
    let mut extent = vk::Extent2D::default();
    let mut colors = Vec::new();
    let mut depth = None;
    for u in &pass.images {
        let Some(r) = resolved.images[u.id as usize] else {
            continue;
        };
        let view = |layout| {
            vk::RenderingAttachmentInfo::default()
                .image_view(r.view)
                .image_layout(layout)
                .store_op(vk::AttachmentStoreOp::STORE)
        };
        match u.access {
            ImageAccess::ColorAttachment(load) => {
                extent = vk::Extent2D {
                    width: r.desc.width,
                    height: r.desc.height,
                };
                let (op, clear) = match load {
                    LoadOp::Clear(c) => (
                        vk::AttachmentLoadOp::CLEAR,
                        vk::ClearValue {
                            color: vk::ClearColorValue { float32: c },
                        },
                    ),
                    LoadOp::Load => (vk::AttachmentLoadOp::LOAD, vk::ClearValue::default()),
                    LoadOp::DontCare => {
                        (vk::AttachmentLoadOp::DONT_CARE, vk::ClearValue::default())
                    }
                };
                colors.push(
                    view(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                        .load_op(op)
                        .clear_value(clear),
                );
            }
            ImageAccess::DepthAttachment(load) => {
                extent = vk::Extent2D {
                    width: r.desc.width,
                    height: r.desc.height,
                };
                let (op, clear) = match load {
                    LoadOp::Clear(d) => (
                        vk::AttachmentLoadOp::CLEAR,
                        vk::ClearValue {
                            depth_stencil: vk::ClearDepthStencilValue {
                                depth: d,
                                stencil: 0,
                            },
                        },
                    ),
                    LoadOp::Load => (vk::AttachmentLoadOp::LOAD, vk::ClearValue::default()),
                    LoadOp::DontCare => {
                        (vk::AttachmentLoadOp::DONT_CARE, vk::ClearValue::default())
                    }
                };
                depth = Some(
                    view(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
                        .load_op(op)
                        .clear_value(clear),
                );
            }
            _ => {}
        }
    }
    let area = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent,
    };
    let mut info = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(&colors);
    if let Some(d) = depth.as_ref() {
        info = info.depth_attachment(d);
    }
    unsafe {
        ctx.device.cmd_begin_rendering(cmd, &info);
        // Negative-height viewport is not used: naga's ADJUST_COORDINATE_SPACE
        // already flips WGSL's Y-up clip space for Vulkan.
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        ctx.device.cmd_set_viewport(cmd, 0, &[viewport]);
        ctx.device.cmd_set_scissor(cmd, 0, &[area]);
    }
    extent
}

/// Everything recording needs besides the graph.
pub(crate) struct RecordEnv<'r> {
    pub ctx: &'r Context,
    pub cmd: vk::CommandBuffer,
    pub descriptors: &'r mut DescriptorArena,
    pub samplers: &'r Samplers,
    pub queries: &'r PassQueries,
}

/// Records every live pass of `graph` in plan order, with the plan's
/// barriers before each and timestamps around each (the start before the
/// barriers).
pub(crate) fn record_graph(
    env: RecordEnv<'_>,
    mut graph: FrameGraph,
    plan: &Plan,
    resolved: &Resolved,
) -> Result<RecordOutput> {
    let RecordEnv {
        ctx,
        cmd,
        descriptors,
        samplers,
        queries,
    } = env;
    queries.reset(cmd, plan.order.len() as u32);
    let mut passes = Vec::with_capacity(plan.order.len());
    let mut callbacks: Vec<_> = graph.passes.iter_mut().map(|p| p.exec.take()).collect();
    for (slot, (&p, barriers)) in plan.order.iter().zip(&plan.barriers).enumerate() {
        let started = Instant::now();
        // The start timestamp goes before the pass's barriers, so a pass's
        // time includes its wait for what it depends on and the passes tile
        // the frame. Written after them, lavapipe stamped it late: a warm
        // probe trace (4 workgroups) read 0.05 ms and its 26 ms showed
        // up nowhere but in the wall clock (docs/benchmarks.md, issue 26's
        // sixth pass).
        queries.write(cmd, slot as u32, false);
        record_barriers(ctx, cmd, &graph, resolved, barriers);
        let decl = &graph.passes[p];
        let extent = if decl.kind == PassKind::Raster {
            begin_rendering(ctx, cmd, decl, resolved)
        } else {
            vk::Extent2D::default()
        };
        if let Some(f) = callbacks[p].take() {
            let mut pc = PassContext {
                ctx,
                cmd,
                pass: PassView {
                    name: &decl.name,
                    kind: decl.kind,
                    images: &decl.images,
                    buffers: &decl.buffers,
                },
                resolved,
                descriptors,
                samplers,
                extent,
                dispatches: 0,
            };
            f(&mut pc)?;
        }
        if decl.kind == PassKind::Raster {
            unsafe { ctx.device.cmd_end_rendering(cmd) };
        }
        queries.write(cmd, slot as u32, true);
        passes.push((decl.name.clone(), started.elapsed().as_secs_f64() * 1e3));
    }
    record_barriers(ctx, cmd, &graph, resolved, &plan.final_barriers);
    let culled = plan
        .culled
        .iter()
        .map(|&p| graph.passes[p].name.clone())
        .collect();
    Ok(RecordOutput {
        passes,
        culled,
        skipped: graph.skipped.clone(),
    })
}
