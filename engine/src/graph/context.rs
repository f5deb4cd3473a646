//! The safe [`PassContext`] through which a pass's callback binds the
//! resources it declared and records its work, and the physical resources
//! the logical ones resolve to this frame.

use ash::vk;

use super::decl::{BufferUse, ImageUse};
use super::{BufferAccess, BufferHandle, ImageAccess, ImageHandle, PassKind};
use crate::context::Context;
use crate::descriptors::{DescriptorArena, Samplers};
use crate::error::{EngineError, Result};
use crate::memory::{whole, ImageDesc};
use crate::pipeline::{descriptor_type, ComputePipeline, GraphicsPipeline, PipelineCore};
use crate::shader::DescriptorKind;

/// Which shared sampler to bind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SamplerKind {
    /// Bilinear, clamped to the edge.
    LinearClamp,
    /// Nearest texel, clamped to the edge.
    NearestClamp,
    /// Bilinear, repeating outside [0, 1] (tiled textures).
    LinearRepeat,
}

/// A resource bound to one binding of a pipeline, in binding order.
#[derive(Debug, Clone, Copy)]
pub enum Binding {
    /// `texture_2d` (the pass must declare `ImageAccess::Sampled`).
    SampledImage(ImageHandle),
    /// `texture_storage_2d` (the pass must declare a storage access).
    StorageImage(ImageHandle),
    /// `var<storage>` (the pass must declare a storage access).
    StorageBuffer(BufferHandle),
    /// `var<uniform>` (the pass must declare `BufferAccess::Uniform`).
    UniformBuffer(BufferHandle),
    /// `sampler`.
    Sampler(SamplerKind),
}

/// A physical image a logical one resolves to this frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ResolvedImage {
    pub image: vk::Image,
    pub view: vk::ImageView,
    pub desc: ImageDesc,
}

/// A physical buffer a logical one resolves to this frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ResolvedBuffer {
    pub buffer: vk::Buffer,
    pub size: u64,
}

/// Physical resources of every logical one (None: not used by a live pass).
pub(crate) struct Resolved {
    pub images: Vec<Option<ResolvedImage>>,
    pub buffers: Vec<Option<ResolvedBuffer>>,
}

/// What a pass's callback may touch: its name, kind and declared uses.
#[derive(Clone, Copy)]
pub(crate) struct PassView<'r> {
    pub name: &'r str,
    pub kind: PassKind,
    pub images: &'r [ImageUse],
    pub buffers: &'r [BufferUse],
}

/// What a pass's callback records through: resolved resources, descriptor
/// sets and commands, checked against the accesses the pass declared.
pub struct PassContext<'r> {
    pub(crate) ctx: &'r Context,
    pub(crate) cmd: vk::CommandBuffer,
    pub(crate) pass: PassView<'r>,
    pub(crate) resolved: &'r Resolved,
    pub(crate) descriptors: &'r mut DescriptorArena,
    pub(crate) samplers: &'r Samplers,
    pub(crate) extent: vk::Extent2D,
    pub(crate) dispatches: u32,
}

impl PassContext<'_> {
    fn error(&self, message: String) -> EngineError {
        EngineError::Pass {
            pass: self.pass.name.to_string(),
            message,
        }
    }

    /// The size of a raster pass's attachments (zero for other passes).
    pub fn extent(&self) -> (u32, u32) {
        (self.extent.width, self.extent.height)
    }

    /// The physical image behind a handle, checking the pass declared it.
    fn image(
        &self,
        h: ImageHandle,
        ok: impl Fn(ImageAccess) -> bool,
        what: &str,
    ) -> Result<ResolvedImage> {
        let declared = self
            .pass
            .images
            .iter()
            .find(|u| u.id == h.id)
            .map(|u| u.access);
        self.check_declared("image", h.id, declared, ok, what)?;
        self.resolved
            .images
            .get(h.id as usize)
            .copied()
            .flatten()
            .ok_or_else(|| self.error(format!("image #{} has no physical resource", h.id)))
    }

    /// The physical buffer behind a handle, checking the pass declared it.
    fn buffer(
        &self,
        h: BufferHandle,
        ok: impl Fn(BufferAccess) -> bool,
        what: &str,
    ) -> Result<ResolvedBuffer> {
        let declared = self
            .pass
            .buffers
            .iter()
            .find(|u| u.id == h.id)
            .map(|u| u.access);
        self.check_declared("buffer", h.id, declared, ok, what)?;
        self.resolved
            .buffers
            .get(h.id as usize)
            .copied()
            .flatten()
            .ok_or_else(|| self.error(format!("buffer #{} has no physical resource", h.id)))
    }

    fn check_declared<A: std::fmt::Debug + Copy>(
        &self,
        noun: &str,
        id: u32,
        declared: Option<A>,
        ok: impl Fn(A) -> bool,
        what: &str,
    ) -> Result<()> {
        match declared {
            Some(a) if ok(a) => Ok(()),
            Some(a) => Err(self.error(format!(
                "uses {noun} #{id} as {what} but declared it as {a:?}"
            ))),
            None => Err(self.error(format!("uses {noun} #{id} as {what} without declaring it"))),
        }
    }

    /// Allocates and writes the descriptor set for `bindings`, binds it and
    /// the pipeline, and pushes constants.
    fn bind(
        &mut self,
        core: &PipelineCore,
        bind_point: vk::PipelineBindPoint,
        bindings: &[Binding],
        push: &[u8],
    ) -> Result<()> {
        if bindings.len() != core.bindings.len() {
            let names: Vec<&str> = core.bindings.iter().map(|b| b.name.as_str()).collect();
            return Err(self.error(format!(
                "pipeline {} takes {} bindings {names:?}, got {}",
                core.name,
                core.bindings.len(),
                bindings.len()
            )));
        }
        if push.len() as u32 != core.push_size {
            return Err(self.error(format!(
                "pipeline {} takes {} bytes of push constants, got {}",
                core.name,
                core.push_size,
                push.len()
            )));
        }
        let mut image_infos = Vec::with_capacity(bindings.len());
        let mut buffer_infos = Vec::with_capacity(bindings.len());
        for (b, r) in bindings.iter().zip(&core.bindings) {
            let kind = match b {
                Binding::SampledImage(_) => DescriptorKind::SampledImage,
                Binding::StorageImage(_) => DescriptorKind::StorageImage,
                Binding::StorageBuffer(_) => DescriptorKind::StorageBuffer,
                Binding::UniformBuffer(_) => DescriptorKind::UniformBuffer,
                Binding::Sampler(_) => DescriptorKind::Sampler,
            };
            if kind != r.kind {
                return Err(self.error(format!(
                    "binding {} (`{}`) of {} is a {:?}, got a {kind:?}",
                    r.binding, r.name, core.name, r.kind
                )));
            }
            match *b {
                Binding::SampledImage(h) => {
                    let i = self.image(h, |a| a == ImageAccess::Sampled, "a sampled image")?;
                    image_infos.push((
                        r.binding,
                        vk::DescriptorImageInfo::default()
                            .image_view(i.view)
                            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
                    ));
                }
                Binding::StorageImage(h) => {
                    let i = self.image(
                        h,
                        |a| {
                            matches!(
                                a,
                                ImageAccess::StorageRead
                                    | ImageAccess::StorageWrite
                                    | ImageAccess::StorageReadWrite
                            )
                        },
                        "a storage image",
                    )?;
                    image_infos.push((
                        r.binding,
                        vk::DescriptorImageInfo::default()
                            .image_view(i.view)
                            .image_layout(vk::ImageLayout::GENERAL),
                    ));
                }
                Binding::Sampler(s) => {
                    let sampler = match s {
                        SamplerKind::LinearClamp => self.samplers.linear_clamp,
                        SamplerKind::NearestClamp => self.samplers.nearest_clamp,
                        SamplerKind::LinearRepeat => self.samplers.linear_repeat,
                    };
                    image_infos.push((
                        r.binding,
                        vk::DescriptorImageInfo::default().sampler(sampler),
                    ));
                }
                Binding::StorageBuffer(h) => {
                    let buf = self.buffer(
                        h,
                        |a| {
                            matches!(
                                a,
                                BufferAccess::StorageRead
                                    | BufferAccess::StorageWrite
                                    | BufferAccess::StorageReadWrite
                            )
                        },
                        "a storage buffer",
                    )?;
                    buffer_infos.push((
                        r.binding,
                        vk::DescriptorBufferInfo::default()
                            .buffer(buf.buffer)
                            .range(vk::WHOLE_SIZE),
                    ));
                }
                Binding::UniformBuffer(h) => {
                    let buf = self.buffer(h, |a| a == BufferAccess::Uniform, "a uniform buffer")?;
                    buffer_infos.push((
                        r.binding,
                        vk::DescriptorBufferInfo::default()
                            .buffer(buf.buffer)
                            .range(vk::WHOLE_SIZE),
                    ));
                }
            }
        }
        let device = &self.ctx.device;
        let set = if core.bindings.is_empty() {
            None
        } else {
            Some(self.descriptors.allocate(core.set_layout)?)
        };
        if let Some(set) = set {
            let kind_of = |binding: u32| {
                core.bindings
                    .iter()
                    .find(|r| r.binding == binding)
                    .map(|r| descriptor_type(r.kind))
                    .unwrap_or_default()
            };
            let mut writes = Vec::with_capacity(bindings.len());
            for (binding, info) in &image_infos {
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(*binding)
                        .descriptor_type(kind_of(*binding))
                        .image_info(std::slice::from_ref(info)),
                );
            }
            for (binding, info) in &buffer_infos {
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(*binding)
                        .descriptor_type(kind_of(*binding))
                        .buffer_info(std::slice::from_ref(info)),
                );
            }
            unsafe { device.update_descriptor_sets(&writes, &[]) };
        }
        unsafe {
            device.cmd_bind_pipeline(self.cmd, bind_point, core.pipeline);
            if let Some(set) = set {
                device.cmd_bind_descriptor_sets(self.cmd, bind_point, core.layout, 0, &[set], &[]);
            }
            if !push.is_empty() {
                device.cmd_push_constants(self.cmd, core.layout, core.push_stages, 0, push);
            }
        }
        Ok(())
    }

    /// What every dispatch records first: its pipeline, bindings and push
    /// constants, and, after an earlier dispatch of the pass that wrote
    /// storage, the barrier that orders them.
    fn begin_dispatch(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[Binding],
        push: &[u8],
    ) -> Result<()> {
        if self.pass.kind != PassKind::Compute {
            return Err(self.error("dispatch outside a compute pass".into()));
        }
        self.bind(
            &pipeline.core,
            vk::PipelineBindPoint::COMPUTE,
            bindings,
            push,
        )?;
        if self.dispatches > 0 && self.writes_storage() {
            self.order_after_previous_dispatch();
        }
        self.dispatches += 1;
        Ok(())
    }

    /// Records a compute dispatch of `groups` workgroups.
    pub fn dispatch(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[Binding],
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<()> {
        self.begin_dispatch(pipeline, bindings, push)?;
        if groups.iter().all(|&g| g > 0) {
            unsafe {
                self.ctx
                    .device
                    .cmd_dispatch(self.cmd, groups[0], groups[1], groups[2])
            };
        }
        Ok(())
    }

    /// Records a dispatch whose workgroup counts a previous pass wrote
    /// into `args` (three u32 at byte `offset`, declared with
    /// [`BufferAccess::Indirect`]): work sized on the device, read back by
    /// nobody.
    pub fn dispatch_indirect(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[Binding],
        push: &[u8],
        args: BufferHandle,
        offset: u64,
    ) -> Result<()> {
        let a = self.buffer(
            args,
            |a| a == BufferAccess::Indirect,
            "indirect dispatch arguments",
        )?;
        if offset % 4 != 0 || offset + 12 > a.size {
            return Err(self.error(format!(
                "indirect dispatch arguments at byte {offset} of a {}-byte buffer",
                a.size
            )));
        }
        let buffer = a.buffer;
        self.begin_dispatch(pipeline, bindings, push)?;
        unsafe {
            self.ctx
                .device
                .cmd_dispatch_indirect(self.cmd, buffer, offset)
        };
        Ok(())
    }

    /// Records a dispatch whose bindings are looked up by binding number in
    /// `table` (`table[n]` for `@binding(n)`), taking only those the entry
    /// point uses, and the first bytes of `push` it takes: one table and one
    /// push block serve all entry points of a multi-kernel shader.
    pub fn dispatch_table(
        &mut self,
        pipeline: &ComputePipeline,
        table: &[Binding],
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<()> {
        let core = &pipeline.core;
        let mut bindings = Vec::with_capacity(core.bindings.len());
        for r in &core.bindings {
            match table.get(r.binding as usize) {
                Some(b) => bindings.push(*b),
                None => {
                    return Err(self.error(format!(
                        "pipeline {} uses binding {} (`{}`), which the table of {} lacks",
                        core.name,
                        r.binding,
                        r.name,
                        table.len()
                    )))
                }
            }
        }
        let size = core.push_size as usize;
        if push.len() < size {
            return Err(self.error(format!(
                "pipeline {} takes {size} bytes of push constants, got {}",
                core.name,
                push.len()
            )));
        }
        self.dispatch(pipeline, &bindings, &push[..size], groups)
    }

    /// Whether the pass declared any storage write: then each of its
    /// dispatches may read what the previous one wrote.
    fn writes_storage(&self) -> bool {
        self.pass.buffers.iter().any(|u| {
            matches!(
                u.access,
                BufferAccess::StorageWrite | BufferAccess::StorageReadWrite
            )
        }) || self.pass.images.iter().any(|u| {
            matches!(
                u.access,
                ImageAccess::StorageWrite | ImageAccess::StorageReadWrite
            )
        })
    }

    /// Orders a dispatch after the previous one of the same pass: the graph
    /// orders passes, and within a pass that writes storage, successive
    /// dispatches are ordered the same way (compute writes visible to
    /// compute reads and writes).
    fn order_after_previous_dispatch(&self) {
        let barrier = vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .dst_access_mask(
                vk::AccessFlags2::SHADER_STORAGE_READ
                    | vk::AccessFlags2::SHADER_STORAGE_WRITE
                    | vk::AccessFlags2::UNIFORM_READ,
            );
        let info = vk::DependencyInfo::default().memory_barriers(std::slice::from_ref(&barrier));
        unsafe { self.ctx.device.cmd_pipeline_barrier2(self.cmd, &info) };
    }

    /// Records a non-indexed draw inside the raster pass's rendering.
    pub fn draw(
        &mut self,
        pipeline: &GraphicsPipeline,
        bindings: &[Binding],
        push: &[u8],
        vertices: u32,
        instances: u32,
    ) -> Result<()> {
        if self.pass.kind != PassKind::Raster {
            return Err(self.error("draw outside a raster pass".into()));
        }
        let colors: Vec<vk::Format> = self
            .pass
            .images
            .iter()
            .filter(|u| matches!(u.access, ImageAccess::ColorAttachment(_)))
            .filter_map(|u| self.resolved.images[u.id as usize].map(|i| i.desc.format))
            .collect();
        let depth = self
            .pass
            .images
            .iter()
            .find(|u| matches!(u.access, ImageAccess::DepthAttachment(_)))
            .and_then(|u| self.resolved.images[u.id as usize].map(|i| i.desc.format));
        if colors != pipeline.desc.color_formats || depth != pipeline.desc.depth_format {
            return Err(self.error(format!("pipeline {} renders to {:?} + depth {:?} but the pass's attachments are {colors:?} + depth {depth:?}", pipeline.core.name, pipeline.desc.color_formats, pipeline.desc.depth_format)));
        }
        self.bind(
            &pipeline.core,
            vk::PipelineBindPoint::GRAPHICS,
            bindings,
            push,
        )?;
        if vertices > 0 && instances > 0 {
            unsafe {
                self.ctx
                    .device
                    .cmd_draw(self.cmd, vertices, instances, 0, 0)
            };
        }
        Ok(())
    }

    /// Copies a whole image into a buffer, tightly packed.
    pub fn copy_image_to_buffer(&mut self, src: ImageHandle, dst: BufferHandle) -> Result<()> {
        let i = self.image(src, |a| a == ImageAccess::TransferSrc, "a copy source")?;
        let b = self.buffer(
            dst,
            |a| a == BufferAccess::TransferDst,
            "a copy destination",
        )?;
        let bytes = texel_bytes(i.desc.format).ok_or_else(|| {
            self.error(format!(
                "cannot read back images of format {:?}",
                i.desc.format
            ))
        })? as u64
            * i.desc.width as u64
            * i.desc.height as u64;
        if b.size < bytes {
            return Err(self.error(format!(
                "buffer of {} bytes is too small for a {}x{} {:?} image ({bytes} bytes)",
                b.size, i.desc.width, i.desc.height, i.desc.format
            )));
        }
        let region = vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(whole(i.desc.format).aspect_mask)
                    .layer_count(1),
            )
            .image_extent(vk::Extent3D {
                width: i.desc.width,
                height: i.desc.height,
                depth: 1,
            });
        unsafe {
            self.ctx.device.cmd_copy_image_to_buffer(
                self.cmd,
                i.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                b.buffer,
                &[region],
            )
        };
        Ok(())
    }

    /// Copies the whole of image `src` into `dst`, which has the same
    /// size and format.
    pub fn copy_image(&mut self, src: ImageHandle, dst: ImageHandle) -> Result<()> {
        let s = self.image(src, |a| a == ImageAccess::TransferSrc, "a copy source")?;
        let d = self.image(dst, |a| a == ImageAccess::TransferDst, "a copy destination")?;
        if s.desc != d.desc {
            return Err(self.error(format!(
                "copy_image needs images of one size and format: {:?} into {:?}",
                s.desc, d.desc
            )));
        }
        let layers = vk::ImageSubresourceLayers::default()
            .aspect_mask(whole(s.desc.format).aspect_mask)
            .layer_count(1);
        let region = vk::ImageCopy::default()
            .src_subresource(layers)
            .dst_subresource(layers)
            .extent(vk::Extent3D {
                width: s.desc.width,
                height: s.desc.height,
                depth: 1,
            });
        unsafe {
            self.ctx.device.cmd_copy_image(
                self.cmd,
                s.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                d.image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
        Ok(())
    }

    /// Copies `src` into `dst` (the smaller of the two sizes).
    pub fn copy_buffer(&mut self, src: BufferHandle, dst: BufferHandle) -> Result<()> {
        let s = self.buffer(src, |a| a == BufferAccess::TransferSrc, "a copy source")?;
        let d = self.buffer(
            dst,
            |a| a == BufferAccess::TransferDst,
            "a copy destination",
        )?;
        let region = vk::BufferCopy::default().size(s.size.min(d.size));
        unsafe {
            self.ctx
                .device
                .cmd_copy_buffer(self.cmd, s.buffer, d.buffer, &[region])
        };
        Ok(())
    }

    /// Writes `bytes` at the start of `dst` from the command buffer itself
    /// (vkCmdUpdateBuffer: the data is copied at record time, so a frame's
    /// small per-frame data never races a frame still in flight). At most
    /// 65536 bytes, a multiple of 4.
    pub fn update_buffer(&mut self, dst: BufferHandle, bytes: &[u8]) -> Result<()> {
        let d = self.buffer(
            dst,
            |a| a == BufferAccess::TransferDst,
            "an update destination",
        )?;
        if bytes.is_empty() {
            return Ok(());
        }
        if bytes.len() > 65536 || bytes.len() % 4 != 0 || bytes.len() as u64 > d.size {
            return Err(self.error(format!(
                "update_buffer takes 4..=65536 bytes in multiples of 4 that fit the buffer ({} bytes); got {}",
                d.size,
                bytes.len()
            )));
        }
        unsafe {
            self.ctx
                .device
                .cmd_update_buffer(self.cmd, d.buffer, 0, bytes)
        };
        Ok(())
    }

    /// Fills a whole buffer with a repeated 32-bit value.
    pub fn fill_buffer(&mut self, dst: BufferHandle, value: u32) -> Result<()> {
        let d = self.buffer(
            dst,
            |a| a == BufferAccess::TransferDst,
            "a fill destination",
        )?;
        unsafe {
            self.ctx
                .device
                .cmd_fill_buffer(self.cmd, d.buffer, 0, vk::WHOLE_SIZE, value)
        };
        Ok(())
    }

    /// Clears a whole colour image.
    pub fn clear_image(&mut self, dst: ImageHandle, color: [f32; 4]) -> Result<()> {
        let i = self.image(
            dst,
            |a| a == ImageAccess::TransferDst,
            "a clear destination",
        )?;
        let value = vk::ClearColorValue { float32: color };
        unsafe {
            self.ctx.device.cmd_clear_color_image(
                self.cmd,
                i.image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &value,
                &[whole(i.desc.format)],
            )
        };
        Ok(())
    }
}

/// Bytes per texel of the formats the engine reads back.
pub(crate) fn texel_bytes(format: vk::Format) -> Option<u32> {
    Some(match format {
        vk::Format::R32G32B32A32_SFLOAT => 16,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R8G8B8A8_UNORM
        | vk::Format::R8G8B8A8_SRGB
        | vk::Format::B8G8R8A8_UNORM
        | vk::Format::B8G8R8A8_SRGB
        | vk::Format::R32_SFLOAT
        | vk::Format::D32_SFLOAT => 4,
        vk::Format::R32G32_SFLOAT => 8,
        vk::Format::R16_SFLOAT => 2,
        _ => return None,
    })
}
