//! The direct-light pass on the GPU (`direct-light`,
//! `shaders/lighting/direct.wgsl`): after the fit, the object's shading lobes
//! are assembled in one persistent buffer — the M fitted lobes, then each
//! sharp lobe of L_env ([`super::sharp`]) scaled by the field's
//! transmittance towards it, then each local light ([`super::local`]) as
//! the object's centre sees it. Built only when there are sharp lobes or
//! local lights; the CPU mirror is [`super::direct_reference::direct_lights`].

use crate::frame::meta::{PassInfo, Table1Module};
use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, ComputePipeline, Context};

use super::local::{LocalLight, INTENSITY_SIDE};
use super::sharp::lobe_rays;
use super::{DirectRays, LightLobes, LocalLightBindings};
use crate::field::GpuGridField;
use crate::march::loop_budget::check_loop_budget;
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
        /// Local lights after the sharp lobes.
        pub local: u32,
        /// Side of each local light's visibility rays.
        pub local_side: u32,
        /// 1 to shade the sharp lobes of L_env and the local lights of
        /// known emission (outside the field), 0 to leave them black.
        pub environment: u32,
        /// 1 to copy the fitted lobes alone (a fit continued with the
        /// object still: the sharp lobes and the local lights stand).
        pub fitted_only: u32,
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

/// The sharp lobes, their rays, the local lights and the assembled light
/// buffer.
pub struct DirectLightPass {
    pipeline: Arc<ComputePipeline>,
    sharp: Arc<Buffer>,
    rays: Arc<Buffer>,
    lights: Arc<Buffer>,
    spheres: Arc<Buffer>,
    local_lights: Arc<Buffer>,
    readback: BufferReadback,
    fitted: u32,
    sharp_count: u32,
    local_count: u32,
    known_count: u32,
    count: u32,
    side: u32,
    local_side: u32,
    march: MarchKnobs,
}

/// A storage buffer of `data`, or of one zero vec4 when `data` is empty
/// (a binding the shader declares is always bound).
fn storage(
    ctx: &Arc<Context>,
    name: &str,
    data: &[u8],
    extra: vk::BufferUsageFlags,
) -> anyhow::Result<Arc<Buffer>> {
    let zero = [0u8; 16];
    let data = if data.is_empty() { &zero[..] } else { data };
    Ok(Arc::new(Buffer::with_data(
        ctx,
        name,
        data,
        vk::BufferUsageFlags::STORAGE_BUFFER | extra,
    )?))
}

/// Packs local lights as two vec4s each: (centre, radius), and their
/// known emission (intensity, radius it shines from), zero when it is
/// measured from the field.
pub(crate) fn sphere_bytes(local: &[LocalLight]) -> Vec<u8> {
    local
        .iter()
        .flat_map(|l| {
            let c = l.centre.as_vec3();
            let e = l.emission.map_or([0.0; 4], |e| {
                let i = e.intensity.as_vec3();
                [i.x, i.y, i.z, e.radius as f32]
            });
            [c.x, c.y, c.z, l.radius as f32, e[0], e[1], e[2], e[3]]
        })
        .flat_map(f32::to_le_bytes)
        .collect()
}

/// The rays a shaded pixel of the object and a pixel of its cast shadow
/// take per frame for the direct lobes ([`DirectLightPass::ray_counts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DirectRayCounts {
    /// Sharp lobes of L_env, each seen along `side`² rays.
    pub sharp: u32,
    /// Their rays' side.
    pub side: u32,
    /// Local lights, each seen along `local_side`² rays.
    pub local: u32,
    /// Their rays' side.
    pub local_side: u32,
}

/// Invocations of a workgroup, which share each lobe's rays
/// (`shaders/lighting/direct.wgsl` DIRECT_GROUP).
const DIRECT_GROUP: u64 = 64;

/// The most loop iterations one invocation of `direct-light` runs
/// ([`crate::march::loop_budget`]): its share of a sharp lobe's `side`²
/// rays, or of a local light's intensity rays (each counted as a whole
/// march, since the sphere's size against the step is not known here)
/// and `local_side`² rays, and the group's sums.
fn loop_iterations(side: u32, local_side: u32, local: bool, march: &MarchKnobs) -> u64 {
    let share = |rays: u64| rays.div_ceil(DIRECT_GROUP);
    let sums = 3 * (DIRECT_GROUP.ilog2() as u64 + 1);
    let sharp = share((side * side) as u64);
    let intensity = share((INTENSITY_SIDE * INTENSITY_SIDE) as u64);
    let lights = if local {
        intensity + share((local_side * local_side) as u64)
    } else {
        0
    };
    sharp.max(lights) * march.loop_iterations() + sums
}

impl DirectLightPass {
    /// Compiles the pass for `fitted` fitted lobes followed by `sharp`,
    /// each attenuated along `side`² rays, then the `local` lights, each
    /// seen along `local_side`² rays; None when there are neither sharp
    /// lobes nor local lights (the fit's lobes are the whole light and no
    /// pass runs).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        fitted: u32,
        sharp: &[Sg64],
        side: u32,
        local: &[LocalLight],
        local_side: u32,
        march: MarchKnobs,
    ) -> anyhow::Result<Option<Self>> {
        if sharp.is_empty() && local.is_empty() {
            return Ok(None);
        }
        let side = side.max(1);
        let local_side = local_side.max(1);
        check_loop_budget(
            ctx,
            DIRECT_LIGHT,
            loop_iterations(side, local_side, !local.is_empty(), &march),
            || {
                format!(
                    "`[lighting] probe_supersampling` {side} (rays² per sharp lobe), \
                     `[lighting] local_light_rays` {local_side}, `[march] samples_per_ray` {}",
                    march.samples_per_ray
                )
            },
        )?;
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
        let none = vk::BufferUsageFlags::empty();
        let count = fitted + sharp.len() as u32 + local.len() as u32;
        let bytes = count as u64 * LOBE_BYTES;
        Ok(Some(Self {
            pipeline,
            sharp: storage(ctx, "sharp-lobes", &lobe_bytes, none)?,
            rays: storage(ctx, "sharp-rays", &ray_bytes, none)?,
            lights: storage(
                ctx,
                "light-lobes",
                &vec![0u8; bytes as usize],
                vk::BufferUsageFlags::TRANSFER_SRC,
            )?,
            spheres: storage(ctx, "local-spheres", &sphere_bytes(local), none)?,
            local_lights: storage(ctx, "local-lights", &vec![0u8; 32 * local.len()], none)?,
            readback: BufferReadback::new(ctx, "light-lobes (readback)", bytes)?,
            fitted,
            sharp_count: sharp.len() as u32,
            local_count: local.len() as u32,
            known_count: local.iter().filter(|l| l.emission.is_some()).count() as u32,
            count,
            side,
            local_side,
            march,
        }))
    }

    /// What each shaded pixel casts rays for: sharp lobes and their rays'
    /// side, local lights and theirs.
    pub fn ray_counts(&self) -> DirectRayCounts {
        DirectRayCounts {
            sharp: self.sharp_count,
            side: self.side,
            local: self.local_count,
            local_side: self.local_side,
        }
    }

    /// Lobes in the assembled buffer (fitted, then sharp).
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The lobes as the last run left them (for frames that reuse them).
    pub fn reused(&self, graph: &mut FrameGraph) -> LightLobes {
        let buffer = self.import(graph);
        let rays = graph.import_buffer(&self.rays, None);
        let local = graph.import_buffer(&self.local_lights, None);
        self.light_lobes(buffer, rays, local)
    }

    fn light_lobes(
        &self,
        buffer: BufferHandle,
        rays: BufferHandle,
        local: BufferHandle,
    ) -> LightLobes {
        LightLobes {
            buffer,
            count: self.count,
            environment: None,
            direct: Some(DirectRays {
                lobes: self.count - self.fitted,
                rays,
                rays_per_lobe: self.side * self.side,
                local: LocalLightBindings {
                    lights: local,
                    count: self.local_count,
                    side: self.local_side,
                },
            }),
        }
    }

    /// Imports the assembled buffer as the last run left it.
    fn import(&self, graph: &mut FrameGraph) -> BufferHandle {
        graph.import_buffer(&self.lights, None)
    }

    /// Whether environment light is shaded here: sharp lobes of L_env, or
    /// local lights of known emission (outside the field).
    pub fn has_environment(&self) -> bool {
        self.sharp_count > 0 || self.known_count > 0
    }

    /// Whether the field's own lights are shaded here (local lights
    /// measured from the field), which the environment switch leaves on.
    pub fn has_field_lights(&self) -> bool {
        self.local_count > self.known_count
    }

    /// Adds `direct-light`: copies the fit's current lobes from `fitted`
    /// (the fit's buffer, as written this frame), attenuates the sharp
    /// lobes (black without the `environment`) by `field` seen from
    /// `origin` and measures the local lights; returns the assembled lobes.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        origin: DVec3,
        fitted: BufferHandle,
        environment: bool,
    ) -> LightLobes {
        self.add_with(graph, field, origin, fitted, environment, false)
    }

    /// As [`Self::add`]; with `fitted_only`, only the fitted lobes are
    /// copied in, the sharp lobes and local lights standing as the last
    /// frame measured them (the object has not moved).
    pub fn add_with(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        origin: DVec3,
        fitted: BufferHandle,
        environment: bool,
        fitted_only: bool,
    ) -> LightLobes {
        let grid = field.import(graph);
        let sharp = graph.import_buffer(&self.sharp, None);
        let rays = graph.import_buffer(&self.rays, None);
        let lights = self.import(graph);
        let spheres = graph.import_buffer(&self.spheres, None);
        let mut local = graph.import_buffer(&self.local_lights, None);
        let push = DirectPush {
            origin: origin.as_vec3().to_array(),
            step: self.march.step(field.diagonal) as f32,
            termination: self.march.termination as f32,
            fitted: self.fitted,
            sharp: self.sharp_count,
            rays: self.side * self.side,
            local: self.local_count,
            local_side: self.local_side,
            environment: environment as u32,
            fitted_only: fitted_only as u32,
        };
        let mut lights = lights;
        grid.bind(graph.compute(DIRECT_LIGHT, &self.pipeline))
            .read("fitted_lobes", fitted)
            .read("sharp_lobes", sharp)
            .read("sharp_rays", rays)
            .write("lights", &mut lights)
            .read("local_spheres", spheres)
            .write("local_lights", &mut local)
            .push(&push)
            .groups([if fitted_only { self.fitted } else { self.count }, 1, 1]);
        self.light_lobes(lights, rays, local)
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
