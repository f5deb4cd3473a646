//! Buffers and images whose memory comes from gpu-allocator. They free
//! themselves on drop; the frame graph and the targets hand them to passes.

use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::context::Context;
use crate::error::{EngineError, Result, VkContext};
use crate::graph::SyncState;

/// Where a buffer's memory lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BufferLocation {
    /// Device-local, not mapped.
    Gpu,
    /// Host-visible, written by the CPU and read by the GPU.
    Upload,
    /// Host-visible, written by the GPU and read back by the CPU.
    Readback,
}

/// A buffer with its memory.
pub struct Buffer {
    ctx: Arc<Context>,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    name: String,
    sync: Mutex<SyncState>,
}

impl Buffer {
    /// Creates a buffer of `size` bytes (at least 4) for the given usage.
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: BufferLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        let limit = ctx.info().max_storage_buffer_range as u64;
        if usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER) && size > limit {
            // Bound whole, it would exceed the binding limit: the shader
            // would read garbage past it, and the layer may not say so.
            return Err(EngineError::Allocation {
                what: format!("storage buffer `{name}`"),
                message: format!(
                    "{} MiB is more than {}'s largest storage binding ({} MiB)",
                    size >> 20,
                    ctx.info().name,
                    limit >> 20
                ),
            });
        }
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { ctx.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let location = match location {
            BufferLocation::Gpu => MemoryLocation::GpuOnly,
            BufferLocation::Upload => MemoryLocation::CpuToGpu,
            BufferLocation::Readback => MemoryLocation::GpuToCpu,
        };
        let allocation = ctx
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| {
                unsafe { ctx.device.destroy_buffer(raw, None) };
                EngineError::Allocation {
                    what: format!("buffer `{name}` ({size} bytes)"),
                    message: e.to_string(),
                }
            })?;
        unsafe {
            ctx.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        }
        .vk("vkBindBufferMemory")?;
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            allocation: Some(allocation),
            size,
            name: name.to_owned(),
            sync: Mutex::new(SyncState::FRESH),
        })
    }

    /// Size in bytes.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// The name given at creation.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The state the last recorded frame left the buffer in.
    pub(crate) fn sync_state(&self) -> SyncState {
        *self.sync.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn set_sync_state(&self, state: SyncState) {
        *self.sync.lock().unwrap_or_else(|p| p.into_inner()) = state;
    }

    /// The mapped bytes of a host-visible buffer (`None` for GPU-only memory).
    /// Read only after the GPU work writing it has completed.
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation
            .as_ref()?
            .mapped_slice()
            .map(|s| &s[..self.size as usize])
    }

    /// A host-visible buffer of `usage` holding `bytes`, written through its
    /// mapping (no transfer): staging, or records the GPU reads once.
    pub fn host_with_data(
        ctx: &Arc<Context>,
        name: &str,
        bytes: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<Self> {
        let mut buffer = Self::new(ctx, name, bytes.len() as u64, usage, BufferLocation::Upload)?;
        buffer
            .mapped_mut()
            .expect("upload buffers are host-visible")[..bytes.len()]
            .copy_from_slice(bytes);
        Ok(buffer)
    }

    /// The mapped bytes of a host-visible buffer, for writing uploads.
    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()?
            .mapped_slice_mut()
            .map(|s| &mut s[..size])
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
    }
}

/// Shape and format of a 2D image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ImageDesc {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texel format.
    pub format: vk::Format,
}

/// Whether a format is a depth (or depth-stencil) format.
pub fn is_depth_format(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::D16_UNORM
            | vk::Format::D32_SFLOAT
            | vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
            | vk::Format::X8_D24_UNORM_PACK32
    )
}

/// The aspect a whole-image view or barrier of this format covers.
pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    if is_depth_format(format) {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    }
}

/// A 2D image with one mip level, its memory and a whole-image view.
pub struct Image {
    pub(crate) ctx: Arc<Context>,
    pub(crate) raw: vk::Image,
    pub(crate) view: vk::ImageView,
    allocation: Option<Allocation>,
    desc: ImageDesc,
    usage: vk::ImageUsageFlags,
    sync: Mutex<SyncState>,
}

impl Image {
    /// Creates a device-local image with the given usage.
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        desc: ImageDesc,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        if desc.width == 0 || desc.height == 0 {
            return Err(EngineError::Allocation {
                what: format!("image `{name}`"),
                message: "width and height must be at least 1".into(),
            });
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { ctx.device.create_image(&info, None) }.vk("vkCreateImage")?;
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = ctx
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| {
                unsafe { ctx.device.destroy_image(raw, None) };
                EngineError::Allocation {
                    what: format!("image `{name}` ({}x{})", desc.width, desc.height),
                    message: e.to_string(),
                }
            })?;
        unsafe {
            ctx.device
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        }
        .vk("vkBindImageMemory")?;
        let view = create_view(ctx, raw, desc.format)?;
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            view,
            allocation: Some(allocation),
            desc,
            usage,
            sync: Mutex::new(SyncState::FRESH),
        })
    }

    /// Its shape and format.
    pub fn desc(&self) -> ImageDesc {
        self.desc
    }

    /// The usages it was created with.
    pub fn usage(&self) -> vk::ImageUsageFlags {
        self.usage
    }

    /// The state the last recorded frame left the image in.
    pub(crate) fn sync_state(&self) -> SyncState {
        *self.sync.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn set_sync_state(&self, state: SyncState) {
        *self.sync.lock().unwrap_or_else(|p| p.into_inner()) = state;
    }
}

pub(crate) fn create_view(
    ctx: &Context,
    image: vk::Image,
    format: vk::Format,
) -> Result<vk::ImageView> {
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(whole(format));
    unsafe { ctx.device.create_image_view(&info, None) }.vk("vkCreateImageView")
}

/// The subresource range covering the whole (single-mip, single-layer) image.
pub(crate) fn whole(format: vk::Format) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(aspect_of(format))
        .level_count(1)
        .layer_count(1)
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_image_view(self.view, None);
            self.ctx.device.destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
    }
}
