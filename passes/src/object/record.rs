//! One placed object's pose as the GPU passes read it: to-world, to-object
//! and normal matrices and the bounding sphere, uploaded once per frame as
//! one buffer of records (`shaders/object/record.wgsl`) that the G-buffer,
//! the shading's self-shadows and the cast shadow index by object.

use inlay_engine::graph::{BufferHandle, FrameGraph};

use super::PlacedObject;

inlay_engine::gpu_struct! {
    /// `ObjectRecord` of `shaders/object/record.wgsl` (checked through the
    /// cast shadow, which binds the records).
    pub struct ObjectRecord = "shadow/cast.wgsl" : "ObjectRecord" {
        /// Rows of the affine object → world map.
        pub to_world: [[f32; 4]; 3],
        /// Rows of the affine world → object map.
        pub to_object: [[f32; 4]; 3],
        /// Rows of the normal matrix (w unused).
        pub normal: [[f32; 4]; 3],
        /// World-space bounding sphere (centre, radius).
        pub sphere: [f32; 4],
    }
}

impl ObjectRecord {
    /// The record of `placed`.
    pub fn of(placed: &PlacedObject) -> Self {
        let m = placed.pose.matrix();
        let inv = placed.world_to_object();
        let nm = placed.pose.normal_matrix();
        let (c, r) = placed.sphere();
        Self {
            to_world: std::array::from_fn(|i| m.row(i).as_vec4().to_array()),
            to_object: std::array::from_fn(|i| inv.row(i).as_vec4().to_array()),
            normal: std::array::from_fn(|i| nm.row(i).extend(0.0).as_vec4().to_array()),
            sphere: c.extend(r).as_vec4().to_array(),
        }
    }
}

/// A frame's object records in its graph: record `i` is the `i`-th object
/// given to [`ObjectRecords::upload`].
#[derive(Debug, Clone, Copy)]
pub struct ObjectRecords {
    /// The buffer (read-only storage, `array<ObjectRecord>`).
    pub buffer: BufferHandle,
}

impl ObjectRecords {
    /// Uploads the records of `objects` (in order) for this frame.
    pub fn upload<'a>(
        graph: &mut FrameGraph,
        objects: impl IntoIterator<Item = &'a PlacedObject>,
    ) -> Self {
        let mut records: Vec<ObjectRecord> = objects.into_iter().map(ObjectRecord::of).collect();
        // A storage binding may not be empty.
        if records.is_empty() {
            records.push(bytemuck::Zeroable::zeroed());
        }
        Self {
            buffer: graph.upload_buffer("object-records", bytemuck::cast_slice(&records).to_vec()),
        }
    }
}
