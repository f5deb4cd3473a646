//! Shadow data on the GPU: an object's compressed SSDF field, the f_h
//! table, the per-frame object block (`SsdfObject` in
//! `shaders/ssdf/ssdf.wgsl`) and the defines every shadow shader needs.

use std::sync::Arc;

use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::Define;
use inlay_engine::{vk, Buffer, Context};

use super::fh::{FhTable, FH_COLUMNS, FH_ROWS, FH_SHARPNESS_RANGE};
use super::ObjectReflectance;
use crate::object::{ObjectMesh, ObjectRecords, PlacedObject};
use crate::ssdf::bake::MAX_SSDF_COMPONENTS;
use crate::ssdf::field::{OutsideMode, SsdfField};

inlay_engine::gpu_struct! {
    /// `SsdfObject` of `shaders/ssdf/ssdf.wgsl` (checked through the cast
    /// shadow, which binds it): an object's SSDF as one
    /// frame reads it.
    pub struct SsdfObject = "shadow/cast.wgsl" : "SsdfObject" {
        /// Grid centre (object space) and bounding-sphere radius.
        pub grid: [f32; 4],
        /// Nodes per axis, direction map side, components, outside mode.
        pub dims: [u32; 4],
        /// Silhouette fill times albedo (rgb) and the fill alone (w).
        pub reflectance: [f32; 4],
        /// The object's record in the frame's [`ObjectRecords`] (its pose).
        pub object: u32,
        /// Padding (the struct's size rounds up to 16 bytes).
        pub _pad: [u32; 3],
    }
}

/// The defines of `shadow/fh.wgsl`, `shadow/cone.wgsl`, `ssdf/ssdf.wgsl`
/// and `shadow/cast_body.wgsl`.
pub fn shadow_defines() -> Vec<Define> {
    vec![
        Define::U32("FH_COLUMNS", FH_COLUMNS),
        Define::U32("FH_ROWS", FH_ROWS),
        Define::F32("FH_SHARPNESS_MIN", FH_SHARPNESS_RANGE.0 as f32),
        Define::F32("FH_SHARPNESS_MAX", FH_SHARPNESS_RANGE.1 as f32),
        Define::U32("SSDF_MAX_COMPONENTS", MAX_SSDF_COMPONENTS),
        Define::U32("MAX_LOCAL_LIGHTS", crate::lighting::local::MAX_LOCAL_LIGHTS),
        Define::U32("CONE_POINTS", super::CONE_POINTS as u32),
        Define::F32("CONE_RESOLUTION", super::CONE_RESOLUTION as f32),
    ]
}

fn storage(ctx: &Arc<Context>, name: &str, values: &[f32]) -> anyhow::Result<Arc<Buffer>> {
    let mut bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.resize(bytes.len().max(16), 0);
    Ok(Arc::new(Buffer::with_data(
        ctx,
        name,
        &bytes,
        vk::BufferUsageFlags::STORAGE_BUFFER,
    )?))
}

/// The f_h table, uploaded once.
pub struct GpuFhTable {
    /// The table (also used by the CPU mirrors).
    pub table: FhTable,
    buffer: Arc<Buffer>,
}

impl GpuFhTable {
    /// Tabulates and uploads.
    pub fn new(ctx: &Arc<Context>) -> anyhow::Result<Self> {
        let table = FhTable::new();
        let buffer = storage(ctx, "fh table", table.values())?;
        Ok(Self { table, buffer })
    }

    /// The buffer in `graph`.
    pub fn import(&self, graph: &mut FrameGraph) -> BufferHandle {
        graph.import_buffer(&self.buffer, None)
    }
}

/// An object's shadow geometry on the GPU: its SSDF field, and its mesh
/// in a bounding-volume hierarchy for the direct lobes' ray-cast shadows
/// ([`super::direct`]), both in the object's own frame.
pub struct GpuSsdf {
    /// The field (for the CPU mirrors and the per-frame block).
    pub field: Arc<SsdfField>,
    rows: Arc<Buffer>,
    coefs: Arc<Buffer>,
    bvh_nodes: Arc<Buffer>,
    bvh_triangles: Arc<Buffer>,
    /// How much of its bounding sphere the mesh fills, with what albedo
    /// (the light it sends back onto the field, [`super::bounce`]).
    pub reflectance: super::ObjectReflectance,
}

/// A [`GpuSsdf`]'s buffers in one frame's graph.
#[derive(Debug, Clone, Copy)]
pub struct SsdfBindings {
    /// The per-frame `SsdfObject` block (read-only storage; see
    /// shaders/ssdf/ssdf.wgsl for why not uniform).
    pub object: BufferHandle,
    /// The frame's object records (the object's pose is one of them).
    pub records: BufferHandle,
    /// Per texel: mean and basis.
    pub rows: BufferHandle,
    /// Per node: coefficients.
    pub coefs: BufferHandle,
    /// The mesh's hierarchy: nodes (`shaders/geometry/mesh_bvh.wgsl`).
    pub bvh_nodes: BufferHandle,
    /// The mesh's hierarchy: triangles.
    pub bvh_triangles: BufferHandle,
}

impl GpuSsdf {
    /// Uploads `field` and the hierarchy of `mesh` (the mesh it was baked
    /// from); fails with a clear message when the mesh's triangles exceed
    /// the device's largest storage binding.
    pub fn upload(
        ctx: &Arc<Context>,
        field: Arc<SsdfField>,
        mesh: &Arc<ObjectMesh>,
    ) -> anyhow::Result<Self> {
        let (nodes, triangles) = crate::ssdf::object_scene(mesh).packed();
        let limit = ctx.info().max_storage_buffer_range as u64;
        let bytes = triangles.len() as u64 * 4;
        anyhow::ensure!(
            bytes <= limit,
            "object `{}`: its {} triangles take {} MiB for the shadow rays, beyond this \
             device's largest storage binding ({} MiB): simplify the mesh",
            mesh.name,
            triangles.len() / 12,
            bytes >> 20,
            limit >> 20
        );
        Ok(Self {
            rows: storage(ctx, "ssdf rows", &field.texel_rows)?,
            coefs: storage(ctx, "ssdf coefficients", &field.coefficients)?,
            bvh_nodes: storage(ctx, "shadow bvh nodes", &nodes)?,
            bvh_triangles: storage(ctx, "shadow bvh triangles", &triangles)?,
            reflectance: super::ObjectReflectance::measure(mesh),
            field,
        })
    }

    /// Imports the field and uploads this frame's block for `placed`,
    /// whose pose is record `record` of `records`.
    pub fn import(
        &self,
        graph: &mut FrameGraph,
        placed: &PlacedObject,
        (records, record): (ObjectRecords, u32),
        mode: OutsideMode,
    ) -> SsdfBindings {
        let block = object_block(&self.field, placed, record, mode, &self.reflectance);
        SsdfBindings {
            object: graph.upload_buffer("ssdf object", bytemuck::bytes_of(&block).to_vec()),
            records: records.buffer,
            rows: graph.import_buffer(&self.rows, None),
            coefs: graph.import_buffer(&self.coefs, None),
            bvh_nodes: graph.import_buffer(&self.bvh_nodes, None),
            bvh_triangles: graph.import_buffer(&self.bvh_triangles, None),
        }
    }
}

/// The `SsdfObject` block: grid, dims, the object's silhouette reflectance
/// ([`ObjectReflectance::of`]) and fill, and the index of its pose in the
/// frame's object records.
pub fn object_block(
    field: &SsdfField,
    placed: &PlacedObject,
    record: u32,
    mode: OutsideMode,
    object: &ObjectReflectance,
) -> SsdfObject {
    let g = &field.grid;
    SsdfObject {
        grid: g.centre.extend(g.radius).as_vec4().to_array(),
        dims: [g.nodes, field.directions, field.components, mode.index()],
        reflectance: object.of(placed).extend(object.fill).as_vec4().to_array(),
        object: record,
        _pad: [0; 3],
    }
}
