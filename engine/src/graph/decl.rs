//! What a frame graph's declarations are made of: handles to versions of
//! its resources, and the uses a pass declares of them. Shared by the
//! builder, the planner and the context passes record through.

use super::access::{BufferAccess, ImageAccess};

/// A version of an image in a [`FrameGraph`](super::FrameGraph). Writing returns a new handle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ImageHandle {
    pub(crate) id: u32,
    pub(crate) version: u32,
}

/// A version of a buffer in a [`FrameGraph`](super::FrameGraph). Writing returns a new handle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BufferHandle {
    pub(crate) id: u32,
    pub(crate) version: u32,
}

/// A pass's declared use of one version of an image.
#[derive(Clone, Copy)]
pub(crate) struct ImageUse {
    pub id: u32,
    /// The version read (for writes: the version overwritten).
    pub version: u32,
    pub access: ImageAccess,
}

/// A pass's declared use of one version of a buffer.
#[derive(Clone, Copy)]
pub(crate) struct BufferUse {
    pub id: u32,
    pub version: u32,
    pub access: BufferAccess,
}
