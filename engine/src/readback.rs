//! Headless target support: copying a rendered HDR image (or any buffer)
//! into host-visible memory through a graph transfer pass, and decoding it
//! on the CPU.

use std::sync::Arc;

use ash::vk;

use crate::context::Context;
use crate::error::{EngineError, Result};
use crate::graph::{
    texel_bytes, BufferAccess, BufferHandle, FrameGraph, ImageAccess, ImageHandle, PassKind,
    SyncState,
};
use crate::image_io::HdrImage;
use crate::memory::{Buffer, BufferLocation, ImageDesc};

/// A host-visible buffer that receives an RGBA16F or RGBA32F image at the end
/// of a frame.
pub struct Readback {
    buffer: Arc<Buffer>,
    desc: ImageDesc,
}

impl Readback {
    /// A readback buffer for images of this shape (RGBA16F, RGBA32F, R32F
    /// which reads back as (v, 0, 0, 1), or RG32F as (r, g, 0, 1)).
    pub fn new(ctx: &Arc<Context>, desc: ImageDesc) -> Result<Self> {
        if !matches!(
            desc.format,
            vk::Format::R16G16B16A16_SFLOAT
                | vk::Format::R32G32B32A32_SFLOAT
                | vk::Format::R32_SFLOAT
                | vk::Format::R32G32_SFLOAT
        ) {
            return Err(EngineError::Pass {
                pass: "readback".into(),
                message: format!(
                    "reads back RGBA16F, RGBA32F, RG32F or R32F images, not {:?}",
                    desc.format
                ),
            });
        }
        let bytes =
            texel_bytes(desc.format).unwrap_or(16) as u64 * desc.width as u64 * desc.height as u64;
        let buffer = Buffer::new(
            ctx,
            "readback",
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            BufferLocation::Readback,
        )?;
        Ok(Self {
            buffer: Arc::new(buffer),
            desc,
        })
    }

    /// Adds a transfer pass named `readback` that copies `image` into the
    /// buffer; the buffer is left ready for host reads.
    pub fn add_to_graph(&self, graph: &mut FrameGraph, image: ImageHandle) {
        let export = SyncState {
            stage: vk::PipelineStageFlags2::HOST,
            access: vk::AccessFlags2::HOST_READ,
            layout: vk::ImageLayout::UNDEFINED,
        };
        let buffer = graph.import_buffer(&self.buffer, Some(export));
        let mut pass = graph.add_pass("readback", PassKind::Transfer);
        pass.image(image, ImageAccess::TransferSrc);
        pass.buffer(buffer, BufferAccess::TransferDst);
        pass.exec(move |ctx| ctx.copy_image_to_buffer(image, buffer));
    }

    /// Decodes the buffer. Call after the frame that filled it has finished
    /// (e.g. after [`Renderer::finish`](crate::Renderer::finish)).
    pub fn read(&self) -> Result<HdrImage> {
        let bytes = self.buffer.mapped().ok_or_else(|| EngineError::Pass {
            pass: "readback".into(),
            message: "readback buffer is not host-visible".into(),
        })?;
        let n = (self.desc.width * self.desc.height) as usize;
        let pixels = match self.desc.format {
            vk::Format::R16G16B16A16_SFLOAT => bytes
                .chunks_exact(8)
                .take(n)
                .map(|c| {
                    std::array::from_fn(|i| {
                        half::f16::from_le_bytes([c[2 * i], c[2 * i + 1]]).to_f32()
                    })
                })
                .collect(),
            vk::Format::R32_SFLOAT => bytes
                .chunks_exact(4)
                .take(n)
                .map(|c| [f32::from_le_bytes([c[0], c[1], c[2], c[3]]), 0.0, 0.0, 1.0])
                .collect(),
            vk::Format::R32G32_SFLOAT => bytes
                .chunks_exact(8)
                .take(n)
                .map(|c| {
                    let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                    [f(0), f(4), 0.0, 1.0]
                })
                .collect(),
            _ => bytes
                .chunks_exact(16)
                .take(n)
                .map(|c| {
                    std::array::from_fn(|i| {
                        f32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])
                    })
                })
                .collect(),
        };
        Ok(HdrImage {
            width: self.desc.width,
            height: self.desc.height,
            pixels,
        })
    }
}

/// A host-visible buffer that receives a copy of a device buffer at the end
/// of a frame (results, statistics, fitted parameters).
pub struct BufferReadback {
    buffer: Arc<Buffer>,
}

impl BufferReadback {
    /// A readback buffer of `size` bytes.
    pub fn new(ctx: &Arc<Context>, name: &str, size: u64) -> Result<Self> {
        let buffer = Buffer::new(
            ctx,
            name,
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            BufferLocation::Readback,
        )?;
        Ok(Self {
            buffer: Arc::new(buffer),
        })
    }

    /// Adds a transfer pass named `pass` copying `source` (which needs
    /// transfer-source usage) into this buffer, left ready for host reads.
    pub fn add_to_graph(&self, graph: &mut FrameGraph, pass: &str, source: BufferHandle) {
        let export = SyncState {
            stage: vk::PipelineStageFlags2::HOST,
            access: vk::AccessFlags2::HOST_READ,
            layout: vk::ImageLayout::UNDEFINED,
        };
        let buffer = graph.import_buffer(&self.buffer, Some(export));
        let mut p = graph.add_pass(pass, PassKind::Transfer);
        p.buffer(source, BufferAccess::TransferSrc);
        p.buffer(buffer, BufferAccess::TransferDst);
        p.exec(move |ctx| ctx.copy_buffer(source, buffer));
    }

    /// The buffer's first `size_of::<T>()` bytes as a `T` (a
    /// [`gpu_struct!`](crate::gpu_struct) mirror, say). Call after the
    /// frame that filled it has finished.
    pub fn read_pod<T: bytemuck::Pod>(&self) -> Result<T> {
        let bytes = self.buffer.mapped().ok_or_else(|| EngineError::Pass {
            pass: "readback".into(),
            message: "readback buffer is not host-visible".into(),
        })?;
        let size = std::mem::size_of::<T>();
        let bytes = bytes.get(..size).ok_or_else(|| EngineError::Pass {
            pass: "readback".into(),
            message: format!("{} bytes read back, {size} wanted", bytes.len()),
        })?;
        Ok(bytemuck::pod_read_unaligned(bytes))
    }

    /// The buffer's content as little-endian f32s. Call after the frame
    /// that filled it has finished.
    pub fn read_f32(&self) -> Result<Vec<f32>> {
        let bytes = self.buffer.mapped().ok_or_else(|| EngineError::Pass {
            pass: "readback".into(),
            message: "readback buffer is not host-visible".into(),
        })?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}
