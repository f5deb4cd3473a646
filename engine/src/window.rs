//! The windowed target: a swapchain on the context's surface, acquire and
//! present with per-slot and per-image semaphores, present-mode choice, and
//! recreation on resize; a minimised window (zero extent) renders nothing.

use std::sync::Arc;

use ash::vk;

use crate::context::Context;
use crate::error::{EngineError, Result, VkContext};
use crate::graph::{FrameGraph, ImageHandle, SyncState};
use crate::memory::{create_view, ImageDesc};
use crate::renderer::{FrameToken, SubmitSync};

/// How presentation paces frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PresentMode {
    /// Wait for vertical blank (always available).
    #[default]
    Fifo,
    /// Like FIFO, but late frames tear instead of waiting.
    FifoRelaxed,
    /// Latest frame replaces the queued one; no tearing, no waiting.
    Mailbox,
    /// No waiting; may tear.
    Immediate,
}

impl PresentMode {
    fn vk(self) -> vk::PresentModeKHR {
        match self {
            PresentMode::Fifo => vk::PresentModeKHR::FIFO,
            PresentMode::FifoRelaxed => vk::PresentModeKHR::FIFO_RELAXED,
            PresentMode::Mailbox => vk::PresentModeKHR::MAILBOX,
            PresentMode::Immediate => vk::PresentModeKHR::IMMEDIATE,
        }
    }
}

/// A swapchain image acquired for one frame.
#[derive(Debug, Clone, Copy)]
pub struct Acquired {
    index: u32,
    slot: usize,
}

/// A window's swapchain and its synchronisation objects.
pub struct WindowTarget {
    ctx: Arc<Context>,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    format: vk::Format,
    extent: vk::Extent2D,
    mode: PresentMode,
    acquire_semaphores: Vec<vk::Semaphore>,
    present_semaphores: Vec<vk::Semaphore>,
    wanted: (u32, u32),
    stale: bool,
}

impl WindowTarget {
    /// Creates the swapchain for a context made with a window, at the
    /// window's size in pixels, with one acquire semaphore per frame slot.
    pub fn new(
        ctx: &Arc<Context>,
        size: (u32, u32),
        mode: PresentMode,
        frames_in_flight: usize,
    ) -> Result<Self> {
        if ctx.surface.is_none() {
            return Err(EngineError::Window(
                "the context was created without a window".into(),
            ));
        }
        let mut acquire_semaphores = Vec::new();
        for _ in 0..frames_in_flight.max(1) {
            acquire_semaphores.push(
                unsafe {
                    ctx.device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                }
                .vk("vkCreateSemaphore")?,
            );
        }
        let mut t = Self {
            ctx: ctx.clone(),
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            views: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            mode,
            acquire_semaphores,
            present_semaphores: Vec::new(),
            wanted: size,
            stale: true,
        };
        t.recreate()?;
        Ok(t)
    }

    /// The swapchain's colour format (an sRGB format when one is offered).
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Whether writes to the swapchain are sRGB-encoded by the hardware.
    pub fn is_srgb(&self) -> bool {
        matches!(
            self.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
        )
    }

    /// The current size in pixels (0×0 while minimised).
    pub fn extent(&self) -> (u32, u32) {
        (self.extent.width, self.extent.height)
    }

    /// The present mode in use (FIFO when the requested one is unsupported).
    pub fn present_mode(&self) -> PresentMode {
        self.mode
    }

    /// Notes a new window size; the swapchain is rebuilt at the next acquire.
    pub fn resize(&mut self, size: (u32, u32)) {
        if size != self.wanted {
            self.wanted = size;
            self.stale = true;
        }
    }

    fn destroy_swapchain_parts(&mut self) {
        let Some(s) = &self.ctx.surface else { return };
        unsafe {
            for &v in &self.views {
                self.ctx.device.destroy_image_view(v, None);
            }
            for &sem in &self.present_semaphores {
                self.ctx.device.destroy_semaphore(sem, None);
            }
            if self.swapchain != vk::SwapchainKHR::null() {
                s.swapchain.destroy_swapchain(self.swapchain, None);
            }
        }
        self.views.clear();
        self.present_semaphores.clear();
        self.images.clear();
        self.swapchain = vk::SwapchainKHR::null();
    }

    fn recreate(&mut self) -> Result<()> {
        let Some(s) = &self.ctx.surface else {
            return Err(EngineError::Window("no surface".into()));
        };
        let caps = unsafe {
            s.loader
                .get_physical_device_surface_capabilities(self.ctx.physical, s.surface)
        }
        .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: self
                    .wanted
                    .0
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: self
                    .wanted
                    .1
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        // The old swapchain may still be presenting; resizes are rare.
        self.ctx.wait_idle()?;
        self.destroy_swapchain_parts();
        self.extent = extent;
        self.stale = false;
        if extent.width == 0 || extent.height == 0 {
            return Ok(());
        }
        let Some(s) = &self.ctx.surface else {
            return Err(EngineError::Window("no surface".into()));
        };
        let formats = unsafe {
            s.loader
                .get_physical_device_surface_formats(self.ctx.physical, s.surface)
        }
        .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let chosen = formats
            .iter()
            .find(|f| {
                f.format == vk::Format::B8G8R8A8_SRGB
                    && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
            })
            .or_else(|| {
                formats
                    .iter()
                    .find(|f| f.format == vk::Format::B8G8R8A8_UNORM)
            })
            .or(formats.first())
            .copied()
            .ok_or_else(|| EngineError::Window("the surface offers no formats".into()))?;
        let modes = unsafe {
            s.loader
                .get_physical_device_surface_present_modes(self.ctx.physical, s.surface)
        }
        .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        if !modes.contains(&self.mode.vk()) {
            log::warn!(
                "present mode {:?} is not supported here; using FIFO",
                self.mode
            );
            self.mode = PresentMode::Fifo;
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(s.surface)
            .min_image_count(count)
            .image_format(chosen.format)
            .image_color_space(chosen.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(self.mode.vk())
            .clipped(true);
        self.swapchain =
            unsafe { s.swapchain.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        self.format = chosen.format;
        self.images = unsafe { s.swapchain.get_swapchain_images(self.swapchain) }
            .vk("vkGetSwapchainImagesKHR")?;
        for &image in &self.images {
            self.views
                .push(create_view(&self.ctx, image, chosen.format)?);
            self.present_semaphores.push(
                unsafe {
                    self.ctx
                        .device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                }
                .vk("vkCreateSemaphore")?,
            );
        }
        log::info!(
            "swapchain {}x{} {:?} {:?}, {} images",
            extent.width,
            extent.height,
            chosen.format,
            self.mode,
            self.images.len()
        );
        Ok(())
    }

    /// Acquires the next image for the frame `token`. Returns `None` when
    /// there is nothing to draw to this frame (minimised, or the swapchain was
    /// just rebuilt); the caller then skips the frame.
    pub fn acquire(&mut self, token: FrameToken) -> Result<Option<Acquired>> {
        if self.stale {
            self.recreate()?;
        }
        if self.swapchain == vk::SwapchainKHR::null() {
            // Minimised: check again for a size next time.
            self.stale = true;
            return Ok(None);
        }
        let Some(s) = &self.ctx.surface else {
            return Ok(None);
        };
        let slot = token.slot % self.acquire_semaphores.len();
        let result = unsafe {
            s.swapchain.acquire_next_image(
                self.swapchain,
                u64::MAX,
                self.acquire_semaphores[slot],
                vk::Fence::null(),
            )
        };
        match result {
            Ok((index, suboptimal)) => {
                if suboptimal {
                    self.stale = true;
                }
                Ok(Some(Acquired { index, slot }))
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                Ok(None)
            }
            Err(e) => Err(EngineError::Vulkan {
                call: "vkAcquireNextImageKHR",
                result: e,
            }),
        }
    }

    /// Imports the acquired image into `graph`; the graph leaves it ready to present.
    pub fn import(&self, graph: &mut FrameGraph, acquired: Acquired) -> ImageHandle {
        let desc = ImageDesc {
            width: self.extent.width,
            height: self.extent.height,
            format: self.format,
        };
        let initial = SyncState {
            stage: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            access: vk::AccessFlags2::NONE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        let export = SyncState {
            stage: vk::PipelineStageFlags2::NONE,
            access: vk::AccessFlags2::NONE,
            layout: vk::ImageLayout::PRESENT_SRC_KHR,
        };
        let i = acquired.index as usize;
        graph.import_external_image(
            "swapchain",
            desc,
            self.images[i],
            self.views[i],
            initial,
            Some(export),
        )
    }

    /// The semaphores the frame's submission must wait on and signal.
    pub fn submit_sync(&self, acquired: Acquired) -> SubmitSync {
        SubmitSync {
            wait: vec![(
                self.acquire_semaphores[acquired.slot],
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            )],
            signal: vec![self.present_semaphores[acquired.index as usize]],
        }
    }

    /// Presents the acquired image after the frame's submission.
    pub fn present(&mut self, acquired: Acquired) -> Result<()> {
        let Some(s) = &self.ctx.surface else {
            return Ok(());
        };
        let swapchains = [self.swapchain];
        let indices = [acquired.index];
        let waits = [self.present_semaphores[acquired.index as usize]];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        let presented = {
            let _queue = self.ctx.lock_queue();
            unsafe { s.swapchain.queue_present(self.ctx.queue, &info) }
        };
        match presented {
            Ok(false) => Ok(()),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                Ok(())
            }
            Err(e) => Err(EngineError::Vulkan {
                call: "vkQueuePresentKHR",
                result: e,
            }),
        }
    }
}

impl Drop for WindowTarget {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        self.destroy_swapchain_parts();
        for &s in &self.acquire_semaphores {
            unsafe { self.ctx.device.destroy_semaphore(s, None) };
        }
    }
}
