//! Planning a declared frame, without a device: execution order, culling,
//! transient slot assignment (aliasing by lifetime) and the barriers and
//! layout transitions before every pass and at the end of the frame.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use ash::vk;

use super::access::{write_bits, SyncState, Usage};
use super::builder::{FrameGraph, VersionInfo};
use super::GraphError;
use crate::memory::{aspect_of, ImageDesc};

/// Where a logical resource lives physically.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Target {
    /// A slot of the transient pool (several resources may share one).
    Transient(usize),
    /// An imported resource (its logical id).
    Imported(u32),
}

/// The logical resource a barrier applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BarrierResource {
    /// An image, by logical id.
    Image(u32),
    /// A buffer, by logical id.
    Buffer(u32),
}

/// One derived barrier (an image barrier with layout transition, or a buffer
/// barrier), in synchronization2 terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Barrier {
    /// What it applies to.
    pub resource: BarrierResource,
    /// Stages that must finish first.
    pub src_stage: vk::PipelineStageFlags2,
    /// Writes to make available.
    pub src_access: vk::AccessFlags2,
    /// Stages that wait.
    pub dst_stage: vk::PipelineStageFlags2,
    /// Accesses the data is made visible to.
    pub dst_access: vk::AccessFlags2,
    /// Layout before (UNDEFINED discards content; buffers: UNDEFINED).
    pub old_layout: vk::ImageLayout,
    /// Layout after.
    pub new_layout: vk::ImageLayout,
}

/// A transient slot's shape: what the pool must provide.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlotDesc {
    /// An image with these usages.
    Image(ImageDesc, vk::ImageUsageFlags),
    /// A buffer of this size with these usages.
    Buffer(u64, vk::BufferUsageFlags),
}

/// The executable plan of one frame.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Pass indices in execution order (culled passes absent).
    pub order: Vec<usize>,
    /// Passes culled because nothing consumes their results.
    pub culled: Vec<usize>,
    /// Barriers to record before each pass of `order` (same length).
    pub barriers: Vec<Vec<Barrier>>,
    /// Barriers at the end of the frame (exports of imported resources).
    pub final_barriers: Vec<Barrier>,
    /// Physical target of each logical image (`None`: unused by live passes).
    pub image_targets: Vec<Option<Target>>,
    /// Physical target of each logical buffer.
    pub buffer_targets: Vec<Option<Target>>,
    /// Shapes of the transient slots, indexed by slot number.
    pub slots: Vec<SlotDesc>,
    /// State each imported image is left in (to carry into the next frame).
    pub image_end_states: Vec<(u32, SyncState)>,
    /// State each imported buffer is left in.
    pub buffer_end_states: Vec<(u32, SyncState)>,
}

/// Per-physical-resource hazard tracking while walking the passes.
#[derive(Debug, Clone, Copy)]
struct Track {
    layout: vk::ImageLayout,
    write_stage: vk::PipelineStageFlags2,
    write_access: vk::AccessFlags2,
    read_stage: vk::PipelineStageFlags2,
    read_access: vk::AccessFlags2,
}

impl Track {
    fn from(state: SyncState) -> Self {
        Self {
            layout: state.layout,
            write_stage: state.stage,
            write_access: state.access,
            read_stage: vk::PipelineStageFlags2::NONE,
            read_access: vk::AccessFlags2::NONE,
        }
    }

    fn pending_stages(&self) -> vk::PipelineStageFlags2 {
        self.write_stage | self.read_stage
    }

    /// Updates the state for one access; returns the barrier it needs, if any.
    fn access(
        &mut self,
        resource: BarrierResource,
        u: Usage,
        discard: bool,
        is_image: bool,
    ) -> Option<Barrier> {
        let barrier = |t: &Track, src_stage, old_layout| Barrier {
            resource,
            src_stage,
            src_access: t.write_access,
            dst_stage: u.stage,
            dst_access: u.access,
            old_layout,
            new_layout: if is_image {
                u.layout
            } else {
                vk::ImageLayout::UNDEFINED
            },
        };
        if u.writes {
            let old = if is_image && discard {
                vk::ImageLayout::UNDEFINED
            } else {
                self.layout
            };
            let needs = !self.pending_stages().is_empty()
                || !self.write_access.is_empty()
                || (is_image && old != u.layout);
            let b = needs.then(|| barrier(self, self.pending_stages(), old));
            *self = Track {
                layout: if is_image { u.layout } else { self.layout },
                write_stage: u.stage,
                write_access: write_bits(u.access),
                read_stage: vk::PipelineStageFlags2::NONE,
                read_access: vk::AccessFlags2::NONE,
            };
            return b;
        }
        if is_image && self.layout != u.layout {
            let b = barrier(self, self.pending_stages(), self.layout);
            self.layout = u.layout;
            self.write_stage |= u.stage;
            self.read_stage = u.stage;
            self.read_access = u.access;
            return Some(b);
        }
        let covered = self.read_stage.contains(u.stage) && self.read_access.contains(u.access);
        let pending_write = !self.write_stage.is_empty() || !self.write_access.is_empty();
        self.read_stage |= u.stage;
        self.read_access |= u.access;
        (!covered && pending_write).then(|| barrier(self, self.write_stage, self.layout))
    }

    fn end_state(&self) -> SyncState {
        SyncState {
            stage: self.pending_stages(),
            access: self.write_access,
            layout: self.layout,
        }
    }
}

/// A resource use flattened over images and buffers.
struct Use {
    resource: BarrierResource,
    version: u32,
    usage: Usage,
}

/// What each pass depends on, by pass index.
struct Dependencies {
    /// Passes whose results it reads (they must be live if it is).
    data: Vec<Vec<usize>>,
    /// Passes that must run before it (writers of what it touches, and
    /// readers of what it overwrites).
    after: Vec<Vec<usize>>,
}

/// The transients' usages over the whole frame and where each resource is
/// last used in the execution order.
struct Lifetimes {
    image_usage: Vec<vk::ImageUsageFlags>,
    buffer_usage: Vec<vk::BufferUsageFlags>,
    last_use: HashMap<BarrierResource, usize>,
}

/// Physical targets, transient slots, barriers before each pass, and the
/// hazard state each physical resource is left in.
struct Placement {
    image_targets: Vec<Option<Target>>,
    buffer_targets: Vec<Option<Target>>,
    slots: Vec<SlotDesc>,
    barriers: Vec<Vec<Barrier>>,
    tracks: HashMap<(bool, Target), Track>,
}

/// The barriers at the end of the frame and the end state of each import.
struct Exports {
    final_barriers: Vec<Barrier>,
    image_end_states: Vec<(u32, SyncState)>,
    buffer_end_states: Vec<(u32, SyncState)>,
}

impl Plan {
    /// Plans a declared graph: fails with the first declaration error, or a
    /// cycle among passes.
    pub fn new(graph: &FrameGraph) -> Result<Plan, GraphError> {
        validate(graph)?;
        let uses = flatten_uses(graph);
        let deps = dependencies(graph, &uses);
        let live = liveness(graph, &deps.data);
        let order = execution_order(graph, &live, &deps.after)?;
        let culled = (0..graph.passes.len()).filter(|&p| !live[p]).collect();
        let lifetimes = lifetimes(graph, &order);
        let placement = place_and_synchronise(graph, &uses, &order, &lifetimes);
        let exports = export_imports(graph, &placement.tracks);
        Ok(Plan {
            order,
            culled,
            barriers: placement.barriers,
            final_barriers: exports.final_barriers,
            image_targets: placement.image_targets,
            buffer_targets: placement.buffer_targets,
            slots: placement.slots,
            image_end_states: exports.image_end_states,
            buffer_end_states: exports.buffer_end_states,
        })
    }

    /// The aspect mask to use in a barrier on this logical image.
    pub(crate) fn aspect(graph: &FrameGraph, id: u32) -> vk::ImageAspectFlags {
        aspect_of(graph.images[id as usize].desc.format)
    }
}

/// The first declaration error, or a raster pass whose attachments do not
/// fit together.
fn validate(graph: &FrameGraph) -> Result<(), GraphError> {
    if let Some(e) = &graph.error {
        return Err(e.clone());
    }
    graph
        .passes
        .iter()
        .filter(|p| p.kind == super::PassKind::Raster)
        .try_for_each(|p| check_attachments(graph, p))
}

/// Each pass's image and buffer uses as one list.
fn flatten_uses(graph: &FrameGraph) -> Vec<Vec<Use>> {
    graph
        .passes
        .iter()
        .map(|p| {
            let images = p.images.iter().map(|u| Use {
                resource: BarrierResource::Image(u.id),
                version: u.version,
                usage: u.access.usage(p.kind),
            });
            let buffers = p.buffers.iter().map(|u| Use {
                resource: BarrierResource::Buffer(u.id),
                version: u.version,
                usage: u.access.usage(p.kind),
            });
            images.chain(buffers).collect()
        })
        .collect()
}

/// Data dependencies (for liveness) and ordering edges, from the resources'
/// version tables.
fn dependencies(graph: &FrameGraph, uses: &[Vec<Use>]) -> Dependencies {
    let versions = |r: BarrierResource| -> &Vec<VersionInfo> {
        match r {
            BarrierResource::Image(id) => &graph.images[id as usize].versions,
            BarrierResource::Buffer(id) => &graph.buffers[id as usize].versions,
        }
    };
    let n = graph.passes.len();
    let mut data: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut after: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (p, list) in uses.iter().enumerate() {
        for u in list {
            let v = &versions(u.resource)[u.version as usize];
            if let Some(w) = v.writer {
                if !u.usage.writes || u.usage.keeps {
                    data[p].push(w);
                }
                after[p].push(w);
            }
            if u.usage.writes {
                // Everyone who read the version we overwrite runs first.
                after[p].extend(v.readers.iter().copied().filter(|&r| r != p));
            }
        }
    }
    Dependencies { data, after }
}

/// Which passes are live: those with external effects (kept, or writing an
/// import), those writing a declared output, and everything they read from.
fn liveness(graph: &FrameGraph, data: &[Vec<usize>]) -> Vec<bool> {
    let mut stack: Vec<usize> = Vec::new();
    for (p, decl) in graph.passes.iter().enumerate() {
        let writes_import = decl
            .images
            .iter()
            .any(|u| u.access.writes() && graph.images[u.id as usize].import.is_some())
            || decl
                .buffers
                .iter()
                .any(|u| u.access.writes() && graph.buffers[u.id as usize].import.is_some());
        if decl.keep || writes_import {
            stack.push(p);
        }
    }
    let image_outputs = graph.images.iter().filter_map(|d| {
        d.output_version
            .and_then(|v| d.versions.get(v as usize))
            .and_then(|v| v.writer)
    });
    let buffer_outputs = graph.buffers.iter().filter_map(|d| {
        d.output_version
            .and_then(|v| d.versions.get(v as usize))
            .and_then(|v| v.writer)
    });
    stack.extend(image_outputs.chain(buffer_outputs));
    let mut live = vec![false; graph.passes.len()];
    while let Some(p) = stack.pop() {
        if !std::mem::replace(&mut live[p], true) {
            stack.extend(data[p].iter().copied());
        }
    }
    live
}

/// The live passes in an order that respects `after`: Kahn's algorithm,
/// earliest-declared first; a cycle is an error naming its passes.
fn execution_order(
    graph: &FrameGraph,
    live: &[bool],
    after: &[Vec<usize>],
) -> Result<Vec<usize>, GraphError> {
    let n = graph.passes.len();
    let mut indegree = vec![0usize; n];
    let mut next: Vec<Vec<usize>> = vec![Vec::new(); n];
    for p in (0..n).filter(|&p| live[p]) {
        let mut preds: Vec<usize> = after[p].iter().copied().filter(|&q| live[q]).collect();
        preds.sort_unstable();
        preds.dedup();
        indegree[p] = preds.len();
        for q in preds {
            next[q].push(p);
        }
    }
    let mut ready: BinaryHeap<Reverse<usize>> = (0..n)
        .filter(|&p| live[p] && indegree[p] == 0)
        .map(Reverse)
        .collect();
    let mut order = Vec::new();
    while let Some(Reverse(p)) = ready.pop() {
        order.push(p);
        for &q in &next[p] {
            indegree[q] -= 1;
            if indegree[q] == 0 {
                ready.push(Reverse(q));
            }
        }
    }
    let live_count = live.iter().filter(|&&l| l).count();
    if order.len() != live_count {
        let stuck = (0..n)
            .filter(|&p| live[p] && !order.contains(&p))
            .map(|p| graph.passes[p].name.clone())
            .collect();
        return Err(GraphError::Cycle(stuck));
    }
    Ok(order)
}

/// Every usage each resource needs over the frame, and its last use.
fn lifetimes(graph: &FrameGraph, order: &[usize]) -> Lifetimes {
    let mut image_usage = vec![vk::ImageUsageFlags::empty(); graph.images.len()];
    let mut buffer_usage = vec![vk::BufferUsageFlags::empty(); graph.buffers.len()];
    let mut last_use: HashMap<BarrierResource, usize> = HashMap::new();
    for (pos, &p) in order.iter().enumerate() {
        for u in &graph.passes[p].images {
            image_usage[u.id as usize] |= u.access.image_usage();
            last_use.insert(BarrierResource::Image(u.id), pos);
        }
        for u in &graph.passes[p].buffers {
            buffer_usage[u.id as usize] |= u.access.buffer_usage();
            last_use.insert(BarrierResource::Buffer(u.id), pos);
        }
    }
    Lifetimes {
        image_usage,
        buffer_usage,
        last_use,
    }
}

/// Walks the passes in order: gives each resource its physical target
/// (imports their own, transients a pool slot that is reused once the
/// previous occupant's last use is past), and derives the barriers each
/// pass needs from the hazard state of what it touches.
fn place_and_synchronise(
    graph: &FrameGraph,
    uses: &[Vec<Use>],
    order: &[usize],
    lifetimes: &Lifetimes,
) -> Placement {
    let mut image_targets: Vec<Option<Target>> = vec![None; graph.images.len()];
    let mut buffer_targets: Vec<Option<Target>> = vec![None; graph.buffers.len()];
    let mut slots: Vec<SlotDesc> = Vec::new();
    let mut free: Vec<usize> = Vec::new();
    let mut barriers = Vec::with_capacity(order.len());
    let mut tracks: HashMap<(bool, Target), Track> = HashMap::new();
    for (pos, &p) in order.iter().enumerate() {
        let mut pass_barriers = Vec::new();
        for u in &uses[p] {
            let (is_image, target) = match u.resource {
                BarrierResource::Image(id) => {
                    let d = &graph.images[id as usize];
                    let t = *image_targets[id as usize].get_or_insert_with(|| match &d.import {
                        Some(_) => Target::Imported(id),
                        None => Target::Transient(take_slot(
                            &mut slots,
                            &mut free,
                            SlotDesc::Image(d.desc, lifetimes.image_usage[id as usize]),
                        )),
                    });
                    (true, t)
                }
                BarrierResource::Buffer(id) => {
                    let d = &graph.buffers[id as usize];
                    let t = *buffer_targets[id as usize].get_or_insert_with(|| match &d.import {
                        Some(_) => Target::Imported(id),
                        None => Target::Transient(take_slot(
                            &mut slots,
                            &mut free,
                            SlotDesc::Buffer(d.size, lifetimes.buffer_usage[id as usize]),
                        )),
                    });
                    (false, t)
                }
            };
            let track = tracks.entry((is_image, target)).or_insert_with(|| {
                Track::from(match (u.resource, target) {
                    (BarrierResource::Image(id), Target::Imported(_)) => graph.images[id as usize]
                        .import
                        .as_ref()
                        .map(|i| i.initial)
                        .unwrap_or(SyncState::FRESH),
                    (BarrierResource::Buffer(id), Target::Imported(_)) => graph.buffers
                        [id as usize]
                        .import
                        .as_ref()
                        .map(|i| i.initial)
                        .unwrap_or(SyncState::FRESH),
                    _ => SyncState::FRESH,
                })
            });
            let first_version_of_transient =
                matches!(target, Target::Transient(_)) && u.version == 0;
            let discard = u.usage.writes && (!u.usage.keeps || first_version_of_transient);
            if let Some(b) = track.access(u.resource, u.usage, discard, is_image) {
                pass_barriers.push(b);
            }
        }
        barriers.push(pass_barriers);
        // Release transient slots whose last use was this pass.
        for u in &uses[p] {
            if lifetimes.last_use.get(&u.resource) == Some(&pos) {
                let target = match u.resource {
                    BarrierResource::Image(id) => image_targets[id as usize],
                    BarrierResource::Buffer(id) => buffer_targets[id as usize],
                };
                if let Some(Target::Transient(s)) = target {
                    if !free.contains(&s) {
                        free.push(s);
                    }
                }
            }
        }
    }
    Placement {
        image_targets,
        buffer_targets,
        slots,
        barriers,
        tracks,
    }
}

/// The barriers that hand each imported resource over in its export state
/// at the end of the frame, and the state each import is left in.
fn export_imports(graph: &FrameGraph, tracks: &HashMap<(bool, Target), Track>) -> Exports {
    let mut final_barriers = Vec::new();
    let mut image_end_states = Vec::new();
    let mut buffer_end_states = Vec::new();
    for (id, d) in graph.images.iter().enumerate() {
        let Some(import) = &d.import else { continue };
        let key = (true, Target::Imported(id as u32));
        let mut track = tracks
            .get(&key)
            .copied()
            .unwrap_or_else(|| Track::from(import.initial));
        if let Some(e) = import.export {
            if track.layout != e.layout
                || !track.pending_stages().is_empty()
                || !track.write_access.is_empty()
            {
                final_barriers.push(Barrier {
                    resource: BarrierResource::Image(id as u32),
                    src_stage: track.pending_stages(),
                    src_access: track.write_access,
                    dst_stage: e.stage,
                    dst_access: e.access,
                    old_layout: track.layout,
                    new_layout: e.layout,
                });
            }
            track = Track::from(SyncState {
                stage: e.stage,
                access: vk::AccessFlags2::NONE,
                layout: e.layout,
            });
        }
        image_end_states.push((id as u32, track.end_state()));
    }
    for (id, d) in graph.buffers.iter().enumerate() {
        let Some(import) = &d.import else { continue };
        let key = (false, Target::Imported(id as u32));
        let mut track = tracks
            .get(&key)
            .copied()
            .unwrap_or_else(|| Track::from(import.initial));
        if let Some(e) = import.export {
            if !track.pending_stages().is_empty() || !track.write_access.is_empty() {
                final_barriers.push(Barrier {
                    resource: BarrierResource::Buffer(id as u32),
                    src_stage: track.pending_stages(),
                    src_access: track.write_access,
                    dst_stage: e.stage,
                    dst_access: e.access,
                    old_layout: vk::ImageLayout::UNDEFINED,
                    new_layout: vk::ImageLayout::UNDEFINED,
                });
            }
            track = Track::from(SyncState {
                stage: e.stage,
                access: vk::AccessFlags2::NONE,
                layout: vk::ImageLayout::UNDEFINED,
            });
        }
        buffer_end_states.push((id as u32, track.end_state()));
    }
    Exports {
        final_barriers,
        image_end_states,
        buffer_end_states,
    }
}

fn take_slot(slots: &mut Vec<SlotDesc>, free: &mut Vec<usize>, desc: SlotDesc) -> usize {
    if let Some(i) = free.iter().position(|&s| slots[s] == desc) {
        return free.swap_remove(i);
    }
    slots.push(desc);
    slots.len() - 1
}

fn check_attachments(
    graph: &FrameGraph,
    pass: &super::builder::PassDecl,
) -> Result<(), GraphError> {
    use super::ImageAccess;
    let attachments: Vec<&ImageDesc> = pass
        .images
        .iter()
        .filter(|u| {
            matches!(
                u.access,
                ImageAccess::ColorAttachment(_) | ImageAccess::DepthAttachment(_)
            )
        })
        .map(|u| &graph.images[u.id as usize].desc)
        .collect();
    let err = |message: &str| GraphError::Attachments {
        pass: pass.name.clone(),
        message: message.into(),
    };
    let first = attachments
        .first()
        .ok_or_else(|| err("declares no colour or depth attachment"))?;
    if attachments
        .iter()
        .any(|d| d.width != first.width || d.height != first.height)
    {
        return Err(err("attachments differ in size"));
    }
    let depths = pass
        .images
        .iter()
        .filter(|u| matches!(u.access, ImageAccess::DepthAttachment(_)))
        .count();
    if depths > 1 {
        return Err(err("declares more than one depth attachment"));
    }
    Ok(())
}
