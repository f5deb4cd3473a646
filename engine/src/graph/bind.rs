//! Compute and raster passes declared by binding (in the spirit of kajiya's
//! `SimpleRenderPass`): each resource is named once, at the shader binding
//! it goes to (by its WGSL name or its number), and the access the graph
//! orders and synchronises by follows from what the shader declares there
//! (a `texture_2d` read is `Sampled`, a `var<storage>` read `StorageRead`,
//! and so on). A binding the dispatch's shader does not use is left out
//! (neither declared nor bound); one it uses and nobody bound is an error.
//! Reading the same resource at several bindings, or in several dispatches
//! of the pass, declares it once. The pipelines are held by `Arc`, so the
//! recording closure owns what it uses. A raster pass declares its
//! attachments on the pass ([`BoundPass::color`], [`BoundPass::depth`])
//! and binds each draw the same way.
//!
//! ```ignore
//! graph
//!     .compute(COMPOSITE, &self.pipeline)
//!     .read("field_colour", field)
//!     .write("out", &mut out)
//!     .push(&push)
//!     .threads([width, height, 1]);
//! ```

use std::sync::Arc;

use super::builder::{FrameGraph, PassBuilder};
use super::context::{Binding, SamplerKind};
use super::decl::{BufferHandle, ImageHandle};
use super::{BufferAccess, GraphError, ImageAccess, LoadOp, PassKind};
use crate::pipeline::{ComputePipeline, GraphicsPipeline};
use crate::push::PushConstants;
use crate::shader::{DescriptorKind, ReflectedBinding};

/// A shader binding, by its WGSL variable name or its `@binding` number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot<'s> {
    /// The variable's name (`var<storage, read> lobes` is `"lobes"`).
    Name(&'s str),
    /// The `@binding(n)` number.
    Number(u32),
}

impl<'s> From<&'s str> for Slot<'s> {
    fn from(name: &'s str) -> Self {
        Slot::Name(name)
    }
}

impl From<u32> for Slot<'_> {
    fn from(number: u32) -> Self {
        Slot::Number(number)
    }
}

impl Slot<'_> {
    fn matches(&self, b: &ReflectedBinding) -> bool {
        match *self {
            Slot::Name(n) => b.name == n,
            Slot::Number(n) => b.binding == n,
        }
    }

    fn owned(&self) -> OwnedSlot {
        match *self {
            Slot::Name(n) => OwnedSlot::Name(n.to_owned()),
            Slot::Number(n) => OwnedSlot::Number(n),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum OwnedSlot {
    Name(String),
    Number(u32),
}

impl OwnedSlot {
    fn matches(&self, b: &ReflectedBinding) -> bool {
        match self {
            OwnedSlot::Name(n) => &b.name == n,
            OwnedSlot::Number(n) => b.binding == *n,
        }
    }
}

/// The binding of `shader` that `slot` names, if the shader uses it.
pub fn find_binding<'b>(
    bindings: &'b [ReflectedBinding],
    slot: Slot<'_>,
) -> Option<&'b ReflectedBinding> {
    bindings.iter().find(|b| slot.matches(b))
}

/// A graph resource a dispatch can bind: an image or a buffer handle.
pub trait GraphResource: Copy + sealed::Sealed {
    #[doc(hidden)]
    fn resource(self) -> Resource;
    #[doc(hidden)]
    fn from_resource(r: Resource) -> Self;
}

// Sealed: nothing outside the engine implements these, so the pipeline
// core they expose stays the engine's.
#[allow(private_interfaces)]
mod sealed {
    pub trait Sealed {}
    impl Sealed for super::ImageHandle {}
    impl Sealed for super::BufferHandle {}
    use crate::pipeline::PipelineCore;
    pub trait SealedPipeline {
        fn core(&self) -> &PipelineCore;
    }
    impl SealedPipeline for super::ComputePipeline {
        fn core(&self) -> &PipelineCore {
            &self.core
        }
    }
    impl SealedPipeline for super::GraphicsPipeline {
        fn core(&self) -> &PipelineCore {
            &self.core
        }
    }
}

/// An image or a buffer handle.
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resource {
    Image(ImageHandle),
    Buffer(BufferHandle),
}

impl GraphResource for ImageHandle {
    fn resource(self) -> Resource {
        Resource::Image(self)
    }
    fn from_resource(r: Resource) -> Self {
        match r {
            Resource::Image(h) => h,
            Resource::Buffer(_) => self::unreachable_handle(),
        }
    }
}

impl GraphResource for BufferHandle {
    fn resource(self) -> Resource {
        Resource::Buffer(self)
    }
    fn from_resource(r: Resource) -> Self {
        match r {
            Resource::Buffer(h) => h,
            Resource::Image(_) => self::unreachable_handle(),
        }
    }
}

/// Declarations keep a resource's kind, so this is never reached; a
/// handle of the other kind would be a bug in this module.
fn unreachable_handle<T>() -> T {
    unreachable!("a graph resource changed kind between declaration and use")
}

/// How a dispatch uses what it binds; the access follows from this and the
/// binding's kind in the shader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Use {
    Read,
    Write,
    ReadWrite,
}

/// An access, of an image or a buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Access {
    Image(ImageAccess),
    Buffer(BufferAccess),
}

/// The access `use_` of a resource bound where the shader has `kind`, or
/// why it cannot be.
fn access_for(resource: Resource, kind: DescriptorKind, use_: Use) -> Result<Access, String> {
    use DescriptorKind as K;
    match (resource, kind, use_) {
        (Resource::Image(_), K::SampledImage, Use::Read) => Ok(Access::Image(ImageAccess::Sampled)),
        (Resource::Image(_), K::StorageImage, Use::Read) => {
            Ok(Access::Image(ImageAccess::StorageRead))
        }
        (Resource::Image(_), K::StorageImage, Use::Write) => {
            Ok(Access::Image(ImageAccess::StorageWrite))
        }
        (Resource::Image(_), K::StorageImage, Use::ReadWrite) => {
            Ok(Access::Image(ImageAccess::StorageReadWrite))
        }
        (Resource::Buffer(_), K::UniformBuffer, Use::Read) => {
            Ok(Access::Buffer(BufferAccess::Uniform))
        }
        (Resource::Buffer(_), K::StorageBuffer, Use::Read) => {
            Ok(Access::Buffer(BufferAccess::StorageRead))
        }
        (Resource::Buffer(_), K::StorageBuffer, Use::Write) => {
            Ok(Access::Buffer(BufferAccess::StorageWrite))
        }
        (Resource::Buffer(_), K::StorageBuffer, Use::ReadWrite) => {
            Ok(Access::Buffer(BufferAccess::StorageReadWrite))
        }
        (r, k, u) => Err(format!(
            "cannot {u:?} {} at a {k:?} binding",
            match r {
                Resource::Image(_) => "an image",
                Resource::Buffer(_) => "a buffer",
            }
        )),
    }
}

/// Whether a pass that already declared `held` on a resource can also
/// make `wanted` of it under the same declaration: identical accesses, or
/// storage accesses after a storage write (a later dispatch of the pass
/// reads or writes what an earlier one wrote).
fn covers(held: Access, wanted: Access) -> bool {
    use BufferAccess as B;
    use ImageAccess as I;
    if held == wanted {
        return true;
    }
    matches!(
        (held, wanted),
        (
            Access::Image(I::StorageWrite | I::StorageReadWrite),
            Access::Image(I::StorageRead | I::StorageWrite | I::StorageReadWrite),
        ) | (
            Access::Buffer(B::StorageWrite | B::StorageReadWrite),
            Access::Buffer(B::StorageRead | B::StorageWrite | B::StorageReadWrite),
        )
    )
}

/// The descriptor a declared resource is bound as at a binding of `kind`.
fn binding_of(resource: Resource, kind: DescriptorKind) -> Binding {
    match (resource, kind) {
        (Resource::Image(h), DescriptorKind::SampledImage) => Binding::SampledImage(h),
        (Resource::Image(h), _) => Binding::StorageImage(h),
        (Resource::Buffer(h), DescriptorKind::UniformBuffer) => Binding::UniformBuffer(h),
        (Resource::Buffer(h), _) => Binding::StorageBuffer(h),
    }
}

/// A pipeline a pass can bind resources for: a compute or a graphics one.
pub trait BoundPipeline: sealed::SealedPipeline {}

impl BoundPipeline for ComputePipeline {}
impl BoundPipeline for GraphicsPipeline {}

/// One dispatch or draw as recorded: everything owned.
enum Recorded {
    Dispatch {
        pipeline: Arc<ComputePipeline>,
        bindings: Vec<Binding>,
        push: Vec<u8>,
        groups: [u32; 3],
    },
    DispatchIndirect {
        pipeline: Arc<ComputePipeline>,
        bindings: Vec<Binding>,
        push: Vec<u8>,
        args: BufferHandle,
        offset: u64,
    },
    Draw {
        pipeline: Arc<GraphicsPipeline>,
        bindings: Vec<Binding>,
        push: Vec<u8>,
        vertices: u32,
        instances: u32,
    },
}

/// A resource this pass has declared, with the handle later uses get.
struct Declared {
    resource: Resource,
    access: Access,
    after: Resource,
}

/// A compute or raster pass under construction: bindings shared by its
/// dispatches or draws ([`Self::image_at`], [`Self::buffer_at`]; a raster
/// pass's attachments), then its dispatches ([`Self::dispatch`]) or draws
/// ([`Self::draw`]), then [`Self::finish`].
pub struct BoundPass<'g> {
    pass: PassBuilder<'g>,
    name: String,
    declared: Vec<Declared>,
    shared: Vec<(OwnedSlot, Resource)>,
    dispatches: Vec<Recorded>,
}

impl FrameGraph {
    /// Starts a compute pass of several dispatches, declared by binding.
    pub fn compute_pass(&mut self, name: &str) -> BoundPass<'_> {
        self.bound_pass(name, PassKind::Compute)
    }

    /// Starts a raster pass: declare its attachments, then bind each draw.
    pub fn raster_pass(&mut self, name: &str) -> BoundPass<'_> {
        self.bound_pass(name, PassKind::Raster)
    }

    fn bound_pass(&mut self, name: &str, kind: PassKind) -> BoundPass<'_> {
        BoundPass {
            pass: self.add_pass(name, kind),
            name: name.to_owned(),
            declared: Vec::new(),
            shared: Vec::new(),
            dispatches: Vec::new(),
        }
    }

    /// Starts a compute pass of one dispatch of `pipeline`: bind its
    /// resources on the returned [`Dispatch`], and [`Dispatch::threads`] or
    /// [`Dispatch::groups`] ends the pass.
    pub fn compute<'p>(
        &'p mut self,
        name: &str,
        pipeline: &Arc<ComputePipeline>,
    ) -> Dispatch<'p, 'p> {
        let pass = self.compute_pass(name);
        Call::new(PassRef::Owned(pass), pipeline)
    }
}

impl<'g> BoundPass<'g> {
    /// Declares `access` to `image` now and binds it at `slot` in every
    /// dispatch whose shader has that binding (and no binding of its own
    /// there); returns the handle later passes use.
    pub fn image_at<'s>(
        &mut self,
        slot: impl Into<Slot<'s>>,
        image: ImageHandle,
        access: ImageAccess,
    ) -> ImageHandle {
        let after = self.declare(image.resource(), Access::Image(access));
        self.shared.push((slot.into().owned(), after));
        ImageHandle::from_resource(after)
    }

    /// As [`Self::image_at`], for a buffer.
    pub fn buffer_at<'s>(
        &mut self,
        slot: impl Into<Slot<'s>>,
        buffer: BufferHandle,
        access: BufferAccess,
    ) -> BufferHandle {
        let after = self.declare(buffer.resource(), Access::Buffer(access));
        self.shared.push((slot.into().owned(), after));
        BufferHandle::from_resource(after)
    }

    /// Declares `image` as a colour attachment of this raster pass (the
    /// attachments' order is the pipeline's) and moves the handle to the
    /// version rendered.
    pub fn color(&mut self, image: &mut ImageHandle, load: LoadOp<[f32; 4]>) -> &mut Self {
        let after = self.declare(
            image.resource(),
            Access::Image(ImageAccess::ColorAttachment(load)),
        );
        *image = ImageHandle::from_resource(after);
        self
    }

    /// Declares `image` as the depth attachment of this raster pass.
    pub fn depth(&mut self, image: &mut ImageHandle, load: LoadOp<f32>) -> &mut Self {
        let after = self.declare(
            image.resource(),
            Access::Image(ImageAccess::DepthAttachment(load)),
        );
        *image = ImageHandle::from_resource(after);
        self
    }

    /// Starts a dispatch of `pipeline` in this compute pass.
    pub fn dispatch<'p>(&'p mut self, pipeline: &Arc<ComputePipeline>) -> Dispatch<'p, 'g> {
        Call::new(PassRef::Borrowed(self), pipeline)
    }

    /// Starts a draw of `pipeline` in this raster pass.
    pub fn draw<'p>(&'p mut self, pipeline: &Arc<GraphicsPipeline>) -> Draw<'p, 'g> {
        Call::new(PassRef::Borrowed(self), pipeline)
    }

    /// Ends the pass: its dispatches (or draws) are recorded in order,
    /// each dispatch after the previous one's storage writes.
    pub fn finish(self) {
        let calls = self.dispatches;
        self.pass.exec(move |ctx| {
            for c in &calls {
                match c {
                    Recorded::Dispatch {
                        pipeline,
                        bindings,
                        push,
                        groups,
                    } => ctx.dispatch(pipeline, bindings, push, *groups)?,
                    Recorded::DispatchIndirect {
                        pipeline,
                        bindings,
                        push,
                        args,
                        offset,
                    } => ctx.dispatch_indirect(pipeline, bindings, push, *args, *offset)?,
                    Recorded::Draw {
                        pipeline,
                        bindings,
                        push,
                        vertices,
                        instances,
                    } => ctx.draw(pipeline, bindings, push, *vertices, *instances)?,
                }
            }
            Ok(())
        });
    }

    fn fail(&mut self, message: String) {
        let pass = self.name.clone();
        self.pass.fail(GraphError::Binding { pass, message });
    }

    /// Declares `access` to `resource` unless an earlier declaration of the
    /// pass covers it; returns the handle the pass binds and later passes
    /// read.
    fn declare(&mut self, resource: Resource, access: Access) -> Resource {
        let same = |r: Resource| match (r, resource) {
            (Resource::Image(a), Resource::Image(b)) => a.id == b.id,
            (Resource::Buffer(a), Resource::Buffer(b)) => a.id == b.id,
            _ => false,
        };
        if let Some(d) = self.declared.iter().find(|d| same(d.resource)) {
            if covers(d.access, access) {
                return d.after;
            }
            let message = format!(
                "declares one resource as {:?} and as {access:?}; bind it once with the combined access",
                d.access
            );
            let after = d.after;
            self.fail(message);
            return after;
        }
        let after = match (resource, access) {
            (Resource::Image(h), Access::Image(a)) => Resource::Image(self.pass.image(h, a)),
            (Resource::Buffer(h), Access::Buffer(a)) => Resource::Buffer(self.pass.buffer(h, a)),
            _ => resource,
        };
        self.declared.push(Declared {
            resource,
            access,
            after,
        });
        after
    }
}

enum PassRef<'p, 'g> {
    Borrowed(&'p mut BoundPass<'g>),
    Owned(BoundPass<'g>),
}

impl<'g> PassRef<'_, 'g> {
    fn get(&mut self) -> &mut BoundPass<'g> {
        match self {
            PassRef::Borrowed(p) => p,
            PassRef::Owned(p) => p,
        }
    }
}

/// One dispatch (or draw) under construction: bind what its shader uses,
/// set its push constants, then end it ([`Dispatch::threads`],
/// [`Dispatch::groups`], [`Draw::vertices`]).
pub struct Call<'p, 'g, P: BoundPipeline> {
    pass: PassRef<'p, 'g>,
    pipeline: Arc<P>,
    bindings: Vec<Option<Binding>>,
    push: Vec<u8>,
}

/// A compute dispatch under construction.
pub type Dispatch<'p, 'g> = Call<'p, 'g, ComputePipeline>;

/// A draw under construction.
pub type Draw<'p, 'g> = Call<'p, 'g, GraphicsPipeline>;

impl<'p, 'g, P: BoundPipeline> Call<'p, 'g, P> {
    fn new(pass: PassRef<'p, 'g>, pipeline: &Arc<P>) -> Self {
        Self {
            bindings: vec![None; pipeline.core().bindings.len()],
            pass,
            pipeline: pipeline.clone(),
            push: Vec::new(),
        }
    }

    fn bind(&mut self, slot: Slot<'_>, resource: Resource, use_: Use) -> Resource {
        let core = self.pipeline.core();
        let Some(index) = core.bindings.iter().position(|b| slot.matches(b)) else {
            return resource;
        };
        let kind = core.bindings[index].kind;
        match access_for(resource, kind, use_) {
            Ok(access) => {
                let after = self.pass.get().declare(resource, access);
                self.bindings[index] = Some(binding_of(after, kind));
                after
            }
            Err(why) => {
                let r = &core.bindings[index];
                let message = format!("{} binding {} (`{}`): {why}", core.name, r.binding, r.name);
                self.pass.get().fail(message);
                resource
            }
        }
    }

    /// The pipeline this call runs.
    pub fn pipeline(&self) -> &Arc<P> {
        &self.pipeline
    }

    /// Binds `resource` at `slot` for reading (sampled, storage or uniform,
    /// as the shader declares it there); nothing if the shader has no such
    /// binding.
    pub fn read<'s, R: GraphResource>(mut self, slot: impl Into<Slot<'s>>, resource: R) -> Self {
        self.bind(slot.into(), resource.resource(), Use::Read);
        self
    }

    /// As [`Self::read`] when `resource` is given; nothing when it is not.
    pub fn read_opt<'s, R: GraphResource>(
        self,
        slot: impl Into<Slot<'s>>,
        resource: Option<R>,
    ) -> Self {
        match resource {
            Some(r) => self.read(slot, r),
            None => self,
        }
    }

    /// Binds `resource` at `slot` for writing (its previous content is not
    /// read) and moves the handle to the version written.
    pub fn write<'s, R: GraphResource>(
        mut self,
        slot: impl Into<Slot<'s>>,
        resource: &mut R,
    ) -> Self {
        *resource = R::from_resource(self.bind(slot.into(), resource.resource(), Use::Write));
        self
    }

    /// Binds `resource` at `slot` for reading and writing, and moves the
    /// handle to the version written.
    pub fn read_write<'s, R: GraphResource>(
        mut self,
        slot: impl Into<Slot<'s>>,
        resource: &mut R,
    ) -> Self {
        *resource = R::from_resource(self.bind(slot.into(), resource.resource(), Use::ReadWrite));
        self
    }

    /// Binds a shared sampler at `slot`.
    pub fn sampler<'s>(mut self, slot: impl Into<Slot<'s>>, sampler: SamplerKind) -> Self {
        let slot = slot.into();
        if let Some(i) = self
            .pipeline
            .core()
            .bindings
            .iter()
            .position(|b| slot.matches(b))
        {
            self.bindings[i] = Some(Binding::Sampler(sampler));
        }
        self
    }

    /// The push constants: their first bytes, as many as the shader takes
    /// (so one block can serve several entry points).
    pub fn push(mut self, push: &impl PushConstants) -> Self {
        self.push = push.push_bytes().to_vec();
        self
    }

    /// The bindings in the pipeline's order (the pass's shared ones where
    /// the call bound none) and the push constants cut to the shader's
    /// size; a missing binding or short push block is recorded as an error.
    fn complete(&mut self) -> (Vec<Binding>, Vec<u8>) {
        let core = self.pipeline.core();
        let shared = match &self.pass {
            PassRef::Borrowed(p) => &p.shared,
            PassRef::Owned(p) => &p.shared,
        };
        let mut bindings = Vec::with_capacity(self.bindings.len());
        let mut missing = Vec::new();
        for (b, r) in self.bindings.iter().zip(&core.bindings) {
            let from_pass = || {
                shared
                    .iter()
                    .find(|(s, _)| s.matches(r))
                    .map(|(_, res)| binding_of(*res, r.kind))
            };
            match b.or_else(from_pass) {
                Some(b) => bindings.push(b),
                None => missing.push(format!("{} (`{}`)", r.binding, r.name)),
            }
        }
        let size = core.push_size as usize;
        let mut problems = Vec::new();
        if !missing.is_empty() {
            problems.push(format!(
                "{} uses unbound bindings {}",
                core.name,
                missing.join(", ")
            ));
        }
        if self.push.len() < size {
            problems.push(format!(
                "{} takes {size} bytes of push constants, got {}",
                core.name,
                self.push.len()
            ));
        }
        if !problems.is_empty() {
            let message = problems.join("; ");
            self.pass.get().fail(message);
        }
        let mut push = std::mem::take(&mut self.push);
        push.truncate(size);
        (bindings, push)
    }

    /// Records the call on its pass, and ends the pass if the call owns it.
    fn end(mut self, call: Recorded) {
        self.pass.get().dispatches.push(call);
        if let PassRef::Owned(pass) = self.pass {
            pass.finish();
        }
    }
}

impl Dispatch<'_, '_> {
    /// Ends the dispatch with enough workgroups to cover `threads`
    /// invocations per axis.
    pub fn threads(self, threads: [u32; 3]) {
        let groups = self.pipeline.groups_for(threads);
        self.groups(groups);
    }

    /// Ends the dispatch with the workgroup counts an earlier pass wrote
    /// into `args` at byte `offset` (three u32; see
    /// [`super::PassContext::dispatch_indirect`]).
    pub fn indirect(mut self, args: BufferHandle, offset: u64) {
        let args = match self.pass.get().declare(
            Resource::Buffer(args),
            Access::Buffer(BufferAccess::Indirect),
        ) {
            Resource::Buffer(b) => b,
            _ => args,
        };
        let (bindings, push) = self.complete();
        let pipeline = self.pipeline.clone();
        self.end(Recorded::DispatchIndirect {
            pipeline,
            bindings,
            push,
            args,
            offset,
        });
    }

    /// Ends the dispatch with `groups` workgroups.
    pub fn groups(mut self, groups: [u32; 3]) {
        let (bindings, push) = self.complete();
        let pipeline = self.pipeline.clone();
        self.end(Recorded::Dispatch {
            pipeline,
            bindings,
            push,
            groups,
        });
    }
}

impl Draw<'_, '_> {
    /// Ends the draw: `vertices` vertices (non-indexed), `instances` times.
    pub fn vertices(mut self, vertices: u32, instances: u32) {
        let (bindings, push) = self.complete();
        let pipeline = self.pipeline.clone();
        self.end(Recorded::Draw {
            pipeline,
            bindings,
            push,
            vertices,
            instances,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binding(name: &str, binding: u32, kind: DescriptorKind) -> ReflectedBinding {
        ReflectedBinding {
            set: 0,
            binding,
            kind,
            name: name.into(),
        }
    }

    #[test]
    fn slots_match_by_name_or_number() {
        let b = [
            binding("field", 0, DescriptorKind::SampledImage),
            binding("out", 2, DescriptorKind::StorageImage),
        ];
        assert_eq!(find_binding(&b, "out".into()).map(|r| r.binding), Some(2));
        assert_eq!(
            find_binding(&b, 0.into()).map(|r| r.name.as_str()),
            Some("field")
        );
        assert!(find_binding(&b, "shadow".into()).is_none());
        assert!(find_binding(&b, 1.into()).is_none());
    }

    #[test]
    fn the_access_follows_the_shader() {
        let img = Resource::Image(ImageHandle { id: 0, version: 0 });
        let buf = Resource::Buffer(BufferHandle { id: 0, version: 0 });
        use DescriptorKind as K;
        assert_eq!(
            access_for(img, K::SampledImage, Use::Read),
            Ok(Access::Image(ImageAccess::Sampled))
        );
        assert_eq!(
            access_for(img, K::StorageImage, Use::Read),
            Ok(Access::Image(ImageAccess::StorageRead))
        );
        assert_eq!(
            access_for(buf, K::UniformBuffer, Use::Read),
            Ok(Access::Buffer(BufferAccess::Uniform))
        );
        assert_eq!(
            access_for(buf, K::StorageBuffer, Use::ReadWrite),
            Ok(Access::Buffer(BufferAccess::StorageReadWrite))
        );
        assert!(access_for(img, K::SampledImage, Use::Write).is_err());
        assert!(access_for(buf, K::SampledImage, Use::Read).is_err());
        assert!(access_for(img, K::StorageBuffer, Use::Read).is_err());
        assert!(access_for(buf, K::UniformBuffer, Use::Write).is_err());
    }

    #[test]
    fn repeated_uses_merge_only_when_covered() {
        let sw = Access::Buffer(BufferAccess::StorageWrite);
        let sr = Access::Buffer(BufferAccess::StorageRead);
        let rw = Access::Buffer(BufferAccess::StorageReadWrite);
        assert!(covers(sr, sr));
        assert!(covers(sw, sr));
        assert!(covers(rw, sw));
        assert!(!covers(sr, sw));
        assert!(!covers(sr, rw));
        let sampled = Access::Image(ImageAccess::Sampled);
        let storage = Access::Image(ImageAccess::StorageWrite);
        assert!(!covers(sampled, storage));
        assert!(!covers(storage, sampled));
    }
}
