//! How a pass uses a resource, and what that means for Vulkan: pipeline stage,
//! access mask, image layout and the usage flags the resource needs.

use ash::vk;

/// The kind of work a pass records; it fixes the shader stages its accesses
/// happen in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PassKind {
    /// Compute dispatches.
    Compute,
    /// Draws inside dynamic rendering, with colour/depth attachments.
    Raster,
    /// Copies, clears and fills.
    Transfer,
}

/// What happens to an attachment's previous content when a raster pass
/// begins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadOp<T> {
    /// Clear to a value (previous content discarded).
    Clear(T),
    /// Keep previous content.
    Load,
    /// Previous content is undefined (discarded).
    DontCare,
}

impl<T> LoadOp<T> {
    /// Whether the previous content is kept.
    pub fn keeps_content(&self) -> bool {
        matches!(self, LoadOp::Load)
    }
}

/// How a pass uses an image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImageAccess {
    /// Read through a sampled-image binding (`texture_2d`).
    Sampled,
    /// Read through a storage-image binding.
    StorageRead,
    /// Written through a storage-image binding.
    StorageWrite,
    /// Read and written through a storage-image binding.
    StorageReadWrite,
    /// Colour attachment of a raster pass.
    ColorAttachment(LoadOp<[f32; 4]>),
    /// Depth attachment of a raster pass (depth test and write).
    DepthAttachment(LoadOp<f32>),
    /// Source of a copy.
    TransferSrc,
    /// Destination of a copy or clear.
    TransferDst,
}

/// How a pass uses a buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BufferAccess {
    /// Read as a uniform buffer.
    Uniform,
    /// Read as a storage buffer.
    StorageRead,
    /// Written as a storage buffer.
    StorageWrite,
    /// Read and written as a storage buffer.
    StorageReadWrite,
    /// Read as vertex attributes.
    Vertex,
    /// Read as an index buffer.
    Index,
    /// Read as indirect draw/dispatch arguments.
    Indirect,
    /// Source of a copy.
    TransferSrc,
    /// Destination of a copy or fill.
    TransferDst,
}

/// The synchronisation-relevant state of a resource: the stages and accesses
/// that must complete (and be made available) before the next use, and the
/// image layout. Used for imports (state on entry), exports (state to leave
/// the resource in) and state carried between frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncState {
    /// Stages of the work that last touched the resource.
    pub stage: vk::PipelineStageFlags2,
    /// Write accesses of that work that must be made available.
    pub access: vk::AccessFlags2,
    /// Current image layout (UNDEFINED for buffers).
    pub layout: vk::ImageLayout,
}

impl SyncState {
    /// A resource nothing has touched yet.
    pub const FRESH: SyncState = SyncState {
        stage: vk::PipelineStageFlags2::NONE,
        access: vk::AccessFlags2::NONE,
        layout: vk::ImageLayout::UNDEFINED,
    };
}

/// One access as Vulkan sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Usage {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    pub layout: vk::ImageLayout,
    pub writes: bool,
    /// Whether the access needs the previous content (false: it may be discarded).
    pub keeps: bool,
}

const READS: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_SAMPLED_READ.as_raw()
        | vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
        | vk::AccessFlags2::UNIFORM_READ.as_raw()
        | vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw()
        | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
        | vk::AccessFlags2::TRANSFER_READ.as_raw()
        | vk::AccessFlags2::VERTEX_ATTRIBUTE_READ.as_raw()
        | vk::AccessFlags2::INDEX_READ.as_raw()
        | vk::AccessFlags2::INDIRECT_COMMAND_READ.as_raw()
        | vk::AccessFlags2::HOST_READ.as_raw()
        | vk::AccessFlags2::MEMORY_READ.as_raw(),
);

/// The write bits of an access mask.
pub(crate) fn write_bits(access: vk::AccessFlags2) -> vk::AccessFlags2 {
    access & !READS
}

fn shader_stages(kind: PassKind) -> vk::PipelineStageFlags2 {
    match kind {
        PassKind::Compute => vk::PipelineStageFlags2::COMPUTE_SHADER,
        PassKind::Raster => {
            vk::PipelineStageFlags2::VERTEX_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER
        }
        PassKind::Transfer => vk::PipelineStageFlags2::NONE,
    }
}

impl ImageAccess {
    /// Whether the access is allowed in a pass of this kind.
    pub(crate) fn allowed_in(&self, kind: PassKind) -> bool {
        match self {
            ImageAccess::Sampled
            | ImageAccess::StorageRead
            | ImageAccess::StorageWrite
            | ImageAccess::StorageReadWrite => kind != PassKind::Transfer,
            ImageAccess::ColorAttachment(_) | ImageAccess::DepthAttachment(_) => {
                kind == PassKind::Raster
            }
            ImageAccess::TransferSrc | ImageAccess::TransferDst => kind == PassKind::Transfer,
        }
    }

    /// Whether the access writes the image.
    pub fn writes(&self) -> bool {
        !matches!(
            self,
            ImageAccess::Sampled | ImageAccess::StorageRead | ImageAccess::TransferSrc
        )
    }

    /// Whether the access depends on what the image held before the pass.
    pub fn reads_previous(&self) -> bool {
        match self {
            ImageAccess::Sampled
            | ImageAccess::StorageRead
            | ImageAccess::StorageReadWrite
            | ImageAccess::TransferSrc => true,
            ImageAccess::ColorAttachment(l) => l.keeps_content(),
            ImageAccess::DepthAttachment(l) => l.keeps_content(),
            ImageAccess::StorageWrite | ImageAccess::TransferDst => false,
        }
    }

    pub(crate) fn usage(&self, kind: PassKind) -> Usage {
        use vk::AccessFlags2 as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags2 as S;
        let sh = shader_stages(kind);
        let (stage, access, layout, keeps) = match *self {
            ImageAccess::Sampled => (
                sh,
                A::SHADER_SAMPLED_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                true,
            ),
            ImageAccess::StorageRead => (sh, A::SHADER_STORAGE_READ, L::GENERAL, true),
            ImageAccess::StorageWrite => (sh, A::SHADER_STORAGE_WRITE, L::GENERAL, true),
            ImageAccess::StorageReadWrite => (
                sh,
                A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE,
                L::GENERAL,
                true,
            ),
            ImageAccess::ColorAttachment(load) => (
                S::COLOR_ATTACHMENT_OUTPUT,
                if load.keeps_content() {
                    A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE
                } else {
                    A::COLOR_ATTACHMENT_WRITE
                },
                L::COLOR_ATTACHMENT_OPTIMAL,
                load.keeps_content(),
            ),
            ImageAccess::DepthAttachment(load) => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                load.keeps_content(),
            ),
            ImageAccess::TransferSrc => (
                S::ALL_TRANSFER,
                A::TRANSFER_READ,
                L::TRANSFER_SRC_OPTIMAL,
                true,
            ),
            ImageAccess::TransferDst => (
                S::ALL_TRANSFER,
                A::TRANSFER_WRITE,
                L::TRANSFER_DST_OPTIMAL,
                true,
            ),
        };
        Usage {
            stage,
            access,
            layout,
            writes: self.writes(),
            keeps,
        }
    }

    pub(crate) fn image_usage(&self) -> vk::ImageUsageFlags {
        use vk::ImageUsageFlags as U;
        match self {
            ImageAccess::Sampled => U::SAMPLED,
            ImageAccess::StorageRead
            | ImageAccess::StorageWrite
            | ImageAccess::StorageReadWrite => U::STORAGE,
            ImageAccess::ColorAttachment(_) => U::COLOR_ATTACHMENT,
            ImageAccess::DepthAttachment(_) => U::DEPTH_STENCIL_ATTACHMENT,
            ImageAccess::TransferSrc => U::TRANSFER_SRC,
            ImageAccess::TransferDst => U::TRANSFER_DST,
        }
    }
}

impl BufferAccess {
    /// Whether the access is allowed in a pass of this kind.
    pub(crate) fn allowed_in(&self, kind: PassKind) -> bool {
        match self {
            BufferAccess::Uniform
            | BufferAccess::StorageRead
            | BufferAccess::StorageWrite
            | BufferAccess::StorageReadWrite => kind != PassKind::Transfer,
            BufferAccess::Vertex | BufferAccess::Index => kind == PassKind::Raster,
            BufferAccess::Indirect => kind != PassKind::Transfer,
            BufferAccess::TransferSrc | BufferAccess::TransferDst => kind == PassKind::Transfer,
        }
    }

    /// Whether the access writes the buffer.
    pub fn writes(&self) -> bool {
        matches!(
            self,
            BufferAccess::StorageWrite | BufferAccess::StorageReadWrite | BufferAccess::TransferDst
        )
    }

    /// Whether the access depends on what the buffer held before the pass.
    pub fn reads_previous(&self) -> bool {
        !matches!(self, BufferAccess::StorageWrite | BufferAccess::TransferDst)
    }

    pub(crate) fn usage(&self, kind: PassKind) -> Usage {
        use vk::AccessFlags2 as A;
        use vk::PipelineStageFlags2 as S;
        let sh = shader_stages(kind);
        let (stage, access) = match self {
            BufferAccess::Uniform => (sh, A::UNIFORM_READ),
            BufferAccess::StorageRead => (sh, A::SHADER_STORAGE_READ),
            BufferAccess::StorageWrite => (sh, A::SHADER_STORAGE_WRITE),
            BufferAccess::StorageReadWrite => {
                (sh, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE)
            }
            BufferAccess::Vertex => (S::VERTEX_ATTRIBUTE_INPUT, A::VERTEX_ATTRIBUTE_READ),
            BufferAccess::Index => (S::INDEX_INPUT, A::INDEX_READ),
            BufferAccess::Indirect => (S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ),
            BufferAccess::TransferSrc => (S::ALL_TRANSFER, A::TRANSFER_READ),
            BufferAccess::TransferDst => (S::ALL_TRANSFER, A::TRANSFER_WRITE),
        };
        Usage {
            stage,
            access,
            layout: vk::ImageLayout::UNDEFINED,
            writes: self.writes(),
            keeps: true,
        }
    }

    pub(crate) fn buffer_usage(&self) -> vk::BufferUsageFlags {
        use vk::BufferUsageFlags as U;
        match self {
            BufferAccess::Uniform => U::UNIFORM_BUFFER,
            BufferAccess::StorageRead
            | BufferAccess::StorageWrite
            | BufferAccess::StorageReadWrite => U::STORAGE_BUFFER,
            BufferAccess::Vertex => U::VERTEX_BUFFER,
            BufferAccess::Index => U::INDEX_BUFFER,
            BufferAccess::Indirect => U::INDIRECT_BUFFER,
            BufferAccess::TransferSrc => U::TRANSFER_SRC,
            BufferAccess::TransferDst => U::TRANSFER_DST,
        }
    }
}
