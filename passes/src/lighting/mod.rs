//! The object's incident light, per frame (METHOD.md §4.4 step 1): the
//! probe trace followed by the SG fit, run only when the object moved or
//! the field's lighting changed, warm-started from the previous fit; and,
//! where L_env has lobes sharper than the fit can hold, those lobes shaded
//! directly with the field's transmittance towards them ([`sharp`]).

pub(crate) mod direct_pass;
pub mod direct_reference;
pub mod local;
pub mod sharp;

pub use direct_pass::{DirectLightPass, DirectRayCounts, DIRECT_LIGHT, DIRECT_LIGHT_INFO};
pub use direct_reference::direct_lights;
pub use local::{LocalLight, LocalLightKnobs};
pub use sharp::{lobe_rays, split_environment, SplitEnvironment};

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::Context;

use crate::field::GpuGridField;
use crate::march::MarchKnobs;
use crate::probe::{EnvironmentLobes, ProbeKnobs, ProbePass, ProbeTexels, PROBE_TRACE};
use crate::scene::Scene;
use crate::sg::Sg64;
use crate::sgfit::{FitKnobs, FitStart, SgFitPass, SG_FIT};

/// What a frame has to do for the incident light.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightingWork {
    /// Nothing changed: the lobes of the last fit stand.
    Reuse,
    /// Trace the probe and fit from `start` for `iterations` iterations.
    Update {
        /// Cold on the first frame, warm afterwards.
        start: FitStart,
        /// Iterations of the fit.
        iterations: u32,
        /// The texels traced (every one, or this update's share of a
        /// strided trace, [`crate::probe::ProbeKnobs::stride`]).
        texels: ProbeTexels,
    },
    /// Go on with the last fit on the last probe for `iterations` more
    /// (the object is still; the update it began is not finished).
    Continue {
        /// Iterations this frame.
        iterations: u32,
    },
    /// A moving object's frame with its lighting interleaved
    /// ([`IncidentLight::set_interleave`]): trace this update's share of
    /// the probe where the object now is; the lobes stand as they are.
    Trace {
        /// The texels traced.
        texels: ProbeTexels,
    },
    /// The frame after a [`LightingWork::Trace`] while the object still
    /// moves: a warm update of `iterations` on the probe as it stands.
    Fit {
        /// Iterations this frame.
        iterations: u32,
    },
}

/// The lobes an object is shaded with, as a frame sees them: a buffer of
/// packed lobes ((p, λ), (μ, 0)) whose first `count` are the light (the
/// fit's buffer holds its iterate and its candidate after them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LightLobes {
    /// The buffer.
    pub buffer: BufferHandle,
    /// How many lobes, from the start, are the light.
    pub count: u32,
    /// The direct lobes at the end of those, when there are any.
    pub direct: Option<DirectRays>,
    /// The broad lobes of L_env the probe added beyond the field (None
    /// when there are none or the environment is switched off): what the
    /// field's light at the object's surface sees past the field
    /// ([`crate::shade::field_light`]).
    pub environment: Option<EnvironmentLobes>,
}

/// The last `lobes` lobes of a [`LightLobes`] are direct (too sharp for the
/// fit), shadowed by casting their rays against the object's mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DirectRays {
    /// How many direct lobes.
    pub lobes: u32,
    /// Each lobe's rays, `rays_per_lobe` world directions (xyz, w unused)
    /// after another ([`lobe_rays`]).
    pub rays: BufferHandle,
    /// Rays per lobe.
    pub rays_per_lobe: u32,
    /// The local lights, last among the direct lobes (`count` may be 0:
    /// the buffer is bound all the same).
    pub local: LocalLightBindings,
}

/// The last `count` direct lobes are local lights ([`local`]), shaded per
/// pixel from their spheres and intensities.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LocalLightBindings {
    /// Each light's (centre, radius), (intensity, radius of the disk it
    /// shines from; 0 while inactive) as the direct pass wrote them.
    pub lights: BufferHandle,
    /// How many.
    pub count: u32,
    /// Side of each light's visibility rays (side² per shaded point).
    pub side: u32,
}

/// The probe and fit passes with the state that decides when they run.
pub struct IncidentLight {
    /// The probe trace (of the broad lobes of L_env).
    pub probe: ProbePass,
    /// The SG fit.
    pub fit: SgFitPass,
    /// The sharp lobes of L_env, shaded directly (None when there are
    /// none: the fit's lobes are the whole light).
    pub direct: Option<DirectLightPass>,
    /// The object's centre and the lighting version of the last fit.
    last: Option<([u64; 3], u64)>,
    /// Iterations of the last warm update still to run.
    pending: u32,
    /// The strided trace's next update ([`ProbeTexels::Phase`]).
    phase: u32,
    /// Of the probe's `stride`² shares, how many were traced where the
    /// object now is, for the lighting it now has.
    fresh: u32,
    /// Whether a moving object's frames trace and fit in turn.
    interleave: bool,
    /// With `interleave`: the last frame traced, so this one fits.
    fit_due: bool,
}

impl IncidentLight {
    /// Builds the passes; `environment` is L_env (empty: none). Its lobes
    /// sharper than the fit can hold on this probe
    /// ([`crate::sgfit::model::max_sharpness`]) skip the probe and are
    /// shaded directly, each attenuated along `probe.supersampling`² rays
    /// (a sharp lobe is integrated as a texel is). The `local` lights leave
    /// the probe and are shaded per pixel along `local_side`² rays.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        probe: ProbeKnobs,
        fit: FitKnobs,
        march: MarchKnobs,
        environment: &[Sg64],
        local: &[LocalLight],
        local_side: u32,
    ) -> anyhow::Result<Self> {
        // The cast shadow keeps one arrival per local light in an array of
        // MAX_LOCAL_LIGHTS (shaders/shadow/cast_body.wgsl): more would
        // write past it, silently.
        anyhow::ensure!(
            local.len() <= local::MAX_LOCAL_LIGHTS as usize,
            "{} local lights light the object (the field's, up to `[lighting] local_lights`, and \
             those outside it: a recipe's hidden bulbs, an environment file's point lights or the \
             lights seen past a trained field's bounds); at most {} are shaded: lower \
             `local_lights`",
            local.len(),
            local::MAX_LOCAL_LIGHTS
        );
        let split = split_environment(environment, sharp_limit(&probe));
        let side = probe.supersampling;
        let probe = ProbePass::new(ctx, lib, probe, march, &split.broad, local)?;
        let direct = DirectLightPass::new(
            ctx,
            lib,
            fit.lobes,
            &split.sharp,
            side,
            local,
            local_side,
            march,
        )?;
        let fit = SgFitPass::new(ctx, lib, fit, probe.map())?;
        Ok(Self {
            probe,
            fit,
            direct,
            last: Default::default(),
            pending: 0,
            phase: 0,
            fresh: 0,
            interleave: false,
            fit_due: false,
        })
    }

    /// Interleaves a moving object's lighting (not in the paper): each
    /// frame while it moves either traces its share of the probe
    /// ([`LightingWork::Trace`]) or runs the warm update's iterations on
    /// the probe as it stands ([`LightingWork::Fit`]), in turn, so a frame
    /// carries about half of the lighting's work and the lobes follow the
    /// object a frame later. Once it stops, the frames go on as without
    /// (a share and the update's iterations each frame), to the same lobes.
    pub fn set_interleave(&mut self, on: bool) {
        self.interleave = on;
        self.fit_due = false;
    }

    /// Whether any environment light is evaluated (broad lobes in the
    /// probe, sharp ones shaded directly, or lights outside the field).
    pub fn has_environment(&self) -> bool {
        self.probe.has_environment() || self.direct.as_ref().is_some_and(|d| d.has_environment())
    }

    /// Decides this frame's work for an object centred at `centre` in a
    /// field whose lighting is at `version` (bump it whenever the field or
    /// the environment light changes), and remembers them: a cold fit
    /// first; a warm update when either changed, at most the fit's
    /// `frame_iterations` of it this frame; while the object stays, the
    /// rest of that update continued; then nothing. With a strided probe
    /// ([`crate::probe::ProbeKnobs::stride`] s > 1) a warm update traces
    /// one texel of each s × s block; while the object stays, each frame
    /// traces the next share and starts the update again from the lobes it
    /// has, until the probe is whole where the object stands (s² − 1
    /// frames after it stopped), and the update on the whole probe then
    /// runs to its end as above. Interleaved ([`Self::set_interleave`]),
    /// a moving object's frames trace a share and fit in turn.
    pub fn plan(&mut self, centre: DVec3, version: u64) -> LightingWork {
        let key = (centre.to_array().map(f64::to_bits), version);
        let knobs = *self.fit.knobs();
        let phases = self.probe.knobs().phases();
        let chunk = |n: u32| match knobs.frame_iterations {
            0 => n,
            f => n.min(f),
        };
        let share = |light: &mut Self| -> LightingWork {
            let texels = if phases <= 1 {
                ProbeTexels::All
            } else {
                ProbeTexels::Phase(light.phase)
            };
            light.phase = (light.phase + 1) % phases.max(1);
            light.fresh = (light.fresh + 1).min(phases);
            let n = chunk(knobs.warm_iterations);
            // The update runs to its end only on a whole probe.
            light.pending = if light.fresh == phases {
                knobs.warm_iterations - n
            } else {
                0
            };
            LightingWork::Update {
                start: FitStart::Warm,
                iterations: n,
                texels,
            }
        };
        let work = match self.last {
            None => {
                self.pending = 0;
                self.fresh = phases;
                LightingWork::Update {
                    start: FitStart::Cold,
                    iterations: knobs.cold_iterations,
                    texels: ProbeTexels::All,
                }
            }
            Some(last) if last != key && self.interleave && self.fit_due => {
                self.fresh = 0;
                self.fit_due = false;
                self.pending = 0;
                LightingWork::Fit {
                    iterations: chunk(knobs.warm_iterations),
                }
            }
            Some(last) if last != key && self.interleave => {
                self.fresh = 0;
                self.fit_due = true;
                let texels = match share(self) {
                    LightingWork::Update { texels, .. } => texels,
                    _ => unreachable!("a share is an update"),
                };
                self.pending = 0;
                LightingWork::Trace { texels }
            }
            Some(last) if last != key => {
                self.fresh = 0;
                share(self)
            }
            // Interleaved, the object stopped right after a frame that
            // traced the last share of a whole probe: its update, which no
            // frame has begun, runs now.
            Some(_) if self.fit_due && self.fresh == phases => {
                self.fit_due = false;
                let n = chunk(knobs.warm_iterations);
                self.pending = knobs.warm_iterations - n;
                LightingWork::Fit { iterations: n }
            }
            Some(_) if self.fresh < phases => {
                self.fit_due = false;
                share(self)
            }
            Some(_) if self.pending > 0 => {
                let n = chunk(self.pending);
                self.pending -= n;
                LightingWork::Continue { iterations: n }
            }
            Some(_) => LightingWork::Reuse,
        };
        self.last = Some(key);
        work
    }

    /// Forgets the last fit: the next frame starts cold.
    pub fn reset(&mut self) {
        self.last = None;
        self.pending = 0;
        self.fresh = 0;
        self.fit_due = false;
    }

    /// Adds the probe trace (with L_env) and the fit when `work` asks for
    /// them, then the direct light; returns the shading lobes (as written
    /// this frame, or as the last run left them).
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        centre: DVec3,
        work: LightingWork,
    ) -> anyhow::Result<LightLobes> {
        self.add_with(graph, field, centre, work, true)
    }

    /// As [`Self::add`], with L_env left out (the probe's term and the
    /// sharp lobes) when `environment` is false (fold that switch into the
    /// `version` given to [`Self::plan`]). A frame that reuses the fit
    /// notes its passes as skipped.
    pub fn add_with(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        centre: DVec3,
        work: LightingWork,
        environment: bool,
    ) -> anyhow::Result<LightLobes> {
        let mut lights = self.add_lobes(graph, field, centre, work, environment)?;
        lights.environment = if environment {
            self.probe.environment_lobes(graph)
        } else {
            None
        };
        Ok(lights)
    }

    /// [`Self::add_with`]'s passes and lobes, before L_env's are attached.
    fn add_lobes(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        centre: DVec3,
        work: LightingWork,
        environment: bool,
    ) -> anyhow::Result<LightLobes> {
        let fitted = self.fit.knobs().lobes;
        // The field's own local lights are shaded with the environment off
        // too (its sharp lobes and outside lights then black).
        let direct = self
            .direct
            .as_ref()
            .filter(|d| environment || d.has_field_lights());
        if self.direct.is_some() && direct.is_none() {
            graph.note_skipped(DIRECT_LIGHT, "environment light off");
        }
        match work {
            LightingWork::Reuse => {
                graph.note_skipped(PROBE_TRACE, "object and lighting unchanged");
                graph.note_skipped(SG_FIT, "object and lighting unchanged");
                if direct.is_some() {
                    graph.note_skipped(DIRECT_LIGHT, "object and lighting unchanged");
                }
                Ok(match direct {
                    Some(d) => d.reused(graph),
                    None => LightLobes {
                        buffer: graph.import_buffer(self.fit.lobes(), None),
                        count: fitted,
                        direct: None,
                        environment: None,
                    },
                })
            }
            LightingWork::Continue { iterations } => {
                graph.note_skipped(PROBE_TRACE, "the fit goes on with the last probe");
                let probe = self.probe.import(graph);
                let lobes = self.fit.add(graph, probe, FitStart::Continue, iterations)?;
                Ok(self.with_direct(graph, field, centre, lobes, environment, direct, true))
            }
            LightingWork::Trace { texels } => {
                graph.note_skipped(
                    SG_FIT,
                    "interleaved: the probe traced this frame, fitted the next",
                );
                self.probe
                    .add_with(graph, field, centre, environment, texels);
                let lobes = graph.import_buffer(self.fit.lobes(), None);
                Ok(self.with_direct(graph, field, centre, lobes, environment, direct, false))
            }
            LightingWork::Fit { iterations } => {
                graph.note_skipped(
                    PROBE_TRACE,
                    "interleaved: fitted on the probe traced last frame",
                );
                let probe = self.probe.import(graph);
                let lobes = self.fit.add(graph, probe, FitStart::Warm, iterations)?;
                Ok(self.with_direct(graph, field, centre, lobes, environment, direct, false))
            }
            LightingWork::Update {
                start,
                iterations,
                texels,
            } => {
                let probe = self
                    .probe
                    .add_with(graph, field, centre, environment, texels);
                let lobes = self.fit.add(graph, probe, start, iterations)?;
                Ok(self.with_direct(graph, field, centre, lobes, environment, direct, false))
            }
        }
    }

    /// The shading lobes from the fit's `lobes` as written this frame:
    /// with the `direct` light's pass, its sharp lobes and local lights
    /// assembled after them (only the fitted lobes copied, with
    /// `fitted_only`, when the object has not moved); without, the fit's
    /// lobes alone.
    #[allow(clippy::too_many_arguments)]
    fn with_direct(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        centre: DVec3,
        lobes: BufferHandle,
        environment: bool,
        direct: Option<&DirectLightPass>,
        fitted_only: bool,
    ) -> LightLobes {
        match direct {
            Some(d) => d.add_with(graph, field, centre, lobes, environment, fitted_only),
            None => LightLobes {
                buffer: lobes,
                count: self.fit.knobs().lobes,
                direct: None,
                environment: None,
            },
        }
    }

    /// Adds readbacks of the fit and of the direct light;
    /// [`Self::read_lights`] reads them once the frame has finished.
    pub fn add_readback(&self, graph: &mut FrameGraph) {
        self.fit.add_readback(graph);
        if let Some(d) = &self.direct {
            d.add_readback(graph);
        }
    }

    /// The shading lobes of the frame that carried [`Self::add_readback`]
    /// (with the environment on): the fitted lobes, then the sharp ones.
    pub fn read_lights(&self) -> anyhow::Result<Vec<crate::sg::Sg32>> {
        match &self.direct {
            Some(d) => d.read(),
            None => Ok(self.fit.read_report()?.lobes),
        }
    }
}

/// The sharpness above which a lobe of L_env is shaded directly on a probe
/// of `knobs`: the fit's largest ([`crate::sgfit::model::max_sharpness`]).
pub fn sharp_limit(knobs: &ProbeKnobs) -> f64 {
    crate::sgfit::model::max_sharpness(knobs.direction_map().texels())
}

/// The distant light L_env an object at `at` is lit with, as SG lobes:
/// the environment file's if the scene names one (its near point
/// lights and the lights seen past the bounds it was estimated with as
/// lobes seen from `at`); otherwise, for a
/// recipe, the whole light from outside the field — the declared
/// environment and every emitter outside the bounds as a lobe seen
/// from `at` ([`crate::envest::hidden_light_lobes`]), since an object in
/// the recipe's world is lit by those lights as the field is (seen from
/// the field's centre instead, ROOM's bulb 2.7 m above its monkey lit
/// it 1.33× too brightly); for a field file, the declared environment
/// ([`environment_lobes`]) and the lights its photographs saw past its
/// bounds ([`Scene::seen_lights`]), each a lobe seen from `at`.
pub fn object_light_lobes(scene: &Scene, at: DVec3) -> Vec<Sg64> {
    match (&scene.object_environment, scene.recipe()) {
        (Some(o), _) => o
            .lobes
            .iter()
            .copied()
            .chain(
                o.lights
                    .iter()
                    .map(|l| l.lobe_from(at, crate::sgfit::model::MAX_SHARPNESS)),
            )
            .chain(o.seen_lights.iter().map(|l| seen_light_lobe(l, at)))
            .collect(),
        (None, Some(r)) => crate::envest::hidden_light_lobes(
            r,
            &scene.environment,
            at,
            crate::sgfit::model::MAX_SHARPNESS,
        ),
        (None, None) => environment_lobes(&scene.environment)
            .into_iter()
            .chain(scene.seen_lights.iter().map(|l| seen_light_lobe(l, at)))
            .collect(),
    }
}

/// A light seen past a field file's bounds ([`Scene::seen_lights`]) as a
/// lobe seen from `at`: a point light of its intensity (π r² L) at its
/// centre.
fn seen_light_lobe(l: &crate::field::SeenLight, at: DVec3) -> Sg64 {
    crate::envest::PointLight {
        position: l.centre,
        intensity: l.intensity(),
    }
    .lobe_from(at, crate::sgfit::model::MAX_SHARPNESS)
}

/// The light an object at `at` is lit with from outside the field, split
/// for shading: distant lobes, and the lights with a position, shaded per
/// pixel as local lights ([`local`]) when `local` is on: a recipe's
/// hidden balls (a ceiling bulb), an environment file's point lights and
/// the seen lights it was estimated with, and a field file's lights seen
/// past its bounds ([`Scene::seen_lights`]) where no environment file is
/// named.
/// Seen from one point, a bulb 1.5 m above a 50 cm object comes from one
/// direction at one distance; per pixel its direction, its fall-off and
/// the field between are each point's own. With `local` off, all of it is
/// lobes ([`object_light_lobes`]).
pub fn object_lights(scene: &Scene, at: DVec3, local: bool) -> (Vec<Sg64>, Vec<LocalLight>) {
    use crate::scene::Shape;
    if !local {
        return (object_light_lobes(scene, at), Vec::new());
    }
    match (&scene.object_environment, scene.recipe()) {
        (Some(o), _) => {
            let mut balls: Vec<LocalLight> = o
                .lights
                .iter()
                .map(|l| LocalLight::known_point(l.position, l.intensity))
                .collect();
            let room = (local::MAX_LOCAL_LIGHTS as usize).saturating_sub(balls.len());
            let (lobes, seen) = seen_lights_split(&o.seen_lights, at, room);
            balls.extend(seen);
            (o.lobes.iter().copied().chain(lobes).collect(), balls)
        }
        (None, Some(r)) => {
            let ball = |p: &crate::scene::Primitive| match p.shape {
                Shape::Sphere { centre, radius } => {
                    Some(LocalLight::known_ball(centre, radius, p.emission))
                }
                _ => None,
            };
            let lobes = crate::envest::hidden_light_lobes_except(
                r,
                &scene.environment,
                at,
                crate::sgfit::model::MAX_SHARPNESS,
                |p| ball(p).is_some(),
            );
            let (_, outside) = r.lights();
            (lobes, outside.into_iter().filter_map(ball).collect())
        }
        (None, None) => {
            let room = local::MAX_LOCAL_LIGHTS as usize;
            let (lobes, balls) = seen_lights_split(&scene.seen_lights, at, room);
            let lobes = environment_lobes(&scene.environment)
                .into_iter()
                .chain(lobes)
                .collect();
            (lobes, balls)
        }
    }
}

/// Lights seen past a field's bounds, for an object at `at`: the brightest
/// `room` as local lights (balls), any more as lobes seen from `at` (a
/// capture with many lamps is lit, not refused).
fn seen_lights_split(
    seen: &[crate::field::SeenLight],
    at: DVec3,
    room: usize,
) -> (Vec<Sg64>, Vec<LocalLight>) {
    let mut seen: Vec<_> = seen.iter().collect();
    let power = |l: &&crate::field::SeenLight| crate::sgfit::model::luminance(l.intensity());
    seen.sort_by(|a, b| power(b).total_cmp(&power(a)));
    let (near, far) = seen.split_at(seen.len().min(room));
    let lobes = far.iter().map(|l| seen_light_lobe(l, at)).collect();
    let balls = near
        .iter()
        .map(|l| LocalLight::known_ball(l.centre, l.radius, l.radiance))
        .collect();
    (lobes, balls)
}

/// The distant light L_env as M SG lobes from a scene's declared
/// environment: none for a black one, its own lobes for an SG one, and for
/// an equirect map an SG fit (f64 reference LM, [`FitKnobs::default`], cold
/// start) of the map sampled on an octahedral 32 × 32 probe. This is the
/// scene author's ground truth; the estimated L_env (METHOD.md eq. 3-4)
/// replaces it where the environment is unknown.
pub fn environment_lobes(env: &crate::scene::Environment) -> Vec<Sg64> {
    use crate::scene::Environment;
    match env {
        Environment::Black => Vec::new(),
        Environment::Lobes { lobes, .. } => lobes.clone(),
        Environment::Map(map) => {
            let dirs = ProbeKnobs::default().direction_map();
            let texels: Vec<[f64; 4]> = (0..dirs.texels())
                .map(|i| {
                    let l = map.eval(dirs.direction(i as u32 % dirs.width, i as u32 / dirs.width));
                    [l.x, l.y, l.z, 0.0]
                })
                .collect();
            let samples = crate::sgfit::ProbeSamples::new(&dirs, &texels);
            let knobs = FitKnobs::default();
            crate::sgfit::fit_reference(
                &samples,
                &knobs,
                crate::sgfit::Start::Cold,
                knobs.cold_iterations,
            )
            .lobes
        }
    }
}
