//! An object's geometry and materials in object space, as loaded from
//! glTF: one vertex and index array for all primitives, a material per
//! primitive, and the textures the materials use.

use glam::{DVec3, Vec3};

use super::material::Material;
use super::texture::Texture;
use crate::geometry::Aabb;

/// One vertex: position, normal and texture coordinates (object space).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshVertex {
    /// Position.
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Texture coordinates (TEXCOORD_0; zero when absent).
    pub uv: [f32; 2],
}

impl MeshVertex {
    /// Bytes of one vertex on the GPU.
    pub const BYTES: usize = 32;

    /// The GPU layout: position, u, normal, v (32 bytes, std430).
    pub fn to_bytes(&self) -> [u8; Self::BYTES] {
        let v = [
            self.position.x,
            self.position.y,
            self.position.z,
            self.uv[0],
            self.normal.x,
            self.normal.y,
            self.normal.z,
            self.uv[1],
        ];
        let mut out = [0u8; 32];
        for (i, f) in v.iter().enumerate() {
            out[i * 4..i * 4 + 4].copy_from_slice(&f.to_le_bytes());
        }
        out
    }
}

/// A run of triangles sharing one material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeshPart {
    /// First index in [`ObjectMesh::indices`].
    pub first_index: u32,
    /// Number of indices (3 per triangle).
    pub index_count: u32,
    /// Index into [`ObjectMesh::materials`].
    pub material: usize,
}

/// A loaded object in object space.
#[derive(Debug, Clone)]
pub struct ObjectMesh {
    /// Where it came from (messages).
    pub name: String,
    /// All vertices.
    pub vertices: Vec<MeshVertex>,
    /// Triangle indices into `vertices`.
    pub indices: Vec<u32>,
    /// Runs of triangles by material.
    pub parts: Vec<MeshPart>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Textures the materials refer to.
    pub textures: Vec<Texture>,
}

impl ObjectMesh {
    /// A 64-bit key of the mesh's geometry (every vertex position and
    /// index, FNV-1a): what an SSDF baked from it records, so that an SSDF
    /// is never used for another object, or for this one edited.
    pub fn geometry_key(&self) -> u64 {
        let mut h: u64 = 0xcbf29ce484222325;
        let mut eat = |word: u32| {
            for b in word.to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x100000001b3);
            }
        };
        eat(self.vertices.len() as u32);
        for c in self.vertices.iter().flat_map(|v| v.position.to_array()) {
            eat(c.to_bits());
        }
        eat(self.indices.len() as u32);
        self.indices.iter().for_each(|&i| eat(i));
        h
    }

    /// The bounding box of the vertices.
    pub fn bounds(&self) -> Aabb {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for v in &self.vertices {
            lo = lo.min(v.position.as_dvec3());
            hi = hi.max(v.position.as_dvec3());
        }
        Aabb::new(lo, hi)
    }

    /// The bounding sphere used by the method: centred on the bounding
    /// box's centre (the object centre x_o where the probe is traced), with
    /// the radius reaching the farthest vertex.
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        let b = self.bounds();
        let c = (b.min + b.max) * 0.5;
        let r = self
            .vertices
            .iter()
            .map(|v| (v.position.as_dvec3() - c).length())
            .fold(0.0, f64::max);
        (c, r)
    }

    /// Number of triangles.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}
