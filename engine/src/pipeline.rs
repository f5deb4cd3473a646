//! Compute and graphics pipelines built from compiled shaders; their
//! descriptor-set layout and push-constant range come from shader reflection.

use std::sync::Arc;

use ash::vk;

use crate::context::Context;
use crate::error::{EngineError, Result, VkContext};
use crate::shader::{CompiledShader, DescriptorKind, ReflectedBinding, ShaderStage};

/// What pipelines of both kinds share: layout, set layout and reflection.
pub(crate) struct PipelineCore {
    pub(crate) ctx: Arc<Context>,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub(crate) set_layout: vk::DescriptorSetLayout,
    pub(crate) bindings: Vec<ReflectedBinding>,
    pub(crate) push_size: u32,
    pub(crate) push_stages: vk::ShaderStageFlags,
    pub(crate) name: String,
}

impl Drop for PipelineCore {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_pipeline(self.pipeline, None);
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
            self.ctx
                .device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

pub(crate) fn descriptor_type(kind: DescriptorKind) -> vk::DescriptorType {
    match kind {
        DescriptorKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
        DescriptorKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
        DescriptorKind::SampledImage => vk::DescriptorType::SAMPLED_IMAGE,
        DescriptorKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        DescriptorKind::Sampler => vk::DescriptorType::SAMPLER,
    }
}

fn stage_flags(stage: ShaderStage) -> vk::ShaderStageFlags {
    match stage {
        ShaderStage::Vertex => vk::ShaderStageFlags::VERTEX,
        ShaderStage::Fragment => vk::ShaderStageFlags::FRAGMENT,
        ShaderStage::Compute => vk::ShaderStageFlags::COMPUTE,
    }
}

/// Merges the bindings of several stages; a binding used by two stages must
/// have the same kind in both.
fn merge_bindings(
    name: &str,
    shaders: &[&CompiledShader],
) -> Result<Vec<(ReflectedBinding, vk::ShaderStageFlags)>> {
    let mut merged: Vec<(ReflectedBinding, vk::ShaderStageFlags)> = Vec::new();
    for s in shaders {
        for b in &s.bindings {
            if b.set != 0 {
                return Err(EngineError::Pass {
                    pass: name.into(),
                    message: format!(
                        "{}: binding `{}` uses @group({}); the engine binds only @group(0)",
                        s.file, b.name, b.set
                    ),
                });
            }
            match merged.iter_mut().find(|(m, _)| m.binding == b.binding) {
                Some((m, stages)) if m.kind == b.kind => *stages |= stage_flags(s.stage),
                Some((m, _)) => {
                    return Err(EngineError::Pass {
                        pass: name.into(),
                        message: format!(
                            "binding {} is `{}` ({:?}) in one stage and `{}` ({:?}) in another",
                            b.binding, m.name, m.kind, b.name, b.kind
                        ),
                    })
                }
                None => merged.push((b.clone(), stage_flags(s.stage))),
            }
        }
    }
    merged.sort_by_key(|(b, _)| b.binding);
    Ok(merged)
}

fn core(
    ctx: &Arc<Context>,
    name: &str,
    shaders: &[&CompiledShader],
) -> Result<(
    vk::DescriptorSetLayout,
    vk::PipelineLayout,
    Vec<ReflectedBinding>,
    u32,
    vk::ShaderStageFlags,
)> {
    let merged = merge_bindings(name, shaders)?;
    let layout_bindings: Vec<vk::DescriptorSetLayoutBinding> = merged
        .iter()
        .map(|(b, stages)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b.binding)
                .descriptor_type(descriptor_type(b.kind))
                .descriptor_count(1)
                .stage_flags(*stages)
        })
        .collect();
    let push_size = shaders
        .iter()
        .map(|s| s.push_constant_size)
        .max()
        .unwrap_or(0);
    if push_size > ctx.info().max_push_constants {
        return Err(EngineError::Pass {
            pass: name.into(),
            message: format!(
                "push constants of {push_size} bytes exceed the device limit of {}",
                ctx.info().max_push_constants
            ),
        });
    }
    let push_stages = shaders
        .iter()
        .filter(|s| s.push_constant_size > 0)
        .fold(vk::ShaderStageFlags::empty(), |f, s| {
            f | stage_flags(s.stage)
        });
    let set_layout = unsafe {
        ctx.device.create_descriptor_set_layout(
            &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
            None,
        )
    }
    .vk("vkCreateDescriptorSetLayout")?;
    let ranges = [vk::PushConstantRange::default()
        .stage_flags(push_stages)
        .offset(0)
        .size(push_size)];
    let set_layouts = [set_layout];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    if push_size > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    let layout = match unsafe { ctx.device.create_pipeline_layout(&info, None) } {
        Ok(l) => l,
        Err(e) => {
            unsafe { ctx.device.destroy_descriptor_set_layout(set_layout, None) };
            return Err(EngineError::Vulkan {
                call: "vkCreatePipelineLayout",
                result: e,
            });
        }
    };
    Ok((
        set_layout,
        layout,
        merged.into_iter().map(|(b, _)| b).collect(),
        push_size,
        push_stages,
    ))
}

fn module(ctx: &Context, shader: &CompiledShader) -> Result<vk::ShaderModule> {
    unsafe {
        ctx.device.create_shader_module(
            &vk::ShaderModuleCreateInfo::default().code(&shader.spirv),
            None,
        )
    }
    .vk("vkCreateShaderModule")
}

/// A compute pipeline for one entry point.
pub struct ComputePipeline {
    pub(crate) core: PipelineCore,
    workgroup: [u32; 3],
    defines: Vec<crate::shader::Define>,
}

impl ComputePipeline {
    /// Builds the pipeline from a compiled compute shader.
    pub fn new(ctx: &Arc<Context>, shader: &CompiledShader) -> Result<Self> {
        let name = format!("{}:{}", shader.file, shader.entry);
        if shader.stage != ShaderStage::Compute {
            return Err(EngineError::Pass {
                pass: name,
                message: "not a compute shader".into(),
            });
        }
        let (set_layout, layout, bindings, push_size, push_stages) = core(ctx, &name, &[shader])?;
        let module = module(ctx, shader)?;
        let entry = std::ffi::CString::new(shader.entry.clone()).unwrap_or_default();
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(&entry);
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout)];
        let result = unsafe {
            ctx.device
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
        };
        unsafe { ctx.device.destroy_shader_module(module, None) };
        let mut core = PipelineCore {
            ctx: ctx.clone(),
            pipeline: vk::Pipeline::null(),
            layout,
            set_layout,
            bindings,
            push_size,
            push_stages,
            name,
        };
        core.pipeline = result.map_err(|(_, e)| EngineError::Vulkan {
            call: "vkCreateComputePipelines",
            result: e,
        })?[0];
        Ok(Self {
            core,
            workgroup: shader.workgroup_size,
            defines: Vec::new(),
        })
    }

    /// The same pipeline, recording the defines it was compiled with.
    pub fn with_defines(mut self, defines: &[crate::shader::Define]) -> Self {
        self.defines = defines.to_vec();
        self
    }

    /// The define of `name` the pipeline was compiled with, if recorded.
    pub fn define(&self, name: &str) -> Option<&crate::shader::Define> {
        self.defines.iter().find(|d| d.name() == name)
    }

    /// The shader's workgroup size, to turn a thread count into groups.
    pub fn workgroup_size(&self) -> [u32; 3] {
        self.workgroup
    }

    /// Workgroups needed to cover `threads` invocations per axis.
    pub fn groups_for(&self, threads: [u32; 3]) -> [u32; 3] {
        std::array::from_fn(|i| threads[i].div_ceil(self.workgroup[i].max(1)))
    }
}

/// How a graphics pipeline rasterises and blends.
#[derive(Debug, Clone)]
pub struct GraphicsDesc {
    /// Formats of the colour attachments, in order.
    pub color_formats: Vec<vk::Format>,
    /// Depth attachment format, if the pass has one.
    pub depth_format: Option<vk::Format>,
    /// Test fragments against the depth attachment (LESS_OR_EQUAL).
    pub depth_test: bool,
    /// Write depth.
    pub depth_write: bool,
    /// Premultiplied-alpha "over" blending on every colour attachment.
    pub blend: bool,
    /// Cull back faces (counter-clockwise front faces).
    pub cull_back: bool,
}

/// A graphics pipeline for dynamic rendering (no render pass objects).
pub struct GraphicsPipeline {
    pub(crate) core: PipelineCore,
    pub(crate) desc: GraphicsDesc,
}

impl GraphicsPipeline {
    /// Builds the pipeline from a vertex and a fragment shader. Vertices come
    /// from storage buffers (no vertex input state); viewport and scissor are
    /// dynamic and set by the graph to the attachments' size.
    pub fn new(
        ctx: &Arc<Context>,
        vertex: &CompiledShader,
        fragment: &CompiledShader,
        desc: &GraphicsDesc,
    ) -> Result<Self> {
        let name = format!("{}:{}+{}", vertex.file, vertex.entry, fragment.entry);
        if vertex.stage != ShaderStage::Vertex || fragment.stage != ShaderStage::Fragment {
            return Err(EngineError::Pass {
                pass: name,
                message: "needs a vertex and a fragment shader".into(),
            });
        }
        let (set_layout, layout, bindings, push_size, push_stages) =
            core(ctx, &name, &[vertex, fragment])?;
        let mut core = PipelineCore {
            ctx: ctx.clone(),
            pipeline: vk::Pipeline::null(),
            layout,
            set_layout,
            bindings,
            push_size,
            push_stages,
            name,
        };
        let vs = module(ctx, vertex)?;
        let fs = match module(ctx, fragment) {
            Ok(m) => m,
            Err(e) => {
                unsafe { ctx.device.destroy_shader_module(vs, None) };
                return Err(e);
            }
        };
        let vs_entry = std::ffi::CString::new(vertex.entry.clone()).unwrap_or_default();
        let fs_entry = std::ffi::CString::new(fragment.entry.clone()).unwrap_or_default();
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs)
                .name(&vs_entry),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fs)
                .name(&fs_entry),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(if desc.cull_back {
                vk::CullModeFlags::BACK
            } else {
                vk::CullModeFlags::NONE
            })
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_test)
            .depth_write_enable(desc.depth_write)
            .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
        let attachment = vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(desc.blend)
            .src_color_blend_factor(vk::BlendFactor::ONE)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .alpha_blend_op(vk::BlendOp::ADD)
            .color_write_mask(vk::ColorComponentFlags::RGBA);
        let attachments = vec![attachment; desc.color_formats.len()];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering)];
        let result = unsafe {
            ctx.device
                .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
        };
        unsafe {
            ctx.device.destroy_shader_module(vs, None);
            ctx.device.destroy_shader_module(fs, None);
        }
        core.pipeline = result.map_err(|(_, e)| EngineError::Vulkan {
            call: "vkCreateGraphicsPipelines",
            result: e,
        })?[0];
        Ok(Self {
            core,
            desc: desc.clone(),
        })
    }
}
