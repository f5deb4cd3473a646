//! The raw TOML shape of a scene file, as serde reads it. [`super::load_scene`]
//! validates it into a [`super::Scene`]; unknown keys are errors so typos
//! do not pass silently.

use glam::DVec3;
use serde::Deserialize;

use crate::camera::CameraSpec;
use crate::sg::SgLobe;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneSpec {
    pub name: Option<String>,
    #[serde(default)]
    pub description: Option<String>,
    /// A field file, relative to the scene file.
    pub field: Option<String>,
    pub recipe: Option<RecipeSpec>,
    #[serde(default)]
    pub environment: Option<EnvironmentSpec>,
    #[serde(default)]
    pub cameras: Vec<CameraSpec>,
    /// A dataset (transforms.json or its folder, relative to the scene
    /// file) whose frames' cameras join `cameras`.
    #[serde(default)]
    pub cameras_from: Option<String>,
    #[serde(default)]
    pub bake: Option<BakeSpec>,
    #[serde(default)]
    pub march: Option<MarchSpec>,
    #[serde(default)]
    pub lighting: Option<LightingSpec>,
    #[serde(default)]
    pub shading: Option<ShadingSpec>,
    #[serde(default)]
    pub shadows: Option<ShadowsSpec>,
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
    #[serde(default)]
    pub capture: Option<CaptureSpec>,
}

/// `[capture]`: where `inlay render-views` may put its cameras.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CaptureSpec {
    /// [from, to] in degrees from +x towards +z.
    pub azimuth: Option<[f64; 2]>,
}

/// `[shadows]`: which shadows are drawn, how the SSDF is read outside its
/// grid, and the knobs of SSDF bakes the scene triggers.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShadowsSpec {
    #[serde(rename = "self")]
    pub self_shadow: Option<bool>,
    pub cast: Option<bool>,
    pub outside: Option<crate::ssdf::OutsideMode>,
    pub grid: Option<u32>,
    pub directions: Option<u32>,
    pub components: Option<u32>,
    pub coarse_angle: Option<f64>,
    pub cast_scale: Option<ScaleSpec>,
    pub cast_refine: Option<f64>,
}

/// A scale knob (`[shadows] cast_scale`, `[shading] field_light_scale`): a
/// whole number, or a word (`"auto"`); anything else is kept to be refused
/// by name.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(crate) enum ScaleSpec {
    Number(i64),
    Word(String),
    Other(serde::de::IgnoredAny),
}

impl ScaleSpec {
    /// The value as an error message starts with it (`3 `, `"half" `), or
    /// nothing for a value of another type.
    pub(crate) fn shown(&self) -> String {
        match self {
            ScaleSpec::Number(n) => format!("{n} "),
            ScaleSpec::Word(w) => format!("\"{w}\" "),
            ScaleSpec::Other(_) => String::new(),
        }
    }
}

/// The scale knob `value`: `default` where it is absent, `auto` for
/// `"auto"`, `fixed(k)` for a whole number k in 1..=`max`; else why not.
pub(crate) fn scale_knob<T>(
    value: Option<&ScaleSpec>,
    default: T,
    max: u32,
    auto: T,
    fixed: impl Fn(u32) -> T,
) -> Result<T, String> {
    match value {
        None => Ok(default),
        Some(ScaleSpec::Word(w)) if w == "auto" => Ok(auto),
        Some(ScaleSpec::Number(n)) if (1..=max as i64).contains(n) => Ok(fixed(*n as u32)),
        Some(other) => Err(format!(
            "{}must be \"auto\" or a whole number in 1..={max}",
            other.shown()
        )),
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShadingSpec {
    pub ndf_lobes: Option<u32>,
    pub field_light: Option<u32>,
    pub field_light_scale: Option<ScaleSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ObjectSpec {
    pub name: Option<String>,
    /// A .gltf or .glb file, relative to the scene file.
    pub file: String,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact")]
    pub position: DVec3,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact")]
    pub rotation: DVec3,
    #[serde(default)]
    pub scale: crate::object::Scale,
    #[serde(default)]
    pub material: crate::object::MaterialOverride,
    pub ssdf: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RecipeSpec {
    pub bounds: crate::geometry::Aabb,
    #[serde(default)]
    pub primitives: Vec<PrimitiveSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PrimitiveSpec {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub point: Option<DVec3>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub normal: Option<DVec3>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub center: Option<DVec3>,
    pub radius: Option<f64>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub size: Option<DVec3>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub axis: Option<DVec3>,
    pub height: Option<f64>,
    pub width: Option<f64>,
    pub thickness: Option<f64>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub up: Option<DVec3>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub rotation: Option<DVec3>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub albedo: Option<DVec3>,
    pub checker: Option<super::Checker>,
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub emission: Option<DVec3>,
    pub density: Option<f64>,
    pub in_field: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EnvironmentSpec {
    #[serde(default)]
    pub lobes: Vec<SgLobe>,
    pub equirect: Option<String>,
    pub scale: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BakeSpec {
    pub resolution: Option<u32>,
    pub samples: Option<u32>,
    pub bounces: Option<u32>,
    pub seed: Option<u64>,
    pub falloff_voxels: Option<f64>,
    pub density_scale: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MarchSpec {
    pub samples_per_ray: Option<u32>,
    pub termination: Option<f64>,
    pub skip_empty: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightingSpec {
    pub probe_map: Option<crate::probe::MapKind>,
    pub probe_resolution: Option<u32>,
    pub probe_supersampling: Option<u32>,
    pub probe_stride: Option<u32>,
    pub lobes: Option<u32>,
    pub cold_iterations: Option<u32>,
    pub warm_iterations: Option<u32>,
    pub frame_iterations: Option<u32>,
    pub damping: Option<f64>,
    pub environment: Option<String>,
    pub local_lights: Option<u32>,
    pub local_light_ratio: Option<f64>,
    pub local_light_share: Option<f64>,
    pub local_light_rays: Option<u32>,
}
