//! The probe-trace pass on the GPU (`shaders/probe/trace.wgsl`), writing a
//! persistent probe image that the SG fit reads.

use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};
use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{BufferHandle, FrameGraph, ImageHandle};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, ComputePipeline, Context, Image, ImageDesc};

use super::direction_map::{DirectionMap, MapKind};
use super::knobs::ProbeKnobs;
use super::texel_filter::texel_environment;
use crate::field::GpuGridField;
use crate::march::MarchKnobs;
use crate::sg::Sg64;

inlay_engine::gpu_struct! {
    /// `ProbePush` of `shaders/probe/trace.wgsl`.
    pub struct ProbePush = "probe/trace.wgsl" : "ProbePush" {
        /// Where the probe is (world).
        pub origin: [f32; 3],
        /// March step (world units).
        pub step: f32,
        /// Probe texels across.
        pub width: u32,
        /// Probe texels down.
        pub height: u32,
        /// Early-termination transmittance.
        pub termination: f32,
        /// Lobes of L_env (0: the field alone).
        pub env_lobe_count: u32,
        /// Rays per texel side.
        pub side: u32,
        /// Local lights left out ([`crate::lighting::local`]).
        pub local_count: u32,
        /// One texel of each `stride` × `stride` block is traced
        /// ([`ProbeKnobs::stride`]; 1: every texel).
        pub stride: u32,
        /// Which one: column + stride × row in the block.
        pub phase: u32,
        /// The first sub-sample this dispatch traces (row-major in a
        /// texel's `side` × `side`); 0 writes the texel, later ones add.
        pub first_sample: u32,
        /// How many it traces.
        pub sample_count: u32,
        /// Padding to the block's 16-byte size.
        pub _pad0: u32,
        /// Padding.
        pub _pad1: u32,
    }
}

/// The probe-trace pass: its name, Table 1 module and effect switch.
pub const PROBE_TRACE_INFO: PassInfo = PassInfo {
    name: "probe-trace",
    module: Table1Module::Lighting,
    switch: Some(ENVIRONMENT_SWITCH),
};

/// The probe trace's name in the frame graph (and in timings).
pub const PROBE_TRACE: &str = PROBE_TRACE_INFO.name;

/// The switch that leaves the distant light L_env out of the probe and the
/// direct lobes (declared here; [`crate::lighting`]'s direct pass shares it).
pub const ENVIRONMENT_SWITCH: EffectSwitch = EffectSwitch {
    effect: Effect::Environment,
    name: "env",
    key: "F1",
};

/// Format of the probe image: L_i in rgb, Ô in alpha.
pub const PROBE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The broad lobes of L_env a probe adds beyond the field, as a frame
/// binds them (two vec4s each, (p, λ), (μ, 0)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EnvironmentLobes {
    /// The buffer.
    pub buffer: BufferHandle,
    /// How many lobes.
    pub count: u32,
}

/// L_env's lobes and the entry point that adds them.
struct ProbeEnvironment {
    pipeline: Arc<ComputePipeline>,
    lobes: Arc<Buffer>,
    count: u32,
}

/// Which texels of the probe a trace writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProbeTexels {
    /// Every texel.
    All,
    /// The texels of the `n`-th update of a strided trace
    /// ([`ProbeKnobs::phase_offset`]); the others keep what the updates
    /// before wrote.
    Phase(u32),
}

/// The probe trace for one set of knobs and one environment light.
pub struct ProbePass {
    field_only: Arc<ComputePipeline>,
    environment: Option<ProbeEnvironment>,
    image: Arc<Image>,
    map: DirectionMap,
    knobs: ProbeKnobs,
    march: MarchKnobs,
    spheres: Arc<Buffer>,
    local_count: u32,
    /// Sub-samples of a texel one dispatch traces ([`samples_per_dispatch`]).
    samples_per_dispatch: u32,
}

/// How many of a texel's `knobs.supersampling`² sub-samples one invocation
/// of the trace may march under the device's loop limit `limit`
/// ([`crate::march::loop_budget`]), with `local` local lights (each taken
/// out of a ray by two marches) and `env_lobes` lobes of L_env, on a field
/// with view-dependent colour if `view_dependent` (the trace takes a
/// sample's corners in a loop, [`crate::march::SH_CORNER_LOOP_DEFINE`]:
/// faster, and it splits its rays at no loss); the pass splits a texel's
/// sub-samples over as many dispatches as that takes. An error names the
/// knobs when even one sub-sample is over the limit.
pub fn samples_per_dispatch(
    limit: Option<u64>,
    knobs: &ProbeKnobs,
    march: &MarchKnobs,
    local: usize,
    env_lobes: usize,
    view_dependent: bool,
) -> anyhow::Result<u32> {
    let samples = knobs.supersampling * knobs.supersampling;
    // Per sub-sample: its march, two per local light, the loops over the
    // lights and the lobes; per invocation: the texel's weight, a loop
    // over every sub-sample.
    let corners = if view_dependent {
        crate::march::VIEW_DEPENDENT_SAMPLE_LOOPS
    } else {
        0
    };
    let march_loops = march.loop_iterations() * (1 + corners);
    let per_sample = march_loops * (1 + 2 * local as u64) + (local + env_lobes + 1) as u64;
    let fixed = samples as u64 + 1;
    crate::march::loop_budget::items_per_invocation(limit, fixed, per_sample, samples).ok_or_else(
        || {
            anyhow::anyhow!(
                "probe-trace: one ray may loop {per_sample} times (`[march] samples_per_ray` {}, \
             {local} local lights taken out of it), over the device's limit of {} loop \
             iterations per invocation; lower `samples_per_ray`",
                march.samples_per_ray,
                limit.unwrap_or(u64::MAX)
            )
        },
    )
}

impl ProbePass {
    /// Compiles the pass and creates its probe image. `environment` is the
    /// distant light L_env (blurred here to the probe's sub-sample spacing,
    /// [`texel_environment`]); when empty, the pass runs the entry point
    /// without the L_env term. The `local` lights' light is left out.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        knobs: ProbeKnobs,
        march: MarchKnobs,
        environment: &[Sg64],
        local: &[crate::lighting::LocalLight],
    ) -> anyhow::Result<Self> {
        knobs
            .check()
            .map_err(|(k, m)| anyhow::anyhow!("probe knob `{k}`: {m}"))?;
        march
            .check()
            .map_err(|(k, m)| anyhow::anyhow!("march knob `{k}`: {m}"))?;
        let defines = [
            Define::Bool("SKIP_EMPTY", march.skip_empty),
            Define::Bool("OCTAHEDRAL", knobs.map == MapKind::Octahedral),
            Define::Bool(crate::march::SH_CORNER_LOOP_DEFINE, true),
        ];
        let build = |entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, "probe/trace.wgsl", entry, &defines)?)
        };
        let field_only = build("main_field_only")?;
        let map = knobs.direction_map();
        let environment = texel_environment(environment, &map, knobs.supersampling);
        let samples_per_dispatch = samples_per_dispatch(
            ctx.info().loop_iteration_limit,
            &knobs,
            &march,
            local.len(),
            environment.len(),
            crate::field::library_marches_view_dependent(lib),
        )?;
        let environment = if environment.is_empty() {
            None
        } else {
            let bytes: Vec<u8> = environment
                .iter()
                .flat_map(|g| g.to_f32().packed())
                .flat_map(f32::to_le_bytes)
                .collect();
            let buffer = Buffer::with_data(
                ctx,
                "environment-lobes",
                &bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?;
            Some(ProbeEnvironment {
                pipeline: build("main_with_environment")?,
                lobes: Arc::new(buffer),
                count: environment.len() as u32,
            })
        };
        let image = Arc::new(Image::new(
            ctx,
            "probe",
            ImageDesc {
                width: map.width,
                height: map.height,
                format: PROBE_FORMAT,
            },
            vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST,
        )?);
        Ok(Self {
            field_only,
            environment,
            image,
            map,
            knobs,
            march,
            spheres: {
                let mut bytes = crate::lighting::direct_pass::sphere_bytes(local);
                bytes.resize(bytes.len().max(16), 0);
                Arc::new(Buffer::with_data(
                    ctx,
                    "probe local spheres",
                    &bytes,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                )?)
            },
            local_count: local.len() as u32,
            samples_per_dispatch,
        })
    }

    /// Dispatches a trace takes: a texel's sub-samples split so that each
    /// invocation stays under the device's loop limit (1 unless the knobs
    /// are high).
    pub fn dispatches(&self) -> u32 {
        (self.knobs.supersampling * self.knobs.supersampling).div_ceil(self.samples_per_dispatch)
    }

    /// The probe's direction map.
    pub fn map(&self) -> DirectionMap {
        self.map
    }

    /// The persistent probe image (what the last trace wrote).
    pub fn image(&self) -> &Arc<Image> {
        &self.image
    }

    /// Imports the probe image without tracing (for frames that reuse it).
    pub fn import(&self, graph: &mut FrameGraph) -> ImageHandle {
        graph.import_image(&self.image, "probe", None)
    }

    /// Whether the pass was built with an environment light (a black one
    /// is never evaluated).
    pub fn has_environment(&self) -> bool {
        self.environment.is_some()
    }

    /// The environment lobes the probe adds beyond the field (packed as
    /// the light lobes are, blurred to the sub-sample spacing), imported
    /// into `graph`; None when there are none.
    pub fn environment_lobes(&self, graph: &mut FrameGraph) -> Option<EnvironmentLobes> {
        self.environment.as_ref().map(|e| EnvironmentLobes {
            buffer: graph.import_buffer(&e.lobes, None),
            count: e.count,
        })
    }

    /// How many lobes of L_env the probe adds beyond the field (0: none).
    pub fn environment_lobe_count(&self) -> u32 {
        self.environment.as_ref().map_or(0, |e| e.count)
    }

    /// The knobs it was built with.
    pub fn knobs(&self) -> ProbeKnobs {
        self.knobs
    }

    /// Adds the `probe-trace` pass tracing every texel of `field` from
    /// `origin`, with the L_env term; returns the written probe image.
    pub fn add(&self, graph: &mut FrameGraph, field: &GpuGridField, origin: DVec3) -> ImageHandle {
        self.add_with(graph, field, origin, true, ProbeTexels::All)
    }

    /// Adds the `probe-trace` pass writing `texels`; `environment = false`
    /// leaves the L_env term out (the field-only entry point runs, the
    /// lobes are not bound).
    pub fn add_with(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        origin: DVec3,
        environment: bool,
        texels: ProbeTexels,
    ) -> ImageHandle {
        let grid = field.import(graph);
        let probe = self.import(graph);
        let chosen = self.environment.as_ref().filter(|_| environment);
        let env = chosen.map(|e| (graph.import_buffer(&e.lobes, None), e.count));
        let (w, h) = (self.map.width, self.map.height);
        let (stride, phase) = match texels {
            ProbeTexels::All => (1, 0),
            ProbeTexels::Phase(n) => {
                let (x, y) = self.knobs.phase_offset(n);
                (self.knobs.stride, x + self.knobs.stride * y)
            }
        };
        let samples = self.knobs.supersampling * self.knobs.supersampling;
        let mut probe = probe;
        let pipeline = chosen.map_or(&self.field_only, |e| &e.pipeline);
        let spheres = graph.import_buffer(&self.spheres, None);
        let mut pass = graph.compute_pass(PROBE_TRACE);
        for first in (0..samples).step_by(self.samples_per_dispatch as usize) {
            let push = ProbePush {
                origin: origin.as_vec3().to_array(),
                step: self.march.step(field.diagonal) as f32,
                width: w,
                height: h,
                termination: self.march.termination as f32,
                env_lobe_count: env.map_or(0, |(_, n)| n),
                side: self.knobs.supersampling,
                local_count: self.local_count,
                stride,
                phase,
                first_sample: first,
                sample_count: self.samples_per_dispatch.min(samples - first),
                _pad0: 0,
                _pad1: 0,
            };
            let dispatch = grid.bind(pass.dispatch(pipeline));
            let dispatch = if first == 0 {
                dispatch.write("probe", &mut probe)
            } else {
                dispatch.read_write("probe", &mut probe)
            };
            dispatch
                .read("local_spheres", spheres)
                .read_opt("env_lobes", env.map(|(b, _)| b))
                .push(&push)
                .threads([w.div_ceil(stride), h.div_ceil(stride), 1]);
        }
        pass.finish();
        probe
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knobs(supersampling: u32) -> ProbeKnobs {
        ProbeKnobs {
            supersampling,
            ..ProbeKnobs::default()
        }
    }

    fn march(samples_per_ray: u32) -> MarchKnobs {
        MarchKnobs {
            samples_per_ray,
            ..MarchKnobs::default()
        }
    }

    #[test]
    fn a_texels_rays_are_split_only_past_the_limit() {
        let limit = Some(inlay_engine::LLVMPIPE_LOOP_LIMIT);
        // The defaults: 36 rays of 513 samples, one dispatch; with two
        // local lights a ray may take 5 marches: 25 rays a dispatch.
        assert_eq!(
            samples_per_dispatch(limit, &knobs(6), &march(512), 0, 4, false).unwrap(),
            36
        );
        assert_eq!(
            samples_per_dispatch(limit, &knobs(6), &march(512), 2, 4, false).unwrap(),
            25
        );
        // 256 rays of 1025: (65535 − 257) / 1026 = 63 a dispatch.
        assert_eq!(
            samples_per_dispatch(limit, &knobs(16), &march(1024), 0, 0, false).unwrap(),
            63
        );
        assert_eq!(
            samples_per_dispatch(None, &knobs(16), &march(1024), 0, 0, false).unwrap(),
            256
        );
        // One ray of 32769 samples and two more marches for a local light.
        // On a view-dependent field a sample costs nine: with a local
        // light, (65535 − 37) / (513 · 9 · 3 + 6) = 4 rays a dispatch.
        assert_eq!(
            samples_per_dispatch(limit, &knobs(6), &march(512), 1, 4, true).unwrap(),
            4
        );
        let e = samples_per_dispatch(limit, &knobs(6), &march(32768), 1, 0, false).unwrap_err();
        assert!(
            e.to_string().contains("`[march] samples_per_ray` 32768"),
            "{e}"
        );
        assert!(samples_per_dispatch(None, &knobs(6), &march(32768), 1, 0, false).is_ok());
    }
}
