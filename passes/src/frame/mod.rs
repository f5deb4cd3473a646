//! One frame of the method, with virtual objects inserted into a field
//! seen from one camera: the per-frame passes of METHOD.md §4.4 in one
//! frame graph — per object the probe trace and SG fit (only when the
//! object moved or the lighting changed), the object G-buffer, the march
//! clipped at the object, SG shading with self-shadows, the cast shadow on
//! the field and compositing. No pass runs whose result the frame does
//! not need: without objects it is the bare march; an object off screen is
//! neither lit nor drawn unless its shadow may reach the screen; each
//! effect can be turned off between frames ([`Effects`]). Passes left out
//! are noted in the frame's timings with the reason. The frame takes plain
//! inputs (camera, placements, effects); the program that shows it keeps
//! them between frames.

pub mod meta;
pub mod pixel_loops;

use std::sync::Arc;

use anyhow::Context as _;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Context};

pub use meta::{
    effect_switches, table1, Effect, EffectSwitch, PassInfo, Table1Module, FRAME_PASSES,
};

use crate::camera::CameraFrame;
use crate::composite::{CompositePass, Layering, COMPOSITE, COMPOSITE_FORMAT};
use crate::edge_aa::{EdgeAaKnobs, EdgeAaPass, OBJECT_EDGE_AA};
use crate::field::GpuGridField;
use crate::gbuffer::{GBufferPass, ObjectDraw, OBJECT_GBUFFER};
use crate::lighting::IncidentLight;
use crate::march::loop_budget::check_loop_budget;
use crate::march::{MarchClip, MarchPass, MarchReuse};
use crate::object::{GpuObject, ObjectRecords, PlacedObject};
use crate::probe::PROBE_TRACE;
use crate::scene::{Scene as SceneFile, ShadowKnobs};
use crate::sgfit::SG_FIT;
use crate::shade::{SelfShadow, ShadePass, OBJECT_SHADE};
use crate::shadow::cast::CastInputs;
use crate::shadow::{CastShadowPass, GpuFhTable, GpuSsdf, CAST_SHADOW};
use crate::sky_behind::{SkyBehindPass, SKY_BEHIND};
use crate::ssdf::SsdfField;

/// How far, in bounding-sphere radii from the object's centre, its cast
/// shadow is drawn when the object itself is off screen: beyond 8 radii
/// the object covers under 1/64 of a cosine-weighted hemisphere, so the
/// shadow it casts there from broad light is below 1.6 %. (A sharp lobe
/// can throw a shadow further; such a shadow is dropped while its object
/// is off screen.)
pub const OFF_SCREEN_SHADOW_REACH: f64 = 8.0;

/// The effects a frame draws; each can be switched between frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Effects {
    /// The estimated or declared distant light L_env in the probe (off, or
    /// a black environment: the term is not evaluated).
    pub environment: bool,
    /// Self-shadows on the objects (eq. 9).
    pub self_shadow: bool,
    /// Shadows cast onto the field (eq. 7-8).
    pub cast_shadow: bool,
    /// The field hides the objects where it is in front of them (eq. 6);
    /// off, the objects are drawn over the unclipped field.
    pub occlusion: bool,
    /// The objects' outlines anti-aliased ([`crate::edge_aa`]).
    pub edge_aa: bool,
}

impl Effects {
    /// Whether `effect` is drawn.
    pub fn on(&self, effect: Effect) -> bool {
        match effect {
            Effect::Environment => self.environment,
            Effect::SelfShadow => self.self_shadow,
            Effect::CastShadow => self.cast_shadow,
            Effect::Occlusion => self.occlusion,
            Effect::EdgeAa => self.edge_aa,
        }
    }

    /// Switches `effect` on or off.
    pub fn set(&mut self, effect: Effect, on: bool) {
        *match effect {
            Effect::Environment => &mut self.environment,
            Effect::SelfShadow => &mut self.self_shadow,
            Effect::CastShadow => &mut self.cast_shadow,
            Effect::Occlusion => &mut self.occlusion,
            Effect::EdgeAa => &mut self.edge_aa,
        } = on;
    }

    /// The effects a scene file asks for.
    pub fn of_scene(shadows: &ShadowKnobs) -> Self {
        Self {
            environment: true,
            self_shadow: shadows.self_shadow,
            cast_shadow: shadows.cast,
            occlusion: true,
            edge_aa: true,
        }
    }
}

/// One object of the frame: its uploaded mesh, its incident light and
/// its SSDF field.
pub struct FrameObject {
    /// Mesh and textures on the GPU.
    pub gpu: GpuObject,
    /// Probe and SG fit at the object's centre.
    pub light: IncidentLight,
    /// Its SSDF field on the GPU (when the scene draws shadows).
    pub ssdf: Option<GpuSsdf>,
}

/// The field, its objects and the passes that insert them.
pub struct InsertionFrame {
    /// The march.
    pub march: MarchPass,
    /// The field on the GPU.
    pub field: GpuGridField,
    /// The objects (may be empty), in the scene's order.
    pub objects: Vec<FrameObject>,
    /// How the SSDF is read outside its grid.
    pub shadow_outside: crate::ssdf::OutsideMode,
    gbuffer: GBufferPass,
    shade: ShadePass,
    composite: CompositePass,
    edge_aa: EdgeAaPass,
    cast: Option<CastShadowPass>,
    fh: Option<GpuFhTable>,
    reuse: Option<MarchReuse>,
    sky: Option<SkyBehindPass>,
}

/// Refuses an object whose shading or cast shadow would loop, at some
/// pixel, past the device's limit ([`pixel_loops`]), naming the knobs.
fn check_pixel_loops(
    ctx: &Context,
    scene: &SceneFile,
    light: &IncidentLight,
    march: &crate::march::MarchKnobs,
    shadows: bool,
) -> anyhow::Result<()> {
    let rays = light
        .direct
        .as_ref()
        .map(|d| d.ray_counts())
        .unwrap_or_default();
    let knobs = || {
        format!(
            "{} sharp lobes of L_env at `[lighting] probe_supersampling` {}, {} local lights \
             at `[lighting] local_light_rays` {}, `[shading] field_light` {}, `[march] \
             samples_per_ray` {}",
            rays.sharp,
            rays.side,
            rays.local,
            rays.local_side,
            scene.shading.field_light,
            march.samples_per_ray
        )
    };
    let field_side = if shadows {
        scene.shading.field_light
    } else {
        0
    };
    let shade = pixel_loops::shade_loop_iterations(
        &rays,
        march,
        field_side,
        scene.lighting.fit.lobes,
        light.probe.environment_lobe_count(),
    );
    check_loop_budget(ctx, OBJECT_SHADE, shade, knobs)?;
    if shadows {
        let cast = pixel_loops::cast_loop_iterations(&rays, march);
        check_loop_budget(ctx, CAST_SHADOW, cast, knobs)?;
    }
    Ok(())
}

/// The format of a frame's image.
pub const FRAME_FORMAT: vk::Format = COMPOSITE_FORMAT;

impl InsertionFrame {
    /// Builds the passes for `scene`'s objects (knobs from the scene file)
    /// over `field`. `ssdfs[i]` is object i's SSDF field, given for every
    /// object when the scene draws shadows (loaded or baked by the caller),
    /// else none.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        scene: &SceneFile,
        march: MarchPass,
        field: GpuGridField,
        ssdfs: Vec<Option<Arc<SsdfField>>>,
    ) -> anyhow::Result<Self> {
        anyhow::ensure!(
            scene.objects.len() <= crate::scene::MAX_OBJECTS,
            "{}: {} objects; at most {} are inserted at once",
            scene.path.display(),
            scene.objects.len(),
            crate::scene::MAX_OBJECTS
        );
        anyhow::ensure!(
            ssdfs.len() == scene.objects.len(),
            "{} SSDF fields for {} objects",
            ssdfs.len(),
            scene.objects.len()
        );
        let shadows = ssdfs.iter().any(Option::is_some);
        let local = scene.lighting.local.choose(&field.emitters, &field.bounds);
        for l in &local {
            log::info!(
                "local light at {:.3} (radius {:.3}): shaded per pixel",
                l.centre,
                l.radius
            );
        }
        let mut objects = Vec::with_capacity(scene.objects.len());
        for (placed, ssdf) in scene.objects.iter().zip(ssdfs) {
            let (centre, _) = placed.sphere();
            if !field.bounds.contains(centre) {
                log::warn!(
                    "object `{}` is centred at {centre}, outside the field's bounds: it is lit by what the field shows from there",
                    placed.name
                );
            }
            // Lit from where it is placed: a recipe's hidden lights are
            // lobes seen from there (and stay so while it is dragged), its
            // hidden bulbs local lights with the field's own.
            let (lobes, hidden) =
                crate::lighting::object_lights(scene, centre, scene.lighting.local.count > 0);
            let lights: Vec<_> = local.iter().copied().chain(hidden).collect();
            let named = || format!("{}: object `{}`", scene.path.display(), placed.name);
            let light = IncidentLight::new(
                ctx,
                lib,
                scene.lighting.probe,
                scene.lighting.fit,
                *march.knobs(),
                &lobes,
                &lights,
                scene.lighting.local.rays,
            )
            .with_context(named)?;
            check_pixel_loops(ctx, scene, &light, march.knobs(), ssdf.is_some())
                .with_context(named)?;
            objects.push(FrameObject {
                gpu: GpuObject::upload(ctx, &placed.mesh)?,
                light,
                ssdf: match ssdf {
                    Some(f) => Some(GpuSsdf::upload(ctx, f, &placed.mesh)?),
                    None => None,
                },
            });
        }
        let beyond = crate::sky_behind::Beyond {
            sky: field.sky.as_deref(),
            lights: &field.seen_lights,
            bounds: field.bounds,
        };
        let sky = SkyBehindPass::new(ctx, lib, &beyond)?;
        Ok(Self {
            gbuffer: GBufferPass::new(ctx, lib)?,
            shade: ShadePass::new(ctx, lib, scene.shading.ndf_lobes, *march.knobs())?
                .with_field_light(scene.shading.field_light)
                .with_field_light_scale(scene.shading.field_light_scale),
            composite: CompositePass::new(ctx, lib)?,
            edge_aa: EdgeAaPass::new(ctx, lib, EdgeAaKnobs::default())?,
            cast: if shadows {
                Some(CastShadowPass::new(
                    ctx,
                    lib,
                    *march.knobs(),
                    scene.shadows.cast_scale,
                    scene.shadows.cast_refine,
                )?)
            } else {
                None
            },
            fh: if shadows {
                Some(GpuFhTable::new(ctx)?)
            } else {
                None
            },
            shadow_outside: scene.shadows.outside,
            march,
            field,
            objects,
            reuse: None,
            sky,
        })
    }

    /// Keeps the field's march across frames from a still camera
    /// ([`MarchReuse`]): each such frame copies it and marches only the
    /// pixels its objects can cover. The images are the same either way;
    /// what changes is the march's cost, so Table 1 (which reads the
    /// march as the cost of rendering the field) is taken without it.
    pub fn set_reuse_march(&mut self, ctx: &Arc<Context>, on: bool) {
        self.reuse = on.then(|| MarchReuse::new(ctx));
    }

    /// Interleaves each moving object's lighting
    /// ([`IncidentLight::set_interleave`](crate::lighting::IncidentLight::set_interleave)):
    /// a frame traces the probe's share or runs the fit, in turn. The
    /// lobes follow the object a frame later; once it stops they reach the
    /// same fit. Table 1, which times a whole update per frame as the
    /// paper does, is taken without it.
    pub fn set_interleave_lighting(&mut self, on: bool) {
        for o in &mut self.objects {
            o.light.set_interleave(on);
        }
    }

    /// How the viewer paces its frames: the march kept while the camera
    /// holds still and a moving object's lighting interleaved (on), or a
    /// whole march and a whole update every frame, as Table 1 times them
    /// (off).
    pub fn set_viewer_pacing(&mut self, ctx: &Arc<Context>, on: bool) {
        self.set_reuse_march(ctx, on);
        self.set_interleave_lighting(on);
    }

    /// The field's march for this frame, kept or afresh.
    fn march_field(
        &mut self,
        graph: &mut FrameGraph,
        frame: &CameraFrame,
        clip: MarchClip,
    ) -> anyhow::Result<crate::march::MarchOutputs> {
        match self.reuse.as_mut() {
            Some(reuse) => reuse.add(&self.march, graph, &self.field, frame, clip),
            None => Ok(self.march.add(
                graph,
                &self.field,
                frame,
                match clip {
                    MarchClip::None => None,
                    MarchClip::Objects { depth, .. } => Some(depth),
                },
            )),
        }
    }

    /// Whether any object has an SSDF field (shadows can be drawn).
    pub fn has_shadows(&self) -> bool {
        self.fh.is_some()
    }

    /// Adds the frame seen through `frame` to `graph`, object i placed as
    /// `placed[i]`, drawing `effects`, the field's sky behind it where it
    /// has one; returns its image ([`FRAME_FORMAT`]).
    pub fn add(
        &mut self,
        graph: &mut FrameGraph,
        frame: &CameraFrame,
        placed: &[PlacedObject],
        effects: Effects,
    ) -> anyhow::Result<ImageHandle> {
        let image = self.add_layers(graph, frame, placed, effects)?;
        Ok(match &self.sky {
            Some(sky) if sky.draws(frame) => sky.add(graph, image, frame),
            Some(_) => {
                graph.note_skipped(
                    SKY_BEHIND,
                    "the field has no sky, and no light seen past its bounds is in view",
                );
                image
            }
            None => {
                graph.note_skipped(SKY_BEHIND, "the field has no sky and no light seen past it");
                image
            }
        })
    }

    /// The frame's field and objects, without the sky.
    fn add_layers(
        &mut self,
        graph: &mut FrameGraph,
        frame: &CameraFrame,
        placed: &[PlacedObject],
        effects: Effects,
    ) -> anyhow::Result<ImageHandle> {
        if self.objects.is_empty() {
            return Ok(self
                .march_field(graph, frame, MarchClip::None)?
                .colour_opacity);
        }
        anyhow::ensure!(
            placed.len() == self.objects.len(),
            "{} placements for {} objects",
            placed.len(),
            self.objects.len()
        );
        let on_screen: Vec<bool> = placed
            .iter()
            .map(|p| {
                let (c, r) = p.sphere();
                frame.sphere_visible(c, r)
            })
            .collect();
        let can_cast = effects.cast_shadow && self.cast.is_some() && self.fh.is_some();
        let casts: Vec<bool> = self
            .objects
            .iter()
            .zip(placed)
            .map(|(o, p)| {
                let (c, r) = p.sphere();
                can_cast && o.ssdf.is_some() && frame.sphere_visible(c, r * OFF_SCREEN_SHADOW_REACH)
            })
            .collect();
        if !effects.cast_shadow {
            graph.note_skipped(CAST_SHADOW, "cast shadows off");
        } else if self.fh.is_none() {
            graph.note_skipped(CAST_SHADOW, "the scene draws no shadows");
        } else if !casts.contains(&true) {
            graph.note_skipped(CAST_SHADOW, "objects and their shadows off screen");
        }
        // Incident light, for the objects that show or shadow what shows.
        let version = effects.environment as u64;
        if !self.objects[0].light.has_environment() {
            graph.note_skipped("environment-term", "the environment is black");
        } else if !effects.environment {
            graph.note_skipped("environment-term", "environment light off");
        }
        let mut lobes = Vec::with_capacity(self.objects.len());
        for (i, (o, p)) in self.objects.iter_mut().zip(placed).enumerate() {
            if !(on_screen[i] || casts[i]) {
                graph.note_skipped(PROBE_TRACE, "object off screen");
                graph.note_skipped(SG_FIT, "object off screen");
                lobes.push(None);
                continue;
            }
            let (centre, _) = p.sphere();
            let work = o.light.plan(centre, version);
            lobes.push(Some(o.light.add_with(
                graph,
                &self.field,
                centre,
                work,
                effects.environment,
            )?));
        }
        let shown: Vec<usize> = (0..placed.len()).filter(|&i| on_screen[i]).collect();
        let fh = self.fh.as_ref().map(|t| t.import(graph));
        // Every object's pose, once for the frame: record i is object i.
        let records = ObjectRecords::upload(graph, placed);
        // Each object's SSDF bindings this frame, where a shadow needs them.
        let ssdf: Vec<_> = self
            .objects
            .iter()
            .zip(placed)
            .enumerate()
            .map(|(i, (o, p))| {
                let needed = casts[i] || (on_screen[i] && effects.self_shadow);
                match (&o.ssdf, fh) {
                    (Some(s), Some(_)) if needed => {
                        Some(s.import(graph, p, (records, i as u32), self.shadow_outside))
                    }
                    _ => None,
                }
            })
            .collect();
        if shown.is_empty() {
            graph.note_skipped(OBJECT_GBUFFER, "objects off screen");
            graph.note_skipped(OBJECT_SHADE, "objects off screen");
            graph.note_skipped(OBJECT_EDGE_AA, "objects off screen");
            let field = self.march_field(graph, frame, MarchClip::None)?;
            let shadowed = self.cast_shadows(
                graph,
                frame,
                &field,
                (&casts, &ssdf, &lobes, fh),
                (None, Layering::FieldOverObject),
            );
            return Ok(match shadowed {
                Some(composited) => composited,
                None => {
                    graph.note_skipped(COMPOSITE, "no object and no shadow on screen");
                    field.colour_opacity
                }
            });
        }
        let draws: Vec<ObjectDraw<'_>> = shown
            .iter()
            .map(|&i| ObjectDraw {
                placed: &placed[i],
                gpu: &self.objects[i].gpu,
                record: i as u32,
            })
            .collect();
        let g = self.gbuffer.add(graph, frame, &draws, records)?;
        // The pixels the shown objects can cover (None: any pixel).
        let region = objects_region(frame, placed, &shown);
        let clip = if effects.occlusion {
            MarchClip::Objects {
                depth: g.distance_id,
                region,
            }
        } else {
            MarchClip::None
        };
        let field = self.march_field(graph, frame, clip)?;
        let shown_lobes: Vec<_> = shown.iter().filter_map(|&i| lobes[i]).collect();
        let self_shadow: Vec<Option<SelfShadow>> = shown
            .iter()
            .map(|&i| match (&ssdf[i], fh) {
                (Some(ssdf), Some(fh_table)) if effects.self_shadow => Some(SelfShadow {
                    fh_table,
                    ssdf: *ssdf,
                    pixels: {
                        let (c, r) = placed[i].sphere();
                        frame.sphere_pixels(c, r)
                    },
                }),
                _ => None,
            })
            .collect();
        if !effects.self_shadow {
            graph.note_skipped("self-shadow", "self-shadows off");
        }
        let object = self.shade.add(
            graph,
            frame,
            &g,
            &self.field,
            &shown_lobes,
            &self_shadow,
            region,
        );
        let layering = if effects.occlusion {
            Layering::FieldOverObject
        } else {
            Layering::ObjectOverField
        };
        let shadowed = self.cast_shadows(
            graph,
            frame,
            &field,
            (&casts, &ssdf, &lobes, fh),
            (Some(object), layering),
        );
        let composite = shadowed.unwrap_or_else(|| {
            self.composite
                .add_layered(graph, field.colour_opacity, object, None, layering)
        });
        if !effects.edge_aa {
            graph.note_skipped(OBJECT_EDGE_AA, "edge anti-aliasing off");
            return Ok(composite);
        }
        Ok(self.edge_aa.add(graph, composite, g.distance_id, region))
    }
}

/// The pixels the objects `shown` (indices into `placed`) can cover: the
/// union of their bounding spheres' rectangles
/// ([`CameraFrame::sphere_pixels`]), None where one of them may cover any
/// pixel.
fn objects_region(
    frame: &CameraFrame,
    placed: &[PlacedObject],
    shown: &[usize],
) -> Option<[u32; 4]> {
    shown
        .iter()
        .map(|&i| {
            let (c, r) = placed[i].sphere();
            frame.sphere_pixels(c, r)
        })
        .try_fold(None, |acc: Option<[u32; 4]>, r| {
            let r = r?;
            Some(Some(match acc {
                None => r,
                Some(a) => [
                    a[0].min(r[0]),
                    a[1].min(r[1]),
                    a[2].max(r[2]),
                    a[3].max(r[3]),
                ],
            }))
        })
        .flatten()
}

impl InsertionFrame {
    /// Chains one `cast-shadow` pass per object that `casts` and
    /// composites the frame with the product ρ ([`CastShadowPass::composite`]):
    /// `field` over `object` as `layering` says, or the shadowed field
    /// alone. None (nothing added) when no object casts.
    fn cast_shadows(
        &self,
        graph: &mut FrameGraph,
        frame: &CameraFrame,
        field: &crate::march::MarchOutputs,
        (casts, ssdf, lobes, fh): ShadowSources<'_>,
        (object, layering): (Option<crate::composite::ObjectLayer>, Layering),
    ) -> Option<ImageHandle> {
        let (cast, fh_table) = (self.cast.as_ref()?, fh?);
        let inputs: Vec<CastInputs> = (0..casts.len())
            .filter_map(|i| match (casts[i], ssdf[i], lobes[i]) {
                (true, Some(ssdf), Some(lobes)) => Some(CastInputs {
                    lobes,
                    fh_table,
                    ssdf,
                }),
                _ => None,
            })
            .collect();
        let mut shadow = None;
        for o in &inputs {
            shadow = Some(cast.add(
                graph,
                &self.field,
                frame,
                field,
                o.lobes,
                fh_table,
                o.ssdf,
                shadow,
            ));
        }
        shadow.map(|low| {
            cast.composite(
                graph,
                &self.field,
                frame,
                field,
                (low, &inputs),
                &self.composite,
                (object, layering),
            )
        })
    }
}

/// What [`InsertionFrame::cast_shadows`] needs per object: whether it
/// casts, its SSDF bindings and its light this frame; and the f_h table.
type ShadowSources<'a> = (
    &'a [bool],
    &'a [Option<crate::shadow::SsdfBindings>],
    &'a [Option<crate::lighting::LightLobes>],
    Option<inlay_engine::graph::BufferHandle>,
);
