//! A radiance field with virtual objects inserted, seen from one camera:
//! the per-frame passes of METHOD.md §4.4 in one frame graph — per object
//! the probe trace and SG fit (only when the object moved or the lighting
//! changed), the object G-buffer, the march clipped at the object, SG
//! shading with self-shadows, the cast shadow on the field and
//! compositing. No pass runs whose result the frame does not need: without
//! objects it is the bare march; an object off screen is neither lit nor
//! drawn unless its shadow may reach the screen; each effect can be turned
//! off between frames ([`Effects`]). Passes left out are noted in the
//! frame's timings with the reason.

use std::sync::{Arc, Mutex};

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Context};
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::composite::{CompositePass, Layering, COMPOSITE_FORMAT};
use inlay_passes::field::GpuGridField;
use inlay_passes::gbuffer::{GBufferPass, ObjectDraw};
use inlay_passes::lighting::IncidentLight;
use inlay_passes::march::MarchPass;
use inlay_passes::object::{GpuObject, PlacedObject};
use inlay_passes::scene::Scene as SceneFile;
use inlay_passes::scene::ShadowKnobs;
use inlay_passes::shade::{SelfShadow, ShadePass};
use inlay_passes::shadow::{CastShadowPass, GpuFhTable, GpuSsdf};

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
}

impl Effects {
    /// The effects a scene file asks for.
    pub fn of_scene(shadows: &ShadowKnobs) -> Self {
        Self {
            environment: true,
            self_shadow: shadows.self_shadow,
            cast_shadow: shadows.cast,
            occlusion: true,
        }
    }
}

/// One object of the view: its placement (changeable between frames), its
/// uploaded mesh and its incident light.
pub struct ViewObject {
    /// Pose and material override; edit between frames to move it.
    pub placed: Mutex<PlacedObject>,
    /// Mesh and textures on the GPU.
    pub gpu: GpuObject,
    /// Probe and SG fit at the object's centre.
    pub light: IncidentLight,
    /// Its SSDF field on the GPU (when the scene draws shadows).
    pub ssdf: Option<GpuSsdf>,
}

/// The field, its objects and the passes that insert them.
pub struct InsertionView {
    /// The march.
    pub march: MarchPass,
    /// The field on the GPU.
    pub field: GpuGridField,
    /// The camera (changeable between frames).
    pub camera: Mutex<CameraSpec>,
    /// The objects (may be empty).
    pub objects: Vec<ViewObject>,
    /// Which effects are drawn (changeable between frames; shadows need
    /// the objects' SSDF fields, loaded when the scene asked for shadows).
    pub effects: Mutex<Effects>,
    /// How the SSDF is read outside its grid.
    pub shadow_outside: inlay_passes::shadow::OutsideMode,
    gbuffer: GBufferPass,
    shade: ShadePass,
    composite: CompositePass,
    cast: Option<CastShadowPass>,
    fh: Option<GpuFhTable>,
}

impl InsertionView {
    /// Builds the passes for `scene`'s objects (knobs from the scene file)
    /// over `field`, seen from `camera`. With shadows on, each object's
    /// SSDF field is loaded, or baked and cached (`use_cache`); the
    /// effects start as the scene file sets them.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        scene: &SceneFile,
        march: MarchPass,
        field: GpuGridField,
        camera: CameraSpec,
        use_cache: bool,
    ) -> anyhow::Result<Self> {
        let shadows = scene.shadows.any() && !scene.objects.is_empty();
        let mut objects = Vec::with_capacity(scene.objects.len());
        anyhow::ensure!(
            scene.objects.len() <= 64,
            "{}: {} objects; at most 64 are inserted at once",
            scene.path.display(),
            scene.objects.len()
        );
        for (placed, source) in scene.objects.iter().zip(&scene.object_sources) {
            let (centre, _) = placed.sphere();
            if !field.bounds.contains(centre) {
                log::warn!(
                    "object `{}` is centred at {centre}, outside the field's bounds: it is lit by what the field shows from there",
                    placed.name
                );
            }
            objects.push(ViewObject {
                placed: Mutex::new(placed.clone()),
                gpu: GpuObject::upload(ctx, &placed.mesh)?,
                // Lit from where it is placed: a recipe's hidden lights are
                // lobes seen from there (and stay so while it is dragged).
                light: IncidentLight::new(
                    ctx,
                    lib,
                    scene.lighting.probe,
                    scene.lighting.fit,
                    *march.knobs(),
                    &scene.object_light_lobes(centre),
                )?,
                ssdf: if shadows {
                    let f = crate::ssdf_source::object_ssdf(
                        ctx,
                        lib,
                        &placed.mesh,
                        &source.file,
                        source.ssdf.as_deref(),
                        &scene.shadows.bake,
                        use_cache,
                    )?;
                    Some(GpuSsdf::upload(ctx, Arc::new(f), &placed.mesh)?)
                } else {
                    None
                },
            });
        }
        Ok(Self {
            gbuffer: GBufferPass::new(ctx, lib)?,
            shade: ShadePass::new(ctx, lib, scene.shading.ndf_lobes)?,
            composite: CompositePass::new(ctx, lib)?,
            cast: if shadows {
                Some(CastShadowPass::new(ctx, lib)?)
            } else {
                None
            },
            fh: if shadows {
                Some(GpuFhTable::new(ctx)?)
            } else {
                None
            },
            effects: Mutex::new(Effects::of_scene(&scene.shadows)),
            shadow_outside: scene.shadows.outside,
            march,
            field,
            camera: Mutex::new(camera),
            objects,
        })
    }
}

/// Locks `m`, recovering the value if a panicking thread poisoned it.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl InsertionView {
    /// This frame's camera for a `width`×`height` image.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        CameraFrame::new(&lock(&self.camera), width, height)
    }

    /// Moves the camera from the next frame on.
    pub fn set_camera(&self, camera: CameraSpec) {
        if camera.problem().is_none() {
            *lock(&self.camera) = camera;
        }
    }

    /// A copy of object `index`'s current placement.
    pub fn placed(&self, index: usize) -> Option<PlacedObject> {
        self.objects.get(index).map(|o| lock(&o.placed).clone())
    }

    /// Replaces object `index`'s placement (pose and material).
    pub fn set_placed(&self, index: usize, placed: PlacedObject) {
        if let Some(o) = self.objects.get(index) {
            *lock(&o.placed) = placed;
        }
    }

    /// The effects drawn now.
    pub fn effects(&self) -> Effects {
        *lock(&self.effects)
    }

    /// Sets the effects drawn from the next frame on.
    pub fn set_effects(&self, effects: Effects) {
        *lock(&self.effects) = effects;
    }

    /// Whether any object has an SSDF field (shadows can be drawn).
    pub fn has_shadows(&self) -> bool {
        self.fh.is_some()
    }
}

impl crate::headless::Scene for InsertionView {
    fn build<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        width: u32,
        height: u32,
        _time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let frame = self.frame(width, height);
        if self.objects.is_empty() {
            return Ok(self
                .march
                .add(graph, &self.field, &frame, None)
                .colour_opacity);
        }
        let effects = self.effects();
        // This frame's placements (copied out of the locks).
        let placed: Vec<PlacedObject> = self
            .objects
            .iter()
            .map(|o| lock(&o.placed).clone())
            .collect();
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
            .zip(&placed)
            .map(|(o, p)| {
                let (c, r) = p.sphere();
                can_cast && o.ssdf.is_some() && frame.sphere_visible(c, r * OFF_SCREEN_SHADOW_REACH)
            })
            .collect();
        if !effects.cast_shadow {
            graph.note_skipped("cast-shadow", "cast shadows off");
        } else if self.fh.is_none() {
            graph.note_skipped("cast-shadow", "the scene draws no shadows");
        } else if !casts.contains(&true) {
            graph.note_skipped("cast-shadow", "objects and their shadows off screen");
        }
        // Incident light, for the objects that show or shadow what shows.
        let version = effects.environment as u64;
        if !self.objects[0].light.has_environment() {
            graph.note_skipped("environment-term", "the environment is black");
        } else if !effects.environment {
            graph.note_skipped("environment-term", "environment light off");
        }
        let mut lobes = Vec::with_capacity(self.objects.len());
        for (i, (o, p)) in self.objects.iter().zip(&placed).enumerate() {
            if !(on_screen[i] || casts[i]) {
                graph.note_skipped("probe-trace", "object off screen");
                graph.note_skipped("sg-fit", "object off screen");
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
        // Each object's SSDF bindings this frame, where a shadow needs them.
        let ssdf: Vec<_> = self
            .objects
            .iter()
            .zip(&placed)
            .enumerate()
            .map(|(i, (o, p))| {
                let needed = casts[i] || (on_screen[i] && effects.self_shadow);
                match (&o.ssdf, fh) {
                    (Some(s), Some(_)) if needed => Some(s.import(graph, p, self.shadow_outside)),
                    _ => None,
                }
            })
            .collect();
        if shown.is_empty() {
            graph.note_skipped("object-gbuffer", "objects off screen");
            graph.note_skipped("object-shade", "objects off screen");
            let field = self.march.add(graph, &self.field, &frame, None);
            let shadow = self.cast_shadows(graph, &frame, &field, &casts, &ssdf, &lobes, fh);
            return Ok(match shadow {
                Some(s) => self
                    .composite
                    .add_field_shadowed(graph, field.colour_opacity, s),
                None => {
                    graph.note_skipped("composite", "no object and no shadow on screen");
                    field.colour_opacity
                }
            });
        }
        let draws: Vec<ObjectDraw<'_>> = shown
            .iter()
            .map(|&i| ObjectDraw {
                placed: &placed[i],
                gpu: &self.objects[i].gpu,
            })
            .collect();
        let g = self.gbuffer.add(graph, &frame, &draws)?;
        let clip = effects.occlusion.then_some(g.distance_id);
        let field = self.march.add(graph, &self.field, &frame, clip);
        let shown_lobes: Vec<_> = shown.iter().filter_map(|&i| lobes[i]).collect();
        let self_shadow: Vec<Option<SelfShadow>> = shown
            .iter()
            .map(|&i| match (&ssdf[i], fh) {
                (Some(ssdf), Some(fh_table)) if effects.self_shadow => Some(SelfShadow {
                    fh_table,
                    ssdf: *ssdf,
                }),
                _ => None,
            })
            .collect();
        if !effects.self_shadow {
            graph.note_skipped("self-shadow", "self-shadows off");
        }
        let object = self
            .shade
            .add(graph, &frame, &g, &shown_lobes, &self_shadow);
        let shadow = self.cast_shadows(graph, &frame, &field, &casts, &ssdf, &lobes, fh);
        let layering = if effects.occlusion {
            Layering::FieldOverObject
        } else {
            Layering::ObjectOverField
        };
        Ok(self
            .composite
            .add_layered(graph, field.colour_opacity, object, shadow, layering))
    }

    fn output_format(&self) -> vk::Format {
        COMPOSITE_FORMAT
    }
}

impl InsertionView {
    /// Chains one `cast-shadow` pass per object that `casts`; returns the
    /// product ρ image, or None when no object casts.
    #[allow(clippy::too_many_arguments)]
    fn cast_shadows<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        frame: &CameraFrame,
        field: &inlay_passes::march::MarchOutputs,
        casts: &[bool],
        ssdf: &[Option<inlay_passes::shadow::SsdfBindings>],
        lobes: &[Option<inlay_passes::lighting::LightLobes>],
        fh: Option<inlay_engine::graph::BufferHandle>,
    ) -> Option<ImageHandle> {
        let (cast, fh_table) = (self.cast.as_ref()?, fh?);
        let mut shadow = None;
        for i in 0..casts.len() {
            if let (true, Some(s), Some(l)) = (casts[i], ssdf[i], lobes[i]) {
                shadow = Some(cast.add(graph, &self.field, frame, field, l, fh_table, s, shadow));
            }
        }
        shadow
    }
}
