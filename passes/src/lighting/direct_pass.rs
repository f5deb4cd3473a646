//! The direct-light pass on the GPU (`direct-light`,
//! `shaders/lighting/direct.wgsl`): after the fit, the object's shading lobes
//! are assembled in one persistent buffer — the M fitted lobes, then each
//! sharp lobe of L_env ([`super::sharp`]) scaled by the field's
//! transmittance towards it. Built only when L_env has sharp lobes; the
//! CPU mirror is [`super::direct_reference::direct_lights`].

use crate::frame::meta::{PassInfo, Table1Module};
use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, ComputePipeline, Context};

use super::sharp::lobe_rays;
use super::{DirectRays, LightLobes};
use crate::field::GpuGridField;
use crate::march::MarchKnobs;
use crate::sg::{Sg32, Sg64};

inlay_engine::gpu_struct! {
    /// `DirectPush` of `shaders/lighting/direct.wgsl`.
    pub struct DirectPush = "lighting/direct.wgsl" : "DirectPush" {
        /// The object's centre (world).
        pub origin: [f32; 3],
        /// March step (world units).
        pub step: f32,
        /// Early-termination transmittance.
        pub termination: f32,
        /// Fitted lobes copied first.
        pub fitted: u32,
        /// Sharp lobes after them.
        pub sharp: u32,
        /// Rays per sharp lobe.
        pub rays: u32,
    }
}

/// The direct-light pass: its name, Table 1 module and effect switch.
pub const DIRECT_LIGHT_INFO: PassInfo = PassInfo {
    name: "direct-light",
    module: Table1Module::Lighting,
    switch: Some(crate::probe::ENVIRONMENT_SWITCH),
};

/// The direct-light pass's name in the frame graph (and in timings).
pub const DIRECT_LIGHT: &str = DIRECT_LIGHT_INFO.name;

/// Bytes of one packed lobe ((p, λ), (μ, 0)).
const LOBE_BYTES: u64 = 32;

/// The sharp lobes, their rays and the assembled light buffer.
pub struct DirectLightPass {
    pipeline: Arc<ComputePipeline>,
    sharp: Arc<Buffer>,
    rays: Arc<Buffer>,
    lights: Arc<Buffer>,
    readback: BufferReadback,
    fitted: u32,
    count: u32,
    side: u32,
    march: MarchKnobs,
}

impl DirectLightPass {
    /// Compiles the pass for `fitted` fitted lobes followed by `sharp`,
    /// each attenuated along `side`² rays; None when `sharp` is empty (the
    /// fit's lobes are the whole light and no pass runs).
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        fitted: u32,
        sharp: &[Sg64],
        side: u32,
        march: MarchKnobs,
    ) -> anyhow::Result<Option<Self>> {
        if sharp.is_empty() {
            return Ok(None);
        }
        let side = side.max(1);
        let pipeline = lib.compute_pipeline(
            ctx,
            "lighting/direct.wgsl",
            "main",
            &[Define::Bool("SKIP_EMPTY", march.skip_empty)],
        )?;
        let lobe_bytes: Vec<u8> = sharp
            .iter()
            .flat_map(|g| g.to_f32().packed())
            .flat_map(f32::to_le_bytes)
            .collect();
        let ray_bytes: Vec<u8> = sharp
            .iter()
            .flat_map(|g| lobe_rays(g, side))
            .flat_map(|d| [d.x as f32, d.y as f32, d.z as f32, 0.0])
            .flat_map(f32::to_le_bytes)
            .collect();
        let read = vk::BufferUsageFlags::STORAGE_BUFFER;
        let count = fitted + sharp.len() as u32;
        let bytes = count as u64 * LOBE_BYTES;
        Ok(Some(Self {
            pipeline,
            sharp: Arc::new(Buffer::with_data(ctx, "sharp-lobes", &lobe_bytes, read)?),
            rays: Arc::new(Buffer::with_data(ctx, "sharp-rays", &ray_bytes, read)?),
            lights: Arc::new(Buffer::with_data(
                ctx,
                "light-lobes",
                &vec![0u8; bytes as usize],
                read | vk::BufferUsageFlags::TRANSFER_SRC,
            )?),
            readback: BufferReadback::new(ctx, "light-lobes (readback)", bytes)?,
            fitted,
            count,
            side,
            march,
        }))
    }

    /// Lobes in the assembled buffer (fitted, then sharp).
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The lobes as the last run left them (for frames that reuse them).
    pub fn reused(&self, graph: &mut FrameGraph) -> LightLobes {
        let buffer = self.import(graph);
        let rays = graph.import_buffer(&self.rays, None);
        self.light_lobes(buffer, rays)
    }

    fn light_lobes(&self, buffer: BufferHandle, rays: BufferHandle) -> LightLobes {
        LightLobes {
            buffer,
            count: self.count,
            direct: Some(DirectRays {
                lobes: self.count - self.fitted,
                rays,
                rays_per_lobe: self.side * self.side,
            }),
        }
    }

    /// Imports the assembled buffer as the last run left it.
    fn import(&self, graph: &mut FrameGraph) -> BufferHandle {
        graph.import_buffer(&self.lights, None)
    }

    /// Adds `direct-light`: copies the fit's current lobes from `fitted`
    /// (the fit's buffer, as written this frame) and attenuates the sharp
    /// lobes by `field` seen from `origin`; returns the assembled lobes.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        origin: DVec3,
        fitted: BufferHandle,
    ) -> LightLobes {
        let grid = field.import(graph);
        let sharp = graph.import_buffer(&self.sharp, None);
        let rays = graph.import_buffer(&self.rays, None);
        let lights = self.import(graph);
        let push = DirectPush {
            origin: origin.as_vec3().to_array(),
            step: self.march.step(field.diagonal) as f32,
            termination: self.march.termination as f32,
            fitted: self.fitted,
            sharp: self.count - self.fitted,
            rays: self.side * self.side,
        };
        let mut lights = lights;
        grid.bind(graph.compute(DIRECT_LIGHT, &self.pipeline))
            .read("fitted_lobes", fitted)
            .read("sharp_lobes", sharp)
            .read("sharp_rays", rays)
            .write("lights", &mut lights)
            .push(&push)
            .threads([self.count, 1, 1]);
        self.light_lobes(lights, rays)
    }

    /// Adds a transfer pass copying the assembled lobes to the host;
    /// [`Self::read`] reads them once the frame has finished.
    pub fn add_readback(&self, graph: &mut FrameGraph) {
        let lights = self.import(graph);
        self.readback
            .add_to_graph(graph, "light-lobes-readback", lights);
    }

    /// The lobes of the frame that carried [`Self::add_readback`].
    pub fn read(&self) -> anyhow::Result<Vec<Sg32>> {
        let l = self.readback.read_f32()?;
        Ok((0..self.count as usize)
            .map(|k| Sg32::unpack(&l[8 * k..8 * k + 8]))
            .collect())
    }
}
