//! Virtual objects: glTF meshes and materials ([`load_gltf`]), their pose
//! and material overrides as a scene places them ([`PlacedObject`]), and
//! their upload to the GPU ([`GpuObject`]).

mod gltf_load;
mod gpu;
mod material;
mod mesh;
mod pose;
mod record;
mod texture;

pub use gltf_load::{gltf_files, load_gltf, ObjectError};
pub use gpu::{check_mesh_fits, GpuObject};
pub use material::{srgb_to_linear, Material, MaterialOverride};
pub use mesh::{MeshPart, MeshVertex, ObjectMesh};
pub use pose::{Pose, Scale, SCALE_RANGE};
pub use record::{ObjectRecord, ObjectRecords};
pub use texture::Texture;

use std::sync::Arc;

use glam::DVec3;

/// One object as a scene places it: its mesh, pose and material override.
/// Pose and override may change every frame; the mesh is shared.
#[derive(Debug, Clone)]
pub struct PlacedObject {
    /// Name (from the scene file, or the file's stem).
    pub name: String,
    /// The loaded mesh.
    pub mesh: Arc<ObjectMesh>,
    /// Where it stands.
    pub pose: Pose,
    /// Material replacements applied to every material of the mesh.
    pub material: MaterialOverride,
}

impl PlacedObject {
    /// The world → object map (the inverse of its pose).
    pub fn world_to_object(&self) -> glam::DMat4 {
        self.pose.matrix().inverse()
    }

    /// The world-space bounding sphere; its centre is x_o, where the probe
    /// is traced.
    pub fn sphere(&self) -> (DVec3, f64) {
        let (c, r) = self.mesh.bounding_sphere();
        self.pose.sphere(c, r)
    }

    /// The effective material of mesh part `part`.
    pub fn material_of(&self, part: usize) -> Material {
        let m = &self.mesh.materials[self.mesh.parts[part].material];
        self.material.apply(m)
    }
}
