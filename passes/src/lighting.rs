//! The object's incident light, per frame (METHOD.md §4.4 step 1): the
//! probe trace followed by the SG fit, run only when the object moved or
//! the field's lighting changed, warm-started from the previous fit.

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::Context;

use crate::field::GpuGridField;
use crate::march::MarchKnobs;
use crate::probe::{ProbeKnobs, ProbePass};
use crate::sg::Sg64;
use crate::sgfit::{FitKnobs, FitStart, SgFitPass};

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
    },
}

/// The probe and fit passes with the state that decides when they run.
pub struct IncidentLight {
    /// The probe trace.
    pub probe: ProbePass,
    /// The SG fit.
    pub fit: SgFitPass,
    last: std::sync::Mutex<Option<([u64; 3], u64)>>,
}

impl IncidentLight {
    /// Builds both passes; `environment` is L_env (empty: none).
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        probe: ProbeKnobs,
        fit: FitKnobs,
        march: MarchKnobs,
        environment: &[Sg64],
    ) -> anyhow::Result<Self> {
        let probe = ProbePass::new(ctx, lib, probe, march, environment)?;
        let fit = SgFitPass::new(ctx, lib, fit, probe.map())?;
        Ok(Self {
            probe,
            fit,
            last: Default::default(),
        })
    }

    /// Decides this frame's work for an object centred at `centre` in a
    /// field whose lighting is at `version` (bump it whenever the field or
    /// the environment light changes), and remembers them (interior
    /// mutability, so a view that builds frames through `&self` can plan).
    pub fn plan(&self, centre: DVec3, version: u64) -> LightingWork {
        let key = (centre.to_array().map(f64::to_bits), version);
        let knobs = *self.fit.knobs();
        let mut last = self.last.lock().unwrap_or_else(|p| p.into_inner());
        let work = match *last {
            None => LightingWork::Update {
                start: FitStart::Cold,
                iterations: knobs.cold_iterations,
            },
            Some(last) if last != key => LightingWork::Update {
                start: FitStart::Warm,
                iterations: knobs.warm_iterations,
            },
            Some(_) => LightingWork::Reuse,
        };
        *last = Some(key);
        work
    }

    /// Forgets the last fit: the next frame starts cold.
    pub fn reset(&self) {
        *self.last.lock().unwrap_or_else(|p| p.into_inner()) = None;
    }

    /// Adds the probe trace (with L_env) and the fit when `work` asks for
    /// them; returns the lobe buffer (as written this frame, or as the last
    /// fit left it).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        field: &GpuGridField,
        centre: DVec3,
        work: LightingWork,
    ) -> anyhow::Result<BufferHandle> {
        self.add_with(graph, field, centre, work, true)
    }

    /// As [`Self::add`], with the L_env term left out of the probe when
    /// `environment` is false (fold that switch into the `version` given
    /// to [`Self::plan`]). A frame that reuses the fit notes both passes as
    /// skipped.
    pub fn add_with<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        field: &GpuGridField,
        centre: DVec3,
        work: LightingWork,
        environment: bool,
    ) -> anyhow::Result<BufferHandle> {
        match work {
            LightingWork::Reuse => {
                graph.note_skipped("probe-trace", "object and lighting unchanged");
                graph.note_skipped("sg-fit", "object and lighting unchanged");
                Ok(graph.import_buffer(self.fit.lobes(), None))
            }
            LightingWork::Update { start, iterations } => {
                let probe = self.probe.add_with(graph, field, centre, environment);
                self.fit.add(graph, probe, start, iterations)
            }
        }
    }
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
