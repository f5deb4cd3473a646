//! Per-frame descriptor sets (reset each time a frame slot is reused) and the
//! engine's shared samplers.

use std::sync::Arc;

use ash::vk;

use crate::context::Context;
use crate::error::{EngineError, Result, VkContext};

const SETS_PER_POOL: u32 = 256;
const DESCRIPTORS_PER_TYPE: u32 = 1024;

/// Descriptor pools for one frame slot; sets live until the slot is reused.
pub(crate) struct DescriptorArena {
    ctx: Arc<Context>,
    pools: Vec<vk::DescriptorPool>,
    current: usize,
}

impl DescriptorArena {
    pub(crate) fn new(ctx: &Arc<Context>) -> Self {
        Self {
            ctx: ctx.clone(),
            pools: Vec::new(),
            current: 0,
        }
    }

    fn new_pool(&self) -> Result<vk::DescriptorPool> {
        let sizes = [
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::STORAGE_BUFFER,
            vk::DescriptorType::SAMPLED_IMAGE,
            vk::DescriptorType::STORAGE_IMAGE,
            vk::DescriptorType::SAMPLER,
        ]
        .map(|ty| vk::DescriptorPoolSize {
            ty,
            descriptor_count: DESCRIPTORS_PER_TYPE,
        });
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(SETS_PER_POOL)
            .pool_sizes(&sizes);
        unsafe { self.ctx.device.create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")
    }

    /// Allocates one set, growing by a pool when the current one is full.
    pub(crate) fn allocate(
        &mut self,
        layout: vk::DescriptorSetLayout,
    ) -> Result<vk::DescriptorSet> {
        let layouts = [layout];
        loop {
            if self.current == self.pools.len() {
                let pool = self.new_pool()?;
                self.pools.push(pool);
            }
            let info = vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(self.pools[self.current])
                .set_layouts(&layouts);
            match unsafe { self.ctx.device.allocate_descriptor_sets(&info) } {
                Ok(sets) => return Ok(sets[0]),
                Err(vk::Result::ERROR_OUT_OF_POOL_MEMORY)
                | Err(vk::Result::ERROR_FRAGMENTED_POOL) => self.current += 1,
                Err(e) => {
                    return Err(EngineError::Vulkan {
                        call: "vkAllocateDescriptorSets",
                        result: e,
                    })
                }
            }
        }
    }

    /// Frees every set; call only once the slot's previous frame has finished.
    pub(crate) fn reset(&mut self) -> Result<()> {
        for &p in &self.pools {
            unsafe {
                self.ctx
                    .device
                    .reset_descriptor_pool(p, vk::DescriptorPoolResetFlags::empty())
            }
            .vk("vkResetDescriptorPool")?;
        }
        self.current = 0;
        Ok(())
    }
}

impl Drop for DescriptorArena {
    fn drop(&mut self) {
        for &p in &self.pools {
            unsafe { self.ctx.device.destroy_descriptor_pool(p, None) };
        }
    }
}

/// The samplers passes can bind.
pub(crate) struct Samplers {
    ctx: Arc<Context>,
    pub(crate) linear_clamp: vk::Sampler,
    pub(crate) nearest_clamp: vk::Sampler,
    pub(crate) linear_repeat: vk::Sampler,
}

impl Samplers {
    pub(crate) fn new(ctx: &Arc<Context>) -> Result<Self> {
        let make = |filter: vk::Filter, mode: vk::SamplerAddressMode| {
            let info = vk::SamplerCreateInfo::default()
                .mag_filter(filter)
                .min_filter(filter)
                .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
                .address_mode_u(mode)
                .address_mode_v(mode)
                .address_mode_w(mode)
                .max_lod(0.0);
            unsafe { ctx.device.create_sampler(&info, None) }.vk("vkCreateSampler")
        };
        let clamp = vk::SamplerAddressMode::CLAMP_TO_EDGE;
        let made = [
            make(vk::Filter::LINEAR, clamp),
            make(vk::Filter::NEAREST, clamp),
            make(vk::Filter::LINEAR, vk::SamplerAddressMode::REPEAT),
        ];
        if made.iter().any(|m| m.is_err()) {
            let mut first_error = None;
            for m in made {
                match m {
                    Ok(s) => unsafe { ctx.device.destroy_sampler(s, None) },
                    Err(e) => first_error = first_error.or(Some(e)),
                }
            }
            return Err(first_error.expect("one failed"));
        }
        let [linear_clamp, nearest_clamp, linear_repeat] = made.map(|m| m.unwrap_or_default());
        Ok(Self {
            ctx: ctx.clone(),
            linear_clamp,
            nearest_clamp,
            linear_repeat,
        })
    }
}

impl Drop for Samplers {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_sampler(self.linear_clamp, None);
            self.ctx.device.destroy_sampler(self.nearest_clamp, None);
            self.ctx.device.destroy_sampler(self.linear_repeat, None);
        }
    }
}
