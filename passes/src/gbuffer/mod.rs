//! The object G-buffer pass (`object-gbuffer`, raster with dynamic
//! rendering; METHOD.md §4.4 step 2): every part of every placed object is
//! drawn with its pose and material from a per-frame draw table, writing
//! normal + roughness, base colour + metallic, and the distance along the
//! camera ray with the object's index. The distance feeds the march's
//! clipping; poses and materials change per frame without new pipelines.

mod projection;

pub use projection::view_projection;

use crate::frame::meta::{PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle, LoadOp, SamplerKind};
use inlay_engine::shader::{compile, ShaderLibrary, ShaderStage};
use inlay_engine::{vk, Context, GraphicsDesc, GraphicsPipeline, ImageDesc};

use crate::camera::CameraFrame;
use crate::object::{GpuObject, ObjectRecords, PlacedObject};

inlay_engine::gpu_struct! {
    /// `Camera` of `shaders/gbuffer/gbuffer.wgsl` (uniform).
    pub struct GBufferCamera = "gbuffer/gbuffer.wgsl" : "Camera" {
        /// View-projection, column-major.
        pub view_proj: [f32; 16],
        /// The eye (w = 1).
        pub origin: [f32; 4],
    }
}

inlay_engine::gpu_struct! {
    /// `Draw` of `shaders/gbuffer/gbuffer.wgsl`: one mesh part's record.
    pub struct DrawRecord = "gbuffer/gbuffer.wgsl" : "Draw" {
        /// Base colour factor (RGBA).
        pub base_colour: [f32; 4],
        /// Roughness factor.
        pub roughness: f32,
        /// Metallic factor.
        pub metallic: f32,
        /// The index the part's object writes to the G-buffer.
        pub object_index: f32,
        /// The object's record in the frame's [`ObjectRecords`] (its pose).
        pub record: u32,
    }
}

inlay_engine::gpu_struct! {
    /// `DrawPush` of `shaders/gbuffer/gbuffer.wgsl`.
    pub struct DrawPush = "gbuffer/gbuffer.wgsl" : "DrawPush" {
        /// Index of the draw's record.
        pub draw: u32,
        /// First index of its part in the index buffer.
        pub first_index: u32,
    }
}

/// The object-gbuffer pass: its name, Table 1 module and effect switch.
pub const OBJECT_GBUFFER_INFO: PassInfo = PassInfo {
    name: "object-gbuffer",
    module: Table1Module::Rendering,
    switch: None,
};

/// The G-buffer pass's name in the frame graph (and in timings).
pub const OBJECT_GBUFFER: &str = OBJECT_GBUFFER_INFO.name;

/// Format of the normal + roughness target.
pub const NORMAL_ROUGHNESS_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Format of the base colour + metallic target.
pub const ALBEDO_METALLIC_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Format of the (distance along the ray, object index) target.
pub const DISTANCE_ID_FORMAT: vk::Format = vk::Format::R32G32_SFLOAT;
/// Format of the raster depth buffer.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// What the distance target holds where no object is: the march's
/// "no object" distance and index −1.
pub const EMPTY_DISTANCE_ID: [f32; 4] = [3.0e38, -1.0, 0.0, 0.0];

/// Bytes of one draw record (`Draw` in `shaders/gbuffer/gbuffer.wgsl`).
const DRAW_BYTES: usize = std::mem::size_of::<DrawRecord>();
/// Most draws (object parts) in one frame: the draw table is uploaded from
/// the command buffer, which takes at most 64 KiB.
pub const MAX_DRAWS: usize = 65536 / DRAW_BYTES;

/// What the G-buffer pass writes.
#[derive(Debug, Clone, Copy)]
pub struct GBuffer {
    /// World normal (xyz) and roughness (w).
    pub normal_roughness: ImageHandle,
    /// Base colour (rgb) and metallic (a).
    pub albedo_metallic: ImageHandle,
    /// Distance along the camera ray (r; [`EMPTY_DISTANCE_ID`] where empty)
    /// and object index (g).
    pub distance_id: ImageHandle,
}

/// An object to draw: its placement and its uploaded mesh.
#[derive(Clone, Copy)]
pub struct ObjectDraw<'a> {
    /// Pose, materials.
    pub placed: &'a PlacedObject,
    /// Buffers and textures.
    pub gpu: &'a GpuObject,
    /// Its pose's record in the frame's [`ObjectRecords`].
    pub record: u32,
}

/// The G-buffer pipeline.
pub struct GBufferPass {
    pipeline: Arc<GraphicsPipeline>,
}

impl GBufferPass {
    /// Compiles the pass.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let v = compile(
            lib,
            "gbuffer/gbuffer.wgsl",
            "vs_main",
            ShaderStage::Vertex,
            &[],
        )?;
        let f = compile(
            lib,
            "gbuffer/gbuffer.wgsl",
            "fs_main",
            ShaderStage::Fragment,
            &[],
        )?;
        let desc = GraphicsDesc {
            color_formats: vec![
                NORMAL_ROUGHNESS_FORMAT,
                ALBEDO_METALLIC_FORMAT,
                DISTANCE_ID_FORMAT,
            ],
            depth_format: Some(DEPTH_FORMAT),
            depth_test: true,
            depth_write: true,
            blend: false,
            // Meshes may be open or mirrored: draw both sides.
            cull_back: false,
        };
        Ok(Self {
            pipeline: Arc::new(GraphicsPipeline::new(ctx, &v, &f, &desc)?),
        })
    }

    /// Adds the `object-gbuffer` pass drawing `objects` from `camera`
    /// (object index = position in `objects`), their poses read from
    /// `records`.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        camera: &CameraFrame,
        objects: &[ObjectDraw<'_>],
        records: ObjectRecords,
    ) -> anyhow::Result<GBuffer> {
        let (width, height) = (camera.width, camera.height);
        let spheres: Vec<_> = objects.iter().map(|o| o.placed.sphere()).collect();
        let view_proj = view_projection(camera, &spheres);
        let camera_record = GBufferCamera {
            view_proj: view_proj.as_mat4().to_cols_array(),
            origin: camera.origin.extend(1.0).as_vec4().to_array(),
        };
        // One draw per mesh part, in object order.
        let mut draw_records = Vec::new();
        let mut draws = Vec::new();
        for (index, o) in objects.iter().enumerate() {
            for (p, part) in o.placed.mesh.parts.iter().enumerate() {
                let mat = o.placed.material_of(p);
                draw_records.push(DrawRecord {
                    base_colour: mat.base_colour.as_vec4().to_array(),
                    roughness: mat.roughness as f32,
                    metallic: mat.metallic as f32,
                    object_index: index as f32,
                    record: o.record,
                });
                draws.push((o.gpu, *part, mat));
            }
        }
        anyhow::ensure!(
            draws.len() <= MAX_DRAWS,
            "{} object parts in one frame; the G-buffer draws at most {MAX_DRAWS}",
            draws.len()
        );
        let camera_buffer =
            graph.upload_buffer("object-camera", bytemuck::bytes_of(&camera_record).to_vec());
        let draw_buffer =
            graph.upload_buffer("object-draws", bytemuck::cast_slice(&draw_records).to_vec());
        let target = |graph: &mut FrameGraph, name: &str, format| {
            graph.create_image(
                name,
                ImageDesc {
                    width,
                    height,
                    format,
                },
            )
        };
        let mut nr = target(graph, "gbuffer-normal-roughness", NORMAL_ROUGHNESS_FORMAT);
        let mut am = target(graph, "gbuffer-albedo-metallic", ALBEDO_METALLIC_FORMAT);
        let mut di = target(graph, "gbuffer-distance-id", DISTANCE_ID_FORMAT);
        let mut depth = target(graph, "gbuffer-depth", DEPTH_FORMAT);
        // Imports of one buffer or image return one handle, and the pass
        // declares a resource once however many draws read it.
        let imports: Vec<_> = draws
            .iter()
            .map(|(gpu, part, mat)| {
                let base = gpu.texture(mat.base_colour_texture, true);
                let mr = gpu.texture(mat.metallic_roughness_texture, false);
                (
                    graph.import_buffer(&gpu.vertices, None),
                    graph.import_buffer(&gpu.indices, None),
                    graph.import_image(base, "base-colour texture", None),
                    graph.import_image(mr, "metallic-roughness texture", None),
                    *part,
                )
            })
            .collect();
        let clear = LoadOp::Clear([0.0; 4]);
        let mut pass = graph.raster_pass(OBJECT_GBUFFER);
        pass.color(&mut nr, clear)
            .color(&mut am, clear)
            .color(&mut di, LoadOp::Clear(EMPTY_DISTANCE_ID))
            .depth(&mut depth, LoadOp::Clear(1.0));
        for (i, (vb, ib, base, mr, part)) in imports.into_iter().enumerate() {
            pass.draw(&self.pipeline)
                .read("camera", camera_buffer)
                .read("draws", draw_buffer)
                .read("objects", records.buffer)
                .read("vertices", vb)
                .read("indices", ib)
                .read("base_colour_texture", base)
                .read("metallic_roughness_texture", mr)
                .sampler("material_sampler", SamplerKind::LinearRepeat)
                .push(&DrawPush {
                    draw: i as u32,
                    first_index: part.first_index,
                })
                .vertices(part.index_count, 1);
        }
        pass.finish();
        Ok(GBuffer {
            normal_roughness: nr,
            albedo_metallic: am,
            distance_id: di,
        })
    }
}
