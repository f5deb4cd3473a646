//! The SG fit on the GPU (`shaders/sgfit/fit.wgsl`): one graph pass,
//! `sg-fit`, recording the cold start, the start selection and the
//! iterations as successive dispatches. The current lobes and the fit's
//! state (cost, damping, residual log) persist across frames for the warm
//! start; the features, their Gram matrix, the normal matrix and the solver
//! workspace are transient.

use crate::frame::meta::{PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{BufferAccess, BufferHandle, FrameGraph, ImageAccess, ImageHandle};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, ComputePipeline, Context};

use super::knobs::{FitKnobs, MAX_ITERATIONS};
use super::model;
use super::reference::relative_residual;
use crate::probe::{DirectionMap, MapKind};
use crate::sg::Sg32;

inlay_engine::gpu_struct! {
    /// `FitPush` of `shaders/sgfit/fit.wgsl`.
    pub struct FitPush = "sgfit/fit.wgsl" : "FitPush" {
        /// Probe texels across.
        pub width: u32,
        /// Probe texels down.
        pub height: u32,
        /// Lobes M.
        pub lobe_count: u32,
        /// Normal-matrix columns (6M + 1 rounded up to 16).
        pub cols: u32,
        /// Feature-matrix rows (texels rounded up to 16).
        pub rows: u32,
        /// Which lobe slot a kernel works on (1: current, 2: candidate).
        pub slot: u32,
        /// Warm start (1) or cold (0).
        pub warm: u32,
        /// Cost-partial workgroups.
        pub groups: u32,
        /// Initial LM damping.
        pub damping: f32,
        /// Feature-matrix columns (4M + 3 rounded up to 16).
        pub feature_cols: u32,
        /// Padding.
        pub pad1: u32,
        /// Padding.
        pub pad2: u32,
    }
}

/// The sg-fit pass: its name, Table 1 module and effect switch.
pub const SG_FIT_INFO: PassInfo = PassInfo {
    name: "sg-fit",
    module: Table1Module::SgUpdating,
    switch: None,
};

/// The SG fit's name in the frame graph (and in timings and traces).
pub const SG_FIT: &str = SG_FIT_INFO.name;

/// Where a GPU fit starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitStart {
    /// From the cold-start initialisation.
    Cold,
    /// From the lobes of the previous fit, unless the cold start fits better.
    Warm,
    /// Going on with the previous fit on the same probe: its iterate, cost
    /// and damping stand (a fit spread over several frames takes the same
    /// steps as in one).
    Continue,
}

/// Slots of M lobes in the lobe buffer: what shading reads (the iterate
/// with its energy conserved), the fit's iterate, its candidate step.
const SLOTS: u64 = 3;
/// The slot of the fit's iterate (`SLOT_CURRENT` in the shader).
const SLOT_CURRENT: u32 = 1;
/// The slot of the candidate step (`SLOT_CANDIDATE` in the shader).
const SLOT_CANDIDATE: u32 = 2;

/// Entries of the fit's cost log: the start and every iteration.
const LOG_LENGTH: usize = MAX_ITERATIONS as usize + 1;

inlay_engine::gpu_struct! {
    /// The fit's state buffer, `FitState` of `shaders/sgfit/fit.wgsl`: its
    /// scalars (kept across frames for the warm start) and its cost log.
    pub struct FitState = "sgfit/fit.wgsl" : "FitState" {
        /// The current lobes' cost.
        pub cost: f32,
        /// The Levenberg–Marquardt damping.
        pub damping: f32,
        /// Whether the current lobes' normal equations are still valid (0/1).
        pub normal_valid: f32,
        /// The probe's energy.
        pub energy: f32,
        /// Texels with a non-finite value, left out of the fit.
        pub invalid: f32,
        /// Whether the fit started from the cold start (0/1).
        pub started_cold: f32,
        /// Iterations run.
        pub iterations: f32,
        /// Candidates accepted.
        pub accepted: f32,
        /// The cold start's cost.
        pub cold_cost: f32,
        /// The warm start's cost (−1 when cold).
        pub warm_cost: f32,
        /// Whether the last candidate solved (0/1).
        pub candidate_ok: f32,
        /// The cost at the start and after each iteration.
        pub log: [f32; LOG_LENGTH],
    }
}

/// What the last GPU fit reported (read back after its frame).
#[derive(Debug, Clone)]
pub struct FitReport {
    /// The fitted lobes, as shading reads them (energy conserved).
    pub lobes: Vec<Sg32>,
    /// The fit's iterate (what a warm start or a continued fit goes on
    /// from).
    pub iterate: Vec<Sg32>,
    /// Cost after each iteration (index 0: at the start).
    pub costs: Vec<f64>,
    /// Σ w |L|² of the probe.
    pub energy: f64,
    /// Whether the fit started cold.
    pub started_cold: bool,
    /// Accepted steps.
    pub accepted: u32,
    /// Probe texels ignored as NaN, infinite or negative.
    pub invalid: u32,
    /// Damping at the end.
    pub damping: f64,
}

impl FitReport {
    /// The final relative residual √(cost / energy).
    pub fn relative_residual(&self) -> f64 {
        relative_residual(*self.costs.last().unwrap_or(&0.0), self.energy)
    }
}

struct Kernels {
    filter_probe: Arc<ComputePipeline>,
    init_cold: Arc<ComputePipeline>,
    cost: Arc<ComputePipeline>,
    select_start: Arc<ComputePipeline>,
    features: Arc<ComputePipeline>,
    gram_blocks: Arc<ComputePipeline>,
    assemble: Arc<ComputePipeline>,
    solve_channels: Arc<ComputePipeline>,
    solve_schur: Arc<ComputePipeline>,
    solve_nonlinear: Arc<ComputePipeline>,
    decide: Arc<ComputePipeline>,
    resume: Arc<ComputePipeline>,
    conserve_energy: Arc<ComputePipeline>,
}

/// Sizes derived from the knobs and the probe.
#[derive(Debug, Clone, Copy)]
struct Shape {
    cols: u32,
    rows: u32,
    feature_cols: u32,
    groups: u32,
}

/// The GPU fit for one set of knobs and one probe layout.
pub struct SgFitPass {
    kernels: Kernels,
    knobs: FitKnobs,
    map: DirectionMap,
    shape: Shape,
    lobes: Arc<Buffer>,
    state: Arc<Buffer>,
    /// The probe filter's rows (`probe_filter::ProbeFilter`), built for the map.
    filter_offsets: Arc<Buffer>,
    filter_entries: Arc<Buffer>,
    lobes_readback: BufferReadback,
    state_readback: BufferReadback,
}

/// Every slot of the lobe buffer holding `lobes` (axes normalised).
fn lobe_bytes_of(lobes: &[Sg32]) -> Vec<u8> {
    let packed: Vec<f32> = lobes
        .iter()
        .flat_map(|g| {
            Sg32 {
                direction: g.direction.normalize_or(glam::Vec3::Y),
                ..*g
            }
            .packed()
        })
        .collect();
    (0..SLOTS)
        .flat_map(|_| packed.iter().flat_map(|f| f.to_le_bytes()))
        .collect()
}

fn round_up(x: u32, m: u32) -> u32 {
    x.div_ceil(m) * m
}

/// The most loop iterations one invocation of the fit's kernels runs
/// ([`crate::march::loop_budget`]): a block of the Gram matrix sums over
/// every texel, and a lobe's cold start gives each of a workgroup's 64
/// invocations its share of the texels, each against every lobe.
fn loop_iterations(texels: u32, lobes: u32) -> u64 {
    let (n, m) = (texels as u64, lobes as u64);
    n.max(n.div_ceil(64) * (m + 2) + m + 32)
}

impl SgFitPass {
    /// Compiles the kernels and creates the persistent buffers; fails with
    /// a clear message when the feature matrix would not fit one storage
    /// binding.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        knobs: FitKnobs,
        map: DirectionMap,
    ) -> anyhow::Result<Self> {
        knobs
            .check()
            .map_err(|(k, m)| anyhow::anyhow!("fit knob `{k}`: {m}"))?;
        let texels = map.texels() as u32;
        crate::march::loop_budget::check_loop_budget(
            ctx,
            SG_FIT,
            loop_iterations(texels, knobs.lobes),
            || {
                format!(
                    "{} probe texels (`[lighting] probe_resolution` {}), `[lighting] lobes` {}",
                    texels,
                    map.width.min(map.height),
                    knobs.lobes
                )
            },
        )?;
        let shape = Shape {
            cols: round_up(knobs.parameters() as u32 + 1, 16),
            rows: round_up(texels, 16),
            feature_cols: round_up(
                (model::FEATURES_PER_LOBE * knobs.lobes as usize + 3) as u32,
                16,
            ),
            groups: texels.div_ceil(64),
        };
        let feature_bytes = shape.rows as u64 * shape.feature_cols as u64 * 4;
        let limit = ctx.info().max_storage_buffer_range as u64;
        if feature_bytes > limit {
            anyhow::bail!(
                "the fit's feature matrix ({} rows × {} columns, {} MiB) exceeds this device's \
                 largest storage binding ({} MiB): lower the probe resolution or the lobe count",
                shape.rows,
                shape.feature_cols,
                feature_bytes >> 20,
                limit >> 20
            );
        }
        let defines = [
            Define::Bool("OCTAHEDRAL", map.kind == MapKind::Octahedral),
            Define::F32(
                "FIT_MAX_SHARPNESS",
                super::model::max_sharpness(map.texels()) as f32,
            ),
        ];
        let build = |entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, "sgfit/fit.wgsl", entry, &defines)?)
        };
        let kernels = Kernels {
            filter_probe: build("filter_probe")?,
            init_cold: build("init_cold")?,
            cost: build("cost")?,
            select_start: build("select_start")?,
            features: build("texel_features")?,
            gram_blocks: build("gram_blocks")?,
            assemble: build("assemble")?,
            solve_channels: build("solve_channels")?,
            solve_schur: build("solve_schur")?,
            solve_nonlinear: build("solve_nonlinear")?,
            decide: build("decide")?,
            resume: build("resume")?,
            conserve_energy: build("conserve_energy")?,
        };
        let lobe_bytes = SLOTS * knobs.lobes as u64 * 32;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        // Before any fit: legal, dark lobes (a warm start from them is a
        // fit of nothing, which the cold start beats on any lit probe).
        let dark: Vec<Sg32> = (0..knobs.lobes)
            .map(|k| Sg32 {
                direction: model::fibonacci_axis(k, knobs.lobes).as_vec3(),
                sharpness: model::initial_sharpness(knobs.lobes) as f32,
                amplitude: glam::Vec3::ZERO,
            })
            .collect();
        let lobes = Buffer::with_data(ctx, "sg-lobes", &lobe_bytes_of(&dark), usage)?;
        let filter = super::probe_filter::ProbeFilter::new(&map);
        let offsets: Vec<u8> = filter
            .offsets
            .iter()
            .flat_map(|o| o.to_le_bytes())
            .collect();
        let entries: Vec<u8> = filter
            .entries
            .iter()
            .flat_map(|&(s, w)| [s.to_le_bytes(), (w as f32).to_le_bytes()])
            .flatten()
            .collect();
        let read_only = vk::BufferUsageFlags::STORAGE_BUFFER;
        let filter_offsets = Buffer::with_data(ctx, "sg-fit-filter-offsets", &offsets, read_only)?;
        let filter_entries = Buffer::with_data(ctx, "sg-fit-filter-entries", &entries, read_only)?;
        let state_bytes = std::mem::size_of::<FitState>() as u64;
        let state = Buffer::with_data(
            ctx,
            "sg-fit-state",
            bytemuck::bytes_of(&<FitState as bytemuck::Zeroable>::zeroed()),
            usage,
        )?;
        Ok(Self {
            kernels,
            knobs,
            map,
            shape,
            lobes: Arc::new(lobes),
            state: Arc::new(state),
            filter_offsets: Arc::new(filter_offsets),
            filter_entries: Arc::new(filter_entries),
            lobes_readback: BufferReadback::new(ctx, "sg-lobes (readback)", lobe_bytes)?,
            state_readback: BufferReadback::new(ctx, "sg-fit-state (readback)", state_bytes)?,
        })
    }

    /// The knobs it was built for.
    pub fn knobs(&self) -> &FitKnobs {
        &self.knobs
    }

    /// The persistent lobe buffer: M shading lobes (two vec4 each: (p, λ),
    /// (μ, 0)), then the fit's M current and M candidate lobes. Shading
    /// passes read the first M.
    pub fn lobes(&self) -> &Arc<Buffer> {
        &self.lobes
    }

    /// Replaces the lobes, every slot (the next warm start begins from them).
    pub fn set_lobes(&mut self, ctx: &Arc<Context>, lobes: &[Sg32]) -> anyhow::Result<()> {
        anyhow::ensure!(
            lobes.len() == self.knobs.lobes as usize,
            "{} lobes given to a fit of {}",
            lobes.len(),
            self.knobs.lobes
        );
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        self.lobes = Arc::new(Buffer::with_data(
            ctx,
            "sg-lobes",
            &lobe_bytes_of(lobes),
            usage,
        )?);
        Ok(())
    }

    fn push(&self, slot: u32, warm: bool) -> FitPush {
        FitPush {
            width: self.map.width,
            height: self.map.height,
            lobe_count: self.knobs.lobes,
            cols: self.shape.cols,
            rows: self.shape.rows,
            slot,
            warm: warm as u32,
            groups: self.shape.groups,
            damping: self.knobs.damping as f32,
            feature_cols: self.shape.feature_cols,
            pad1: 0,
            pad2: 0,
        }
    }

    /// Adds the `sg-fit` pass fitting the lobes to `probe` (an image laid
    /// out by this pass's direction map) from `start` for `iterations`
    /// iterations; returns the lobe buffer as written. A continued fit
    /// needs the probe the fit it continues began on.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        probe: ImageHandle,
        start: FitStart,
        iterations: u32,
    ) -> anyhow::Result<BufferHandle> {
        anyhow::ensure!(
            iterations <= MAX_ITERATIONS,
            "{iterations} iterations: at most {MAX_ITERATIONS} per fit"
        );
        let s = self.shape;
        let n = self.knobs.parameters() as u64;
        let lobes = graph.import_buffer(&self.lobes, None);
        let state = graph.import_buffer(&self.state, None);
        let graph_offsets = graph.import_buffer(&self.filter_offsets, None);
        let graph_entries = graph.import_buffer(&self.filter_entries, None);
        let partials = graph.create_buffer("sg-fit-partials", 2 * s.groups as u64 * 16);
        let features =
            graph.create_buffer("sg-fit-features", s.rows as u64 * s.feature_cols as u64 * 4);
        let gram = graph.create_buffer(
            "sg-fit-gram",
            s.feature_cols as u64 * s.feature_cols as u64 * 4,
        );
        let normal = graph.create_buffer("sg-fit-normal", s.cols as u64 * s.cols as u64 * 4);
        // The solve's layout (shaders/sgfit/fit.wgsl, "the damped step"):
        // √D, three channels of 4M + 1 rows of M, S and its right-hand
        // side, the step, three flags.
        let m = self.knobs.lobes as u64;
        let work = graph.create_buffer(
            "sg-fit-work",
            (n + 3 * (4 * m + 1) * m + (3 * m + 1) * 3 * m + n + 3) * 4,
        );
        let fitted = graph.create_buffer("sg-fit-probe", self.map.texels() as u64 * 16);
        // The transients are written before they are read within the pass
        // (StorageWrite: no previous content); the lobes and the state
        // carry over from the previous fit.
        let mut pass = graph.compute_pass(SG_FIT);
        pass.image_at("probe", probe, ImageAccess::Sampled);
        let lobes = pass.buffer_at("lobes", lobes, BufferAccess::StorageReadWrite);
        pass.buffer_at("state", state, BufferAccess::StorageReadWrite);
        pass.buffer_at("partials", partials, BufferAccess::StorageWrite);
        pass.buffer_at("features", features, BufferAccess::StorageWrite);
        pass.buffer_at("normal", normal, BufferAccess::StorageWrite);
        pass.buffer_at("work", work, BufferAccess::StorageWrite);
        pass.buffer_at("fitted", fitted, BufferAccess::StorageWrite);
        pass.buffer_at("filter_offsets", graph_offsets, BufferAccess::StorageRead);
        pass.buffer_at("filter_entries", graph_entries, BufferAccess::StorageRead);
        pass.buffer_at("gram", gram, BufferAccess::StorageWrite);
        let warm = start == FitStart::Warm;
        let candidate = self.push(SLOT_CANDIDATE, warm);
        let current = self.push(SLOT_CURRENT, warm);
        let k = &self.kernels;
        let blocks = s.feature_cols / 4;
        let block_groups = (blocks * blocks).div_ceil(64);
        let entries = (n * (n + 1)).div_ceil(64) as u32;
        let q = 3 * self.knobs.lobes;
        let schur_groups = ((q + 1) * q).div_ceil(64);
        let mut run = |p: &Arc<ComputePipeline>, push: &FitPush, groups: [u32; 3]| {
            pass.dispatch(p).push(push).groups(groups)
        };
        run(&k.filter_probe, &candidate, [s.groups, 1, 1]);
        if start == FitStart::Continue {
            run(&k.resume, &candidate, [1, 1, 1]);
        } else {
            run(&k.init_cold, &candidate, [self.knobs.lobes, 1, 1]);
            run(&k.cost, &candidate, [s.groups, 1, 1]);
            if warm {
                run(&k.cost, &current, [s.groups, 1, 1]);
            }
            run(&k.select_start, &candidate, [1, 1, 1]);
        }
        for _ in 0..iterations {
            run(&k.features, &candidate, [s.groups, 1, 1]);
            run(&k.gram_blocks, &candidate, [block_groups, 1, 1]);
            run(&k.assemble, &candidate, [entries, 1, 1]);
            run(&k.solve_channels, &candidate, [3, 1, 1]);
            run(&k.solve_schur, &candidate, [schur_groups, 1, 1]);
            run(&k.solve_nonlinear, &candidate, [1, 1, 1]);
            run(&k.cost, &candidate, [s.groups, 1, 1]);
            run(&k.decide, &candidate, [1, 1, 1]);
        }
        run(&k.conserve_energy, &candidate, [self.knobs.lobes, 1, 1]);
        pass.finish();
        Ok(lobes)
    }

    /// Adds transfer passes copying the lobes and the state to the host;
    /// [`Self::read_report`] reads them once the frame has finished.
    pub fn add_readback(&self, graph: &mut FrameGraph) {
        let lobes = graph.import_buffer(&self.lobes, None);
        let state = graph.import_buffer(&self.state, None);
        self.lobes_readback
            .add_to_graph(graph, "sg-lobes-readback", lobes);
        self.state_readback
            .add_to_graph(graph, "sg-fit-state-readback", state);
    }

    /// The report of the fit whose frame carried [`Self::add_readback`].
    pub fn read_report(&self) -> anyhow::Result<FitReport> {
        let l = self.lobes_readback.read_f32()?;
        let st: FitState = self.state_readback.read_pod()?;
        let m = self.knobs.lobes as usize;
        let slot = |s: usize| {
            (0..m)
                .map(|k| Sg32::unpack(&l[8 * (s * m + k)..8 * (s * m + k) + 8]))
                .collect()
        };
        let (lobes, iterate) = (slot(0), slot(SLOT_CURRENT as usize));
        let iterations = (st.iterations as usize).min(MAX_ITERATIONS as usize);
        Ok(FitReport {
            lobes,
            iterate,
            costs: st.log[..=iterations].iter().map(|&c| c as f64).collect(),
            energy: st.energy as f64,
            started_cold: st.started_cold != 0.0,
            accepted: st.accepted as u32,
            invalid: st.invalid as u32,
            damping: st.damping as f64,
        })
    }
}
