//! One-off uploads: device-local buffers and images filled from the CPU
//! through a staging buffer, for data that lives across frames (fields,
//! tables, probes of known content).

use std::sync::Arc;

use ash::vk;

use crate::error::EngineError;
use crate::error::{Result, VkContext};
use crate::graph::SyncState;
use crate::memory::{Buffer, BufferLocation, Image};
use crate::Context;

impl Buffer {
    /// Creates a device-local buffer holding `bytes`, for `usage` (transfer
    /// destination is added). Copies through a staging buffer in a one-time
    /// submission and waits for it, so the buffer is ready for any later
    /// frame; the graph sees it as untouched.
    pub fn with_data(
        ctx: &Arc<Context>,
        name: &str,
        bytes: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        let size = bytes.len() as u64;
        let dst = Buffer::new(
            ctx,
            name,
            size,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            BufferLocation::Gpu,
        )?;
        if bytes.is_empty() {
            return Ok(dst);
        }
        let staging = staging_buffer(ctx, &format!("{name} (staging)"), bytes)?;
        submit_once(ctx, |device, cmd| unsafe {
            let region = vk::BufferCopy::default().size(size);
            device.cmd_copy_buffer(cmd, staging.raw, dst.raw, &[region]);
            // Make the copy visible to whatever reads the buffer next.
            let barrier = vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE);
            let dep = vk::DependencyInfo::default().memory_barriers(std::slice::from_ref(&barrier));
            device.cmd_pipeline_barrier2(cmd, &dep);
        })?;
        dst.set_sync_state(SyncState::FRESH);
        Ok(dst)
    }
}

impl Image {
    /// Replaces the whole content of an RGBA32F image (created with
    /// transfer-destination usage) with `pixels`; see [`Image::write_texels`].
    pub fn write_rgba32f(&self, pixels: &[[f32; 4]]) -> Result<()> {
        let desc = self.desc();
        if desc.format != vk::Format::R32G32B32A32_SFLOAT {
            return Err(EngineError::Pass {
                pass: "upload".into(),
                message: format!(
                    "write_rgba32f needs an RGBA32F image, got {:?}",
                    desc.format
                ),
            });
        }
        let bytes: Vec<u8> = pixels
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        self.write_texels(&bytes)
    }

    /// Replaces the whole content of an image (created with
    /// transfer-destination usage) with tightly packed texels, row by row,
    /// through a staging buffer in a one-time submission; waits for it. The
    /// image is left in GENERAL layout with the copy visible to any later
    /// access.
    pub fn write_texels(&self, bytes: &[u8]) -> Result<()> {
        let desc = self.desc();
        let n = desc.width as usize * desc.height as usize;
        let texel = crate::graph::texel_bytes(desc.format);
        if texel.is_none_or(|t| bytes.len() != n * t as usize) {
            return Err(EngineError::Pass {
                pass: "upload".into(),
                message: format!(
                    "write_texels: {} bytes do not fill a {}x{} {:?} image",
                    bytes.len(),
                    desc.width,
                    desc.height,
                    desc.format
                ),
            });
        }
        let ctx = &self.ctx;
        let staging = staging_buffer(ctx, "image upload (staging)", bytes)?;
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        submit_once(ctx, |device, cmd| unsafe {
            let to_dst = vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::COPY)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .image(self.raw)
                .subresource_range(range);
            let dep =
                vk::DependencyInfo::default().image_memory_barriers(std::slice::from_ref(&to_dst));
            device.cmd_pipeline_barrier2(cmd, &dep);
            let region = vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .layer_count(1),
                )
                .image_extent(vk::Extent3D {
                    width: desc.width,
                    height: desc.height,
                    depth: 1,
                });
            device.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                self.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            );
            let to_general = vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
                .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .new_layout(vk::ImageLayout::GENERAL)
                .image(self.raw)
                .subresource_range(range);
            let dep = vk::DependencyInfo::default()
                .image_memory_barriers(std::slice::from_ref(&to_general));
            device.cmd_pipeline_barrier2(cmd, &dep);
        })?;
        self.set_sync_state(SyncState {
            stage: vk::PipelineStageFlags2::NONE,
            access: vk::AccessFlags2::NONE,
            layout: vk::ImageLayout::GENERAL,
        });
        Ok(())
    }
}

/// A host-visible transfer source holding `bytes`.
fn staging_buffer(ctx: &Arc<Context>, name: &str, bytes: &[u8]) -> Result<Buffer> {
    Buffer::host_with_data(ctx, name, bytes, vk::BufferUsageFlags::TRANSFER_SRC)
}

/// Records `record` into a fresh command buffer, submits it and waits.
fn submit_once(
    ctx: &Arc<Context>,
    record: impl FnOnce(&ash::Device, vk::CommandBuffer),
) -> Result<()> {
    let device = &ctx.device;
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(ctx.queue_family)
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    let pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
    let result = (|| -> Result<()> {
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd =
            unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe { device.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        record(device, cmd);
        unsafe { device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .vk("vkCreateFence")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        let submitted = {
            let _queue = ctx.lock_queue();
            unsafe { device.queue_submit2(ctx.queue, &submit, fence) }.vk("vkQueueSubmit2")
        };
        let waited = submitted.and_then(|_| {
            unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")
        });
        unsafe { device.destroy_fence(fence, None) };
        waited
    })();
    unsafe { device.destroy_command_pool(pool, None) };
    result
}
