//! A grid field uploaded to the GPU, laid out for `shaders/field/grid.wgsl`:
//! a uniform block of bounds and sizes, the nodes as `vec4<f32>` (r, g, b,
//! σ), the occupancy cells as u32, and, with view-dependent colour, each
//! node's further coefficients in a binding of their own as f16
//! ([`super::sh_half`], node-major). A field whose nodes do not fit one
//! storage binding is stored sparsely ([`super::bricks`]): only its
//! non-zero bricks, their table after the occupancy cells.

use std::sync::Arc;

use glam::UVec3;
use inlay_engine::graph::{BufferHandle, Dispatch, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, Context, DeviceInfo};

use super::bricks::{BrickLayout, BRICK_SIDE};
use super::grid::GridField;
use super::sh_half::{pack_sh, sh_first_count, sh_unscale, split_sh, SH_HALF_BYTES};

inlay_engine::gpu_struct! {
    /// `GridInfo` of `shaders/field/grid.wgsl` (the uniform block).
    pub struct GridInfo = "field/grid.wgsl" : "GridInfo" {
        /// The bounds' smallest corner.
        pub bounds_min: [f32; 3],
        /// Nodes per occupancy cell side.
        pub occupancy_block: u32,
        /// The bounds' largest corner.
        pub bounds_max: [f32; 3],
        /// Degree of the view-dependent colour (0: none).
        pub sh_degree: u32,
        /// Nodes per axis.
        pub resolution: [u32; 3],
        /// What the stored halves of the further coefficients are
        /// multiplied by ([`super::sh_half::sh_unscale`]).
        pub sh_unscale: f32,
        /// Occupancy cells per axis.
        pub occupancy_dims: [u32; 3],
        /// Padding.
        pub _pad2: u32,
        /// Bricks per axis of a sparse field (0: dense).
        pub brick_dims: [u32; 3],
        /// Padding.
        pub _pad3: u32,
    }
}

/// The define (bool) that tells the field's shaders that the field may be
/// sparse: false leaves the brick lookup out of every pipeline, so a dense
/// field costs nothing for it.
pub const SPARSE_DEFINE: &str = "FIELD_SPARSE";

/// How a field's nodes are laid out on the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldLayout {
    /// Every node, in grid order.
    Dense,
    /// Only the non-zero bricks ([`super::bricks`]).
    Sparse,
    /// Dense where it fits the device, else sparse.
    Auto,
}

/// The define (bool) that tells the march whether the field it reads may
/// have view-dependent colour: false leaves the code that evaluates it out
/// of every pipeline, so a field without it costs nothing for it.
pub const VIEW_DEPENDENT_DEFINE: &str = "FIELD_VIEW_DEPENDENT";

/// Whether passes compiled from `lib` may march view-dependent colour
/// (its [`VIEW_DEPENDENT_DEFINE`] is not false): what a sample costs them
/// in loop iterations ([`crate::march::MarchKnobs::loop_iterations`]).
pub fn library_marches_view_dependent(lib: &ShaderLibrary) -> bool {
    lib.define(VIEW_DEPENDENT_DEFINE) != Some(&Define::Bool(VIEW_DEPENDENT_DEFINE, false))
}

/// `lib` for passes over any field: the march evaluates view-dependent
/// colour where the field has it (checked per sample). What
/// [`crate::shaders::library`] gives.
pub fn general_field_library(lib: &ShaderLibrary) -> ShaderLibrary {
    lib.with_defines(&[
        Define::Bool(VIEW_DEPENDENT_DEFINE, true),
        Define::Bool(SPARSE_DEFINE, true),
        Define::Bool(crate::march::SH_CORNER_LOOP_DEFINE, false),
    ])
}

/// Device copies of a grid field's data (bindings 0, 1, 2 and 31 of set
/// 0).
/// Clones share the device buffers (several views of one upload).
#[derive(Clone)]
pub struct GpuGridField {
    info: Arc<Buffer>,
    nodes: Arc<Buffer>,
    occupancy: Arc<Buffer>,
    sh: Arc<Buffer>,
    sh_rest: Arc<Buffer>,
    /// Bounds diagonal, for step sizes.
    pub diagonal: f64,
    /// The field's bounds.
    pub bounds: crate::geometry::Aabb,
    /// Nodes per axis.
    pub resolution: glam::UVec3,
    /// The light sources inside the field, brightest first
    /// ([`super::find_emitters`], found once at upload).
    pub emitters: Vec<super::FieldEmitter>,
    /// Degree of the view-dependent colour (0: none).
    pub sh_degree: u32,
    /// Whether its nodes are stored sparsely.
    pub sparse: bool,
    /// Bytes its nodes and further coefficients take on the device.
    pub node_bytes: u64,
    /// The sky learnt with it, drawn behind every frame
    /// ([`crate::sky_behind`]; None: black behind the field).
    pub sky: Option<Arc<super::Sky>>,
    /// The lights its photographs saw past its bounds, drawn with every
    /// frame ([`crate::sky_behind`]).
    pub seen_lights: Arc<Vec<super::SeenLight>>,
}

/// A field on the device, as [`GpuGridField::identity`] gives it: equal
/// when it is the same upload.
#[derive(Clone)]
pub struct FieldIdentity(Arc<Buffer>);

impl PartialEq for FieldIdentity {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl std::fmt::Debug for FieldIdentity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FieldIdentity({:p})", Arc::as_ptr(&self.0))
    }
}

/// The field's buffers as imported into one frame's graph.
#[derive(Debug, Clone, Copy)]
pub struct GridBindings {
    /// `grid_info` (uniform).
    pub info: BufferHandle,
    /// `grid_nodes` (storage, read).
    pub nodes: BufferHandle,
    /// `grid_occupancy` (storage, read).
    pub occupancy: BufferHandle,
    /// `grid_sh` (storage, read): the first half of each node's further
    /// coefficients (a word of padding when the field has no
    /// view-dependent colour).
    pub sh: BufferHandle,
    /// `grid_sh_rest` (storage, read): the rest of them.
    pub sh_rest: BufferHandle,
    /// Degree of the field's view-dependent colour.
    pub sh_degree: u32,
    /// Whether the field is stored sparsely.
    pub sparse: bool,
}

impl GridBindings {
    /// Binds the five buffers for reading on a dispatch (by their names in
    /// `shaders/field/grid.wgsl`).
    ///
    /// Panics if the dispatch's pipeline was compiled for fields without
    /// view-dependent colour or for dense fields ([`GpuGridField::library`]
    /// of another field) and this field has it or is sparse: it would be
    /// read wrong.
    pub fn bind<'p, 'g>(&self, dispatch: Dispatch<'p, 'g>) -> Dispatch<'p, 'g> {
        assert!(
            self.sh_degree == 0
                || dispatch.pipeline().define(VIEW_DEPENDENT_DEFINE)
                    != Some(&Define::Bool(VIEW_DEPENDENT_DEFINE, false)),
            "a pass compiled for fields without view-dependent colour was given one of degree {}",
            self.sh_degree
        );
        assert!(
            !self.sparse
                || dispatch.pipeline().define(SPARSE_DEFINE)
                    != Some(&Define::Bool(SPARSE_DEFINE, false)),
            "a pass compiled for dense fields was given a sparse one"
        );
        dispatch
            .read("grid_info", self.info)
            .read("grid_nodes", self.nodes)
            .read("grid_occupancy", self.occupancy)
            .read("grid_sh", self.sh)
            .read("grid_sh_rest", self.sh_rest)
    }
}

/// How a field's nodes are held on the device, which decides the bytes a
/// node takes in each storage binding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeStorage {
    /// For rendering ([`GpuGridField`]): (r, g, b, σ) as f32 in one
    /// binding, the further coefficients as f16 in two more (each node's
    /// first half in one, the rest in the other,
    /// [`super::sh_half::split_sh`]).
    Render,
    /// For training (`crate::train`): values, gradient and Adam's moments
    /// each one binding of f32 (r, g, b, σ) and one binding a further
    /// coefficient, (r, g, b, 0) f32 (`crate::train::sh_pages`); a check
    /// sees one of the four.
    Training,
}

impl NodeStorage {
    /// Bytes a node of a field of `sh_degree` takes in each binding.
    pub fn bytes_per_node(self, sh_degree: u32) -> Vec<u64> {
        let k = super::sh_extra_coefficients(sh_degree) as u64;
        match self {
            Self::Render if k == 0 => vec![16],
            Self::Render => {
                let first = sh_first_count(k as usize) as u64;
                vec![16, SH_HALF_BYTES * first, SH_HALF_BYTES * (k - first)]
            }
            Self::Training => vec![16; 1 + k as usize],
        }
    }
}

/// Fails, naming the limit and what to change, unless a field of
/// `resolution` nodes with colour of `sh_degree` fits the device dense, held
/// as `storage` says: each of its arrays in one storage binding and all of
/// them in the largest device heap. Whether the upload and the trainer
/// need the sparse layout; before the nodes are known,
/// [`check_field_may_fit`].
pub fn check_field_fits(
    info: &DeviceInfo,
    resolution: UVec3,
    sh_degree: u32,
    storage: NodeStorage,
) -> anyhow::Result<()> {
    check_nodes_fit(info, resolution, sh_degree, storage, None)
}

/// Fails unless a field of `resolution` nodes with colour of `sh_degree`
/// could fit `info`'s largest memory heap held as `storage` says; it may
/// still need the sparse layout to fit one storage binding, which only its
/// nodes tell ([`GpuGridField::upload`] checks that). For checks before a
/// bake or a file is read, where the sparse layout is unknown.
pub fn check_field_may_fit(
    info: &DeviceInfo,
    resolution: UVec3,
    sh_degree: u32,
    storage: NodeStorage,
) -> anyhow::Result<()> {
    let per_node: u64 = storage.bytes_per_node(sh_degree).iter().sum();
    let all = resolution.as_u64vec3().element_product();
    let heap = (info.device_heap_bytes, "largest memory heap");
    check_bytes_within(
        info,
        resolution,
        sh_degree,
        None,
        per_node * all,
        per_node,
        heap,
    )
}

/// Fails unless a field of `resolution` nodes with colour of `sh_degree`,
/// stored sparsely with `pool` nodes in its kept bricks, fits the device
/// held as `storage` says: each array in one binding, all in the heap.
/// What a sparse field file's header allows checking before it is read.
pub fn check_sparse_field_fits(
    info: &DeviceInfo,
    resolution: UVec3,
    sh_degree: u32,
    storage: NodeStorage,
    pool: u64,
) -> anyhow::Result<()> {
    check_nodes_fit(info, resolution, sh_degree, storage, Some(pool))
}

fn degree_words(sh_degree: u32) -> String {
    if sh_degree > 0 {
        format!(" with view-dependent colour of degree {sh_degree}")
    } else {
        String::new()
    }
}

/// [`check_field_fits`] for the layout that holds `pool` of the
/// resolution's nodes (None: all of them, dense): each binding, then the
/// heap.
fn check_nodes_fit(
    info: &DeviceInfo,
    resolution: UVec3,
    sh_degree: u32,
    storage: NodeStorage,
    pool: Option<u64>,
) -> anyhow::Result<()> {
    let nodes = pool.unwrap_or(resolution.as_u64vec3().element_product());
    let per_binding = storage.bytes_per_node(sh_degree);
    let binding = (
        info.max_storage_buffer_range as u64,
        "largest storage binding",
    );
    for &b in &per_binding {
        check_bytes_within(info, resolution, sh_degree, pool, b * nodes, b, binding)?;
    }
    let all: u64 = per_binding.iter().sum();
    let heap = (info.device_heap_bytes, "largest memory heap");
    check_bytes_within(info, resolution, sh_degree, pool, all * nodes, all, heap)
}

/// Fails, naming `limit` (bytes, what it is), when `bytes` (`per_node` a
/// node) of `pool` of the resolution's nodes (None: all) exceed it.
fn check_bytes_within(
    info: &DeviceInfo,
    resolution: UVec3,
    sh_degree: u32,
    pool: Option<u64>,
    bytes: u64,
    per_node: u64,
    (limit, what): (u64, &str),
) -> anyhow::Result<()> {
    if bytes <= limit {
        return Ok(());
    }
    let all = resolution.as_u64vec3().element_product();
    let stored = match pool {
        Some(p) => format!(
            ", stored sparsely ({:.0} % of them in non-zero bricks),",
            100.0 * p as f64 / all as f64
        ),
        None => String::new(),
    };
    anyhow::bail!(
        "the field's {}x{}x{} nodes{}{stored} take {} MiB, more than {}'s {what} \
         ({} MiB); use a field of at most {} nodes",
        resolution.x,
        resolution.y,
        resolution.z,
        degree_words(sh_degree),
        bytes >> 20,
        info.name,
        limit >> 20,
        limit / per_node.max(1)
    )
}

/// The field's values in the trainer's order (`GpuTrainer::values`):
/// (r, g, b, σ) per node, then each node's further colour coefficients as
/// (r, g, b, 0).
pub fn device_values(field: &GridField) -> Vec<[f32; 4]> {
    field
        .nodes
        .iter()
        .copied()
        .chain(field.sh.iter().map(|c| [c[0], c[1], c[2], 0.0]))
        .collect()
}

impl GpuGridField {
    /// Uploads `field`, dense where it fits the device and sparse where
    /// only that fits ([`FieldLayout::Auto`]). Fails with a clear message
    /// when neither does ([`check_field_fits`]).
    pub fn upload(ctx: &Arc<Context>, field: &GridField) -> anyhow::Result<Self> {
        Self::upload_as(ctx, field, FieldLayout::Auto)
    }

    /// Uploads `field` in `layout`.
    pub fn upload_as(
        ctx: &Arc<Context>,
        field: &GridField,
        layout: FieldLayout,
    ) -> anyhow::Result<Self> {
        let render = NodeStorage::Render;
        let dense_fits = check_field_fits(ctx.info(), field.resolution, field.sh_degree, render);
        let bricks = match (layout, dense_fits) {
            (FieldLayout::Dense, fits) => {
                fits?;
                None
            }
            (FieldLayout::Auto, Ok(())) => None,
            (FieldLayout::Sparse | FieldLayout::Auto, _) => {
                let bricks = BrickLayout::of(field);
                check_nodes_fit(
                    ctx.info(),
                    field.resolution,
                    field.sh_degree,
                    render,
                    Some(bricks.pool_nodes()),
                )?;
                Some(bricks)
            }
        };
        let b = field.bounds;
        let occ = &field.occupancy;
        let unscale = sh_unscale(&field.sh);
        let info = GridInfo {
            bounds_min: b.min.as_vec3().to_array(),
            occupancy_block: occ.block,
            bounds_max: b.max.as_vec3().to_array(),
            sh_degree: field.sh_degree,
            resolution: field.resolution.to_array(),
            sh_unscale: unscale,
            occupancy_dims: occ.dims.to_array(),
            _pad2: 0,
            brick_dims: bricks.as_ref().map_or([0; 3], |l| l.dims.to_array()),
            _pad3: 0,
        };
        let (mut values, sh) = match &bricks {
            Some(l) => l.pool_values(field),
            None => (field.nodes.clone(), field.sh.clone()),
        };
        if values.is_empty() {
            values.push([0.0; 4]); // a field with no bricks: a buffer is never empty
        }
        let nodes: Vec<u8> = bytemuck::cast_slice(&values).to_vec();
        let count = super::sh_extra_coefficients(field.sh_degree);
        let (first, rest) = split_sh(&sh, count);
        let (sh_words, rest_words) = (pack_sh(&first, unscale), pack_sh(&rest, unscale));
        if let Some(l) = &bricks {
            log::info!(
                "field stored sparsely: {} of {} bricks of {BRICK_SIDE}³ nodes, {} MiB (dense: {} MiB)",
                l.slots,
                l.table.len(),
                (nodes.len() + 4 * (sh_words.len() + rest_words.len())) >> 20,
                (render.bytes_per_node(field.sh_degree).iter().sum::<u64>()
                    * field.nodes.len() as u64)
                    >> 20
            );
        }
        let table = bricks.as_ref().map_or(&[][..], |l| &l.table[..]);
        let cells: Vec<u8> = occ
            .cells
            .iter()
            .chain(table)
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            info: Arc::new(Buffer::with_data(
                ctx,
                "grid-info",
                bytemuck::bytes_of(&info),
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )?),
            nodes: Arc::new(Buffer::with_data(ctx, "grid-nodes", &nodes, storage)?),
            occupancy: Arc::new(Buffer::with_data(ctx, "grid-occupancy", &cells, storage)?),
            sh: Arc::new(Buffer::with_data(
                ctx,
                "grid-sh",
                bytemuck::cast_slice(&sh_words),
                storage,
            )?),
            sh_rest: Arc::new(Buffer::with_data(
                ctx,
                "grid-sh-rest",
                bytemuck::cast_slice(&rest_words),
                storage,
            )?),
            diagonal: field.bounds.diagonal(),
            bounds: field.bounds,
            resolution: field.resolution,
            emitters: super::find_emitters(field),
            sh_degree: field.sh_degree,
            sparse: bricks.is_some(),
            node_bytes: (nodes.len() + 4 * (sh_words.len() + rest_words.len())) as u64,
            sky: None,
            seen_lights: Arc::new(Vec::new()),
        })
    }

    /// The same field with `sky` behind it (None: black).
    pub fn with_sky(mut self, sky: Option<Arc<super::Sky>>) -> Self {
        self.sky = sky;
        self
    }

    /// The same field with `lights` seen past its bounds.
    pub fn with_seen_lights(mut self, lights: Vec<super::SeenLight>) -> Self {
        self.seen_lights = Arc::new(lights);
        self
    }

    /// `lib` for the passes that read this field: with
    /// [`VIEW_DEPENDENT_DEFINE`] false when it has no view-dependent
    /// colour (the march leaves that code out), true when it has.
    pub fn library(&self, lib: &ShaderLibrary) -> ShaderLibrary {
        lib.with_defines(&[
            Define::Bool(VIEW_DEPENDENT_DEFINE, self.sh_degree > 0),
            Define::Bool(SPARSE_DEFINE, self.sparse),
        ])
    }

    /// What tells this field apart from any other on the device (it keeps
    /// the field's node buffer alive, so no later field can take its
    /// place): a cache of something rendered from it compares these.
    pub fn identity(&self) -> FieldIdentity {
        FieldIdentity(self.nodes.clone())
    }

    /// Imports the buffers into a frame's graph (read-only).
    pub fn import(&self, graph: &mut FrameGraph) -> GridBindings {
        GridBindings {
            info: graph.import_buffer(&self.info, None),
            nodes: graph.import_buffer(&self.nodes, None),
            occupancy: graph.import_buffer(&self.occupancy, None),
            sh: graph.import_buffer(&self.sh, None),
            sh_rest: graph.import_buffer(&self.sh_rest, None),
            sh_degree: self.sh_degree,
            sparse: self.sparse,
        }
    }
}
