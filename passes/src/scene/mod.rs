//! Scene files (TOML): a field — a recipe of analytic primitives to bake or a
//! field file — plus the distant environment light, cameras and quality
//! knobs. `scenes/README.md` documents the format with an example.

mod checker;
mod environment;
mod face;
mod primitive;
mod shape;
pub(crate) mod spec;
pub mod vec3;

pub use crate::shadow::CastScale;
pub use checker::Checker;
pub use environment::{Environment, EquirectMap};
pub use face::Face;
#[cfg(test)]
pub(crate) use primitive::parse as parse_primitive;
pub use primitive::QUAD_THICKNESS;
pub use shape::Shape;

/// The largest radiance inlay accepts anywhere it is given one (an
/// emitter's `emission`, an environment lobe's amplitude or map texel
/// after `scale`, a field's colour): the SG fit and shading are tested
/// stable to it; beyond it (radiance near 10²⁰ and above) the fit's
/// residuals overflow f32 and would come out NaN, so such input is refused
/// with the key that holds it.
pub const RADIANCE_LIMIT: f64 = 1e6;

/// The most objects a scene inserts at once.
pub const MAX_OBJECTS: usize = 64;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use crate::bake::BakeKnobs;
use crate::camera::CameraSpec;
use crate::geometry::Aabb;
use crate::march::MarchKnobs;
use crate::object::{load_gltf, ObjectMesh, PlacedObject, Pose};
use spec::SceneSpec;

/// Why a scene file could not be used: the file, the key and the problem.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {field}: {message}")]
pub struct SceneError {
    /// The scene file.
    pub path: PathBuf,
    /// The key (dotted path) the problem is in.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// Where a scene's field comes from.
#[derive(Debug, Clone)]
pub enum FieldSource {
    /// Baked from analytic primitives.
    Recipe(Recipe),
    /// Read from a field file.
    File(PathBuf),
}

/// Analytic primitives and the bounds of the field baked from them.
#[derive(Debug, Clone)]
pub struct Recipe {
    /// The field's bounds; primitives outside still cast light and shadow.
    pub bounds: Aabb,
    /// The primitives.
    pub primitives: Vec<Primitive>,
}

/// One primitive of a recipe with its material.
#[derive(Debug, Clone)]
pub struct Primitive {
    /// Name, for messages.
    pub name: String,
    /// Geometry.
    pub shape: Shape,
    /// Lambertian albedo (surfaces) or single-scattering albedo (media).
    pub albedo: DVec3,
    /// A checkerboard alternating [`Self::albedo`] with a second colour
    /// (opaque surfaces only).
    pub checker: Option<Checker>,
    /// Emitted radiance (spheres: from all of the surface; quads: from
    /// [`Self::face`] only).
    pub emission: DVec3,
    /// For quads: the one face that emits.
    pub face: Option<Face>,
    /// `Some(σ)`: a homogeneous, semi-transparent medium of density σ
    /// scattering isotropically; `None`: an opaque surface.
    pub medium_density: Option<f64>,
    /// For emitters: whether the source lies inside the field's bounds.
    pub in_field: Option<bool>,
}

impl Primitive {
    /// Whether it emits light.
    pub fn is_emitter(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// The albedo at surface point `x`.
    pub fn albedo_at(&self, x: DVec3) -> DVec3 {
        self.checker
            .map_or(self.albedo, |c| c.albedo_at(self.albedo, x))
    }

    /// The radiance emitted from a surface point with outward normal `n`
    /// (a quad emits only from its face).
    pub fn emission_at(&self, n: DVec3) -> DVec3 {
        match self.face {
            Some(f) if n.dot(f.normal) < 0.5 => DVec3::ZERO,
            _ => self.emission,
        }
    }
}

impl Recipe {
    /// The surfaces and media (not lights) that cross the field's bounds,
    /// each with how far it reaches past them: the baked or trained field
    /// holds only the part inside, while a renderer of the primitives
    /// themselves (Cycles, `render_cycles.py`) draws all of it, so its
    /// pictures show what no field in these bounds can.
    pub fn crossing_bounds(&self) -> Vec<(&Primitive, f64)> {
        self.crossing(self.bounds)
    }

    /// The surfaces and media (not lights) that cross `b`, each with how
    /// far it reaches past it: [`Recipe::crossing_bounds`] for another box,
    /// such as a dataset's that was widened to hold them.
    pub fn crossing(&self, b: Aabb) -> Vec<(&Primitive, f64)> {
        self.primitives
            .iter()
            .filter(|p| !p.is_emitter())
            .filter_map(|p| {
                let e = p.shape.bounds()?;
                let past = (b.min - e.min).max(e.max - b.max).max_element();
                let inside = (e.min.cmplt(b.max) & e.max.cmpgt(b.min)).all();
                (inside && past > 1e-9 * b.diagonal()).then_some((p, past))
            })
            .collect()
    }

    /// Emitters inside the field's bounds, and those outside it.
    pub fn lights(&self) -> (Vec<&Primitive>, Vec<&Primitive>) {
        self.primitives
            .iter()
            .filter(|p| p.is_emitter())
            .partition(|p| p.in_field == Some(true))
    }
}

/// A validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it was read from.
    pub path: PathBuf,
    /// Short name.
    pub name: String,
    /// One line on what it shows.
    pub description: String,
    /// The field.
    pub field: FieldSource,
    /// The distant light (outside the field).
    pub environment: Environment,
    /// The file the environment was read from, if it is an equirect map
    /// (what a baked field depends on besides the scene's own text).
    pub environment_file: Option<PathBuf>,
    /// Cameras (at least one).
    pub cameras: Vec<CameraSpec>,
    /// Bake knobs (recipes).
    pub bake: BakeKnobs,
    /// March knobs.
    pub march: MarchKnobs,
    /// Incident-light knobs: the probe and the SG fit (`[lighting]`).
    pub lighting: LightingKnobs,
    /// Object shading knobs (`[shading]`).
    pub shading: ShadingKnobs,
    /// Virtual objects placed in the field (`[[objects]]`).
    pub objects: Vec<PlacedObject>,
    /// Where each object (same order) comes from and its SSDF field file.
    pub object_sources: Vec<ObjectSource>,
    /// Shadow knobs (`[shadows]`).
    pub shadows: ShadowKnobs,
    /// The distant light objects are lit with instead of [`Self::environment`]
    /// (`[lighting] environment`, an estimated environment file), if any.
    pub object_environment: Option<ObjectEnvironment>,
    /// Where a training set of the recipe is photographed from
    /// (`[capture]`; the whole cap by default).
    pub capture: crate::dataset::capture::Capture,
    /// The lights a trained field's photographs saw past its bounds (read
    /// from beside its file: [`crate::field::seen_lights`]; none for a
    /// scene as written). They light the objects where the scene names no
    /// environment file and the field is a file
    /// ([`crate::lighting::object_lights`]).
    pub seen_lights: Vec<crate::field::SeenLight>,
}

/// Distant light for the objects from an environment file.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectEnvironment {
    /// The file it was read from (or what it stands for).
    pub file: PathBuf,
    /// Its lobes.
    pub lobes: Vec<crate::sg::Sg64>,
    /// Its point lights near the field.
    pub lights: Vec<crate::envest::PointLight>,
    /// The lights seen past the field's bounds that it was estimated with
    /// (it holds them, so that a scene naming it needs no lights file).
    pub seen_lights: Vec<crate::field::SeenLight>,
}

impl ObjectEnvironment {
    /// The light read from environment file `file`.
    pub fn new(file: PathBuf, light: crate::envest::EstimatedLight) -> Self {
        Self {
            file,
            lobes: light.lobes,
            lights: light.lights,
            seen_lights: light.seen_lights,
        }
    }
}

/// An object's files, as the scene names them.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectSource {
    /// The glTF file.
    pub file: PathBuf,
    /// Its baked SSDF field, if the scene names one (else it is baked on
    /// first use and cached).
    pub ssdf: Option<PathBuf>,
}

/// Which shadows a scene draws and how (`[shadows]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowKnobs {
    /// Self-shadows on the objects (eq. 9).
    pub self_shadow: bool,
    /// Shadows cast onto the field (eq. 7–8).
    pub cast: bool,
    /// How the SSDF is read outside its grid.
    pub outside: crate::ssdf::OutsideMode,
    /// Knobs of the SSDF bakes this scene triggers.
    pub bake: crate::ssdf::SsdfKnobs,
    /// The cast shadow is taken at one pixel of each s × s block and
    /// brought back to full resolution (1: every pixel, the paper;
    /// [`crate::shadow::upsample`]), s fixed or growing with the image
    /// ([`CastScale`]). The default, automatic (2 up to 320 × 180, 4 at
    /// 640 × 360, 8 at 1280 × 720) with `cast_refine` 0.02, keeps ρ within
    /// 0.02 of the full resolution's on all but 0–0.05 % of each bundled
    /// scene's field pixels (docs/benchmarks.md, issue 26's third, seventh
    /// and tenth passes).
    pub cast_scale: CastScale,
    /// Above 1 `cast_scale`, a pixel whose neighbouring blocks' ρ spread
    /// by more than this (or of which fewer than two blocks lie on its
    /// surface) is taken exactly (`shadow-refine`), at each image from
    /// the cast scale's half to full resolution
    /// ([`crate::shadow::upsample::refine_levels`]); ≥ 1 refines none.
    pub cast_refine: f64,
}

impl Default for ShadowKnobs {
    fn default() -> Self {
        Self {
            self_shadow: true,
            cast: true,
            outside: crate::ssdf::OutsideMode::Correct,
            bake: crate::ssdf::SsdfKnobs::default(),
            cast_scale: CastScale::Auto,
            cast_refine: DEFAULT_CAST_REFINE,
        }
    }
}

/// The default `[shadows] cast_refine`.
pub const DEFAULT_CAST_REFINE: f64 = 0.02;

impl ShadowKnobs {
    /// Whether any shadow is drawn.
    pub fn any(&self) -> bool {
        self.self_shadow || self.cast
    }
}

/// The object shading's knobs, as a scene file sets them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShadingKnobs {
    /// SG lobes standing for GGX's distribution of normals (1 is the usual
    /// single lobe; see [`crate::brdf::NdfLobes`]).
    pub ndf_lobes: u32,
    /// Side of the rays per 8 × 8 pixel tile that take the field's light
    /// at the object's surface ([`crate::shade::field_light`]; 0: off, the
    /// paper's shading, every point lit by the lobes at the centre). Drawn
    /// with the self-shadows: without them the lobes alone light the object.
    pub field_light: u32,
    /// How many times 8 pixels a side the tiles are whose one point casts
    /// those rays (`"auto"`: 1 up to 639 × 359, growing with the image to 4
    /// at 1280 × 720; [`crate::shade::field_light::TileScale`]).
    pub field_light_scale: crate::shade::field_light::TileScale,
}

/// The default NDF lobe count: the most the shading accepts. One lobe (the
/// paper's) has no GGX tail, so a rough metal's highlight came out too
/// compact and its surroundings too dark: against Cycles, the median
/// per-pixel error on DOG's silver ball was 22.3 % with one lobe, 15.1 %
/// with four and 12.8 % with eight (BOOKS' gold sphere 16.7, 15.2, 13.5 %),
/// for 5 % more shading time (DOG at 1280 × 720 on lavapipe: the shade
/// pass 1022 → 1076 ms, the frame about 10.6 s).
pub const DEFAULT_NDF_LOBES: u32 = crate::brdf::MAX_NDF_LOBES;

/// The default `[shading] field_light`: 16 × 16 rays a tile. Against
/// Cycles it took PLANTS' toy among the foliage from a median error of
/// 0.167 to 0.121 (front) and 0.288 to 0.170 (high); ROOM's monkey and
/// CUPS' cube stayed within 0.002 of their figures; the metal balls of DOG
/// and BOOKS have no diffuse light and cast no rays. With fewer rays the
/// estimate is rougher (12²: 0.114 and 0.178; 8²: 0.136 and 0.226, the toy
/// 17 % too dark on the high view; `docs/fidelity.md`, sixteenth pass).
pub const DEFAULT_FIELD_LIGHT: u32 = 16;

impl Default for ShadingKnobs {
    fn default() -> Self {
        Self {
            ndf_lobes: DEFAULT_NDF_LOBES,
            field_light: DEFAULT_FIELD_LIGHT,
            field_light_scale: crate::shade::field_light::TileScale::Auto,
        }
    }
}

/// The probe's and the SG fit's knobs, as a scene file sets them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LightingKnobs {
    /// Probe layout and resolution.
    pub probe: crate::probe::ProbeKnobs,
    /// Lobes, iterations, damping.
    pub fit: crate::sgfit::FitKnobs,
    /// The field's light sources shaded per pixel.
    pub local: crate::lighting::LocalLightKnobs,
}

impl LightingKnobs {
    fn from_spec(spec: Option<&spec::LightingSpec>) -> Result<Self, (String, String)> {
        let d = Self::default();
        let Some(s) = spec else {
            return Ok(d);
        };
        let k = Self {
            probe: crate::probe::ProbeKnobs {
                map: s.probe_map.unwrap_or(d.probe.map),
                resolution: s.probe_resolution.unwrap_or(d.probe.resolution),
                supersampling: s.probe_supersampling.unwrap_or(d.probe.supersampling),
                stride: s.probe_stride.unwrap_or(d.probe.stride),
            },
            fit: crate::sgfit::FitKnobs {
                lobes: s.lobes.unwrap_or(d.fit.lobes),
                cold_iterations: s.cold_iterations.unwrap_or(d.fit.cold_iterations),
                warm_iterations: s.warm_iterations.unwrap_or(d.fit.warm_iterations),
                frame_iterations: s.frame_iterations.unwrap_or(d.fit.frame_iterations),
                damping: s.damping.unwrap_or(d.fit.damping),
            },
            local: crate::lighting::LocalLightKnobs {
                count: s.local_lights.unwrap_or(d.local.count),
                ratio: s.local_light_ratio.unwrap_or(d.local.ratio),
                share: s.local_light_share.unwrap_or(d.local.share),
                rays: s.local_light_rays.unwrap_or(d.local.rays),
            },
        };
        k.local.check()?;
        k.probe
            .check()
            .map_err(|(f, m)| (format!("probe_{f}"), m))?;
        k.fit.check()?;
        Ok(k)
    }
}

impl Scene {
    /// The camera named `which`, or at index `which`.
    pub fn camera(&self, which: &str) -> Result<&CameraSpec, SceneError> {
        let found = match which.parse::<usize>() {
            Ok(i) => self.cameras.get(i),
            Err(_) => self
                .cameras
                .iter()
                .find(|c| c.name.as_deref() == Some(which)),
        };
        found.ok_or_else(|| SceneError {
            path: self.path.clone(),
            field: "cameras".into(),
            message: format!(
                "no camera `{which}`; the scene has {}: {}",
                self.cameras.len(),
                self.cameras
                    .iter()
                    .enumerate()
                    .map(|(i, c)| format!(
                        "{i}{}",
                        c.name
                            .as_ref()
                            .map(|n| format!(" ({n})"))
                            .unwrap_or_default()
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
    }

    /// The recipe, if the field is baked from one.
    pub fn recipe(&self) -> Option<&Recipe> {
        match &self.field {
            FieldSource::Recipe(r) => Some(r),
            FieldSource::File(_) => None,
        }
    }
}

/// Reads and validates a scene file.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let e = |field: &str, message: String| SceneError {
        path: path.to_owned(),
        field: field.to_owned(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|x| e("file", x.to_string()))?;
    let mut spec: SceneSpec = crate::toml_file::parse_toml(&text).map_err(|(k, m)| e(&k, m))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let field = match (spec.field, spec.recipe) {
        (Some(f), None) => FieldSource::File(dir.join(f)),
        (None, Some(r)) => FieldSource::Recipe(recipe(r, &e)?),
        (Some(_), Some(_)) => {
            return Err(e(
                "field",
                "give either `field` (a file) or `[recipe]`, not both".into(),
            ))
        }
        (None, None) => {
            return Err(e(
                "field",
                "missing: give `field = \"file.inlayfield\"` or a `[recipe]`".into(),
            ))
        }
    };
    let mut environment_file = None;
    let environment = match spec.environment {
        None => Environment::Black,
        Some(env) => {
            let scale = env.scale.unwrap_or(1.0);
            if !(scale.is_finite() && scale >= 0.0) {
                return Err(e(
                    "environment.scale",
                    format!("{scale} must be finite and ≥ 0"),
                ));
            }
            for (i, l) in env.lobes.iter().enumerate() {
                if let Some(m) = crate::envest::file::lobe_problem(l) {
                    return Err(e(&format!("environment.lobes[{i}]"), m));
                }
                if l.amplitude.max_element() * scale > RADIANCE_LIMIT {
                    return Err(e(
                        "environment.scale",
                        format!(
                            "{scale} takes lobes[{i}]'s amplitude above the radiance limit {RADIANCE_LIMIT:e}"
                        ),
                    ));
                }
            }
            match (env.equirect, env.lobes.is_empty()) {
                (Some(_), false) => {
                    return Err(e(
                        "environment",
                        "give `lobes` or `equirect`, not both".into(),
                    ))
                }
                (Some(file), true) => {
                    let path = dir.join(&file);
                    let map = EquirectMap::load(&path, scale)
                        .map_err(|m| e("environment.equirect", m))?;
                    environment_file = Some(path);
                    Environment::Map(map)
                }
                (None, _) => Environment::from_lobes(
                    env.lobes
                        .into_iter()
                        .map(|mut l| {
                            l.amplitude *= scale;
                            l
                        })
                        .collect(),
                ),
            }
        }
    };
    let mut cameras = std::mem::take(&mut spec.cameras);
    if let Some(from) = &spec.cameras_from {
        let found = crate::dataset::scene_cameras(&dir.join(from), "train")
            .map_err(|d| e("cameras_from", d.to_string()))?;
        for c in &found {
            if c.off_centre {
                log::warn!(
                    "{}: camera `{}` of cameras_from has its principal point off centre; it is used centred",
                    path.display(),
                    c.spec.name.as_deref().unwrap_or("?")
                );
            }
        }
        cameras.extend(found.into_iter().map(|c| c.spec));
    }
    spec.cameras = cameras;
    if spec.cameras.is_empty() {
        return Err(e(
            "cameras",
            "a scene needs at least one [[cameras]] entry (or `cameras_from`)".into(),
        ));
    }
    for (i, c) in spec.cameras.iter().enumerate() {
        if let Some(p) = c.problem() {
            return Err(e(&format!("cameras[{i}]"), p));
        }
        // `--camera NAME` must find one camera, not the first of several.
        if let Some(n) = &c.name {
            if let Some(j) = spec.cameras[..i]
                .iter()
                .position(|d| d.name.as_ref() == Some(n))
            {
                return Err(e(
                    &format!("cameras[{i}].name"),
                    format!("duplicate name `{n}` (cameras[{j}] has it)"),
                ));
            }
        }
    }
    let bake =
        BakeKnobs::from_spec(spec.bake.as_ref()).map_err(|(f, m)| e(&format!("bake.{f}"), m))?;
    let march =
        MarchKnobs::from_spec(spec.march.as_ref()).map_err(|(f, m)| e(&format!("march.{f}"), m))?;
    let lighting = LightingKnobs::from_spec(spec.lighting.as_ref())
        .map_err(|(f, m)| e(&format!("lighting.{f}"), m))?;
    let object_environment = match spec.lighting.as_ref().and_then(|l| l.environment.as_ref()) {
        None => None,
        Some(file) => {
            let file = dir.join(file);
            let light = crate::envest::load_environment_file(&file)
                .map_err(|x| e("lighting.environment", x.to_string()))?;
            Some(ObjectEnvironment::new(file, light))
        }
    };
    let shading = ShadingKnobs {
        ndf_lobes: spec
            .shading
            .as_ref()
            .and_then(|s| s.ndf_lobes)
            .unwrap_or(ShadingKnobs::default().ndf_lobes),
        field_light: spec
            .shading
            .as_ref()
            .and_then(|s| s.field_light)
            .unwrap_or(ShadingKnobs::default().field_light),
        field_light_scale: {
            use crate::shade::field_light::{TileScale, MAX_TILE_SCALE};
            let value = spec
                .shading
                .as_ref()
                .and_then(|s| s.field_light_scale.as_ref());
            let default = ShadingKnobs::default().field_light_scale;
            spec::scale_knob(
                value,
                default,
                MAX_TILE_SCALE,
                TileScale::Auto,
                TileScale::Fixed,
            )
            .map_err(|m| e("shading.field_light_scale", m))?
        },
    };
    crate::brdf::NdfLobes::new(shading.ndf_lobes).map_err(|m| e("shading.ndf_lobes", m))?;
    if shading.field_light > crate::shade::field_light::MAX_SIDE {
        return Err(e(
            "shading.field_light",
            format!(
                "{} rays a side is more than the {} the shading holds (0 turns it off)",
                shading.field_light,
                crate::shade::field_light::MAX_SIDE
            ),
        ));
    }
    let shadows = {
        let d = ShadowKnobs::default();
        let sp = spec.shadows.as_ref();
        let bake = crate::ssdf::SsdfKnobs {
            grid: sp.and_then(|s| s.grid).unwrap_or(d.bake.grid),
            directions: sp.and_then(|s| s.directions).unwrap_or(d.bake.directions),
            components: sp.and_then(|s| s.components).unwrap_or(d.bake.components),
            coarse_angle: sp
                .and_then(|s| s.coarse_angle)
                .unwrap_or(d.bake.coarse_angle),
        };
        if let Some((k, m)) = bake.problem() {
            return Err(e(&format!("shadows.{k}"), m));
        }
        let max = crate::shadow::MAX_CAST_SCALE;
        let value = sp.and_then(|s| s.cast_scale.as_ref());
        let cast_scale =
            spec::scale_knob(value, d.cast_scale, max, CastScale::Auto, CastScale::Fixed)
                .map_err(|m| e("shadows.cast_scale", m))?;
        let cast_refine = sp.and_then(|s| s.cast_refine).unwrap_or(d.cast_refine);
        if !(cast_refine.is_finite() && cast_refine >= 0.0) {
            return Err(e(
                "shadows.cast_refine",
                format!("{cast_refine} must be a number ≥ 0 (≥ 1 refines no pixel)"),
            ));
        }
        ShadowKnobs {
            self_shadow: sp.and_then(|s| s.self_shadow).unwrap_or(d.self_shadow),
            cast: sp.and_then(|s| s.cast).unwrap_or(d.cast),
            outside: sp.and_then(|s| s.outside).unwrap_or(d.outside),
            bake,
            cast_scale,
            cast_refine,
        }
    };
    let capture = match spec.capture.and_then(|c| c.azimuth) {
        None => crate::dataset::capture::Capture::FULL,
        Some([azimuth_from, azimuth_to]) => {
            let c = crate::dataset::capture::Capture {
                azimuth_from,
                azimuth_to,
            };
            if let Some(m) = c.problem() {
                return Err(e("capture.azimuth", m));
            }
            c
        }
    };
    if spec.objects.len() > MAX_OBJECTS {
        return Err(e(
            "objects",
            format!(
                "{} objects; at most {MAX_OBJECTS} are inserted at once",
                spec.objects.len()
            ),
        ));
    }
    let mut objects = Vec::with_capacity(spec.objects.len());
    let mut object_sources = Vec::with_capacity(spec.objects.len());
    let mut meshes: std::collections::HashMap<PathBuf, Arc<ObjectMesh>> = Default::default();
    for (i, o) in spec.objects.into_iter().enumerate() {
        let f = |k: &str| format!("objects[{i}].{k}");
        let pose = Pose {
            position: o.position,
            rotation: o.rotation,
            scale: o.scale,
        };
        if let Some((k, m)) = pose.problem() {
            return Err(e(&f(k), m));
        }
        if let Some((k, m)) = o.material.problem() {
            return Err(e(&f(&format!("material.{k}")), m));
        }
        let file = dir.join(&o.file);
        let mesh = match meshes.get(&file) {
            Some(m) => m.clone(),
            None => {
                let m = Arc::new(load_gltf(&file).map_err(|x| e(&f("file"), x.to_string()))?);
                meshes.insert(file.clone(), m.clone());
                m
            }
        };
        let name = o.name.unwrap_or_else(|| {
            file.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        if let Some(j) = objects.iter().position(|q: &PlacedObject| q.name == name) {
            return Err(e(
                &f("name"),
                format!(
                    "duplicate name `{name}` (objects[{j}] has it; an object without a \
                     `name` takes its file's stem): give each object its own `name`"
                ),
            ));
        }
        objects.push(PlacedObject {
            name,
            mesh,
            pose,
            material: o.material,
        });
        let ssdf = o.ssdf.map(|f| dir.join(f));
        if let Some(path) = &ssdf {
            if !path.is_file() {
                return Err(e(
                    &f("ssdf"),
                    format!("{} does not exist (bake it with `inlay bake-ssdf`, or leave `ssdf` out to bake it on first use)", path.display()),
                ));
            }
        }
        object_sources.push(ObjectSource { file, ssdf });
    }
    let name = spec.name.unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    Ok(Scene {
        path: path.to_owned(),
        name,
        description: spec.description.unwrap_or_default(),
        field,
        environment,
        environment_file,
        cameras: spec.cameras,
        bake,
        march,
        lighting,
        shading,
        objects,
        object_sources,
        shadows,
        object_environment,
        capture,
        seen_lights: Vec::new(),
    })
}

fn recipe(
    spec: spec::RecipeSpec,
    e: &dyn Fn(&str, String) -> SceneError,
) -> Result<Recipe, SceneError> {
    let bounds = spec.bounds;
    if !bounds.is_valid() {
        return Err(e(
            "recipe.bounds",
            "min and max must be finite with min < max".into(),
        ));
    }
    let extent = bounds.size();
    if extent.min_element() < 1e-4 || extent.max_element() > 1e5 {
        return Err(e(
            "recipe.bounds",
            format!("extent {extent} is outside the supported 1e-4 ..= 1e5 per axis"),
        ));
    }
    let mut primitives = Vec::new();
    for (i, p) in spec.primitives.into_iter().enumerate() {
        let f = format!("recipe.primitives[{i}] ({})", p.name);
        let prim = primitive::parse(p, &bounds).map_err(|m| e(&f, m))?;
        if primitives.iter().any(|q: &Primitive| q.name == prim.name) {
            return Err(e(&f, "duplicate name".into()));
        }
        primitives.push(prim);
    }
    if primitives.is_empty() {
        return Err(e(
            "recipe.primitives",
            "a recipe needs at least one primitive".into(),
        ));
    }
    Ok(Recipe { bounds, primitives })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundled recipes whose surfaces reach past their bounds are
    /// found, by how far: CUPS' back wall 0.1 above the top, PLANTS' wall
    /// 0.05; DOG's and BOOKS' lie inside, and ROOM's emitting softbox is a
    /// light, not a surface.
    #[test]
    fn surfaces_crossing_the_bounds_are_found() {
        let crossing = |name: &str| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
            let scene = load_scene(&path).unwrap();
            scene
                .recipe()
                .unwrap()
                .crossing_bounds()
                .iter()
                .map(|(p, d)| (p.name.clone(), (d * 1e6).round() / 1e6))
                .collect::<Vec<_>>()
        };
        assert_eq!(crossing("cups"), [("back-wall".to_string(), 0.1)]);
        assert_eq!(crossing("plants"), [("wall".to_string(), 0.05)]);
        for inside in ["dog", "books", "room"] {
            assert_eq!(crossing(inside), [], "{inside}");
        }
    }
}
