//! Packing push constants: 4-byte fields in declaration order, matching WGSL
//! structs of u32/i32/f32 members (and vec2/vec4 of them, which are aligned
//! to their size: add padding fields where WGSL would).

/// Bytes a dispatch or draw pushes: a [`GpuStruct`](crate::shader::GpuStruct)
/// (or any `Pod` value) as it is, or a [`Push`] built field by field.
pub trait PushConstants {
    /// The bytes to push.
    fn push_bytes(&self) -> &[u8];
}

impl<T: bytemuck::Pod> PushConstants for T {
    fn push_bytes(&self) -> &[u8] {
        bytemuck::bytes_of(self)
    }
}

impl PushConstants for Push {
    fn push_bytes(&self) -> &[u8] {
        &self.0
    }
}

/// A push-constant block under construction.
#[derive(Debug, Default, Clone)]
pub struct Push(Vec<u8>);

impl Push {
    /// An empty block.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a `u32`.
    pub fn u32(mut self, v: u32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// Appends an `f32`.
    pub fn f32(mut self, v: f32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// The bytes to push.
    pub fn bytes(&self) -> &[u8] {
        &self.0
    }
}
