//! The environment file `inlay estimate-env` writes and scene files name
//! (`[lighting] environment = "file"`): TOML holding SG lobes in the same
//! form as a scene's `[environment] lobes`, the point lights the estimate
//! placed near the field, and the lights the field's photographs saw past
//! its bounds, which the estimate took as known (so that the file holds
//! all the light from outside the field, and a scene that names it needs
//! nothing else).
//!
//! ```toml
//! format = "inlay-environment"   # required, exactly this
//! version = 1                    # required, this reader's ENV_FILE_VERSION
//! source = "books"               # optional: the scene it was estimated from
//! [estimate]                     # optional: how (knobs, timings, loss); not read
//! views = 100
//! [[lobes]]                      # any number; none is a black environment
//! direction = [0.5, 0.8, 0.35]   # finite, non-zero (normalised on load)
//! sharpness = 120.0              # in (0, 1e4]
//! amplitude = [9.0, 8.4, 7.4]    # RGB radiance on the axis, finite, ≥ 0
//! [[lights]]                     # optional: point lights near the field
//! position = [0.1, 2.9, 0.3]     # finite (scene units)
//! intensity = [22.0, 20.0, 17.0] # RGB radiant intensity, finite, ≥ 0
//! [[seen_lights]]                # optional: spheres seen past the bounds
//! centre = [0.198, 2.894, 0.298] # finite (scene units)
//! radius = 0.03                  # finite, > 0
//! radiance = [7954, 7358, 6364]  # RGB radiance, finite, ≥ 0
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::near_lights::PointLight;
use crate::field::seen_lights::file::LightSpec;
use crate::field::SeenLight;
use crate::sg::Sg64;
use crate::toml_file::{check_format, parse_toml};

/// What an environment file holds: distant lobes, near point lights and
/// the lights seen past the field's bounds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EstimatedLight {
    /// The distant lobes.
    pub lobes: Vec<Sg64>,
    /// The point lights near the field.
    pub lights: Vec<PointLight>,
    /// The lights the field's photographs saw past its bounds, taken as
    /// known by the estimate.
    pub seen_lights: Vec<SeenLight>,
}

/// The version this reader understands.
pub const ENV_FILE_VERSION: u32 = 1;

/// The `format` value of an environment file.
pub const ENV_FILE_FORMAT: &str = "inlay-environment";

/// Why an environment file cannot be used: the file, the field and what.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: `{field}`: {message}", path.display())]
pub struct EnvFileError {
    /// The file.
    pub path: PathBuf,
    /// The key (or `file`, or a TOML line).
    pub field: String,
    /// What is wrong.
    pub message: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvFileSpec {
    format: String,
    version: u32,
    #[serde(default)]
    #[allow(dead_code)]
    source: Option<String>,
    #[serde(default)]
    #[allow(dead_code)]
    estimate: Option<toml::Table>,
    #[serde(default)]
    lobes: Vec<Sg64>,
    #[serde(default)]
    lights: Vec<PointLight>,
    #[serde(default)]
    seen_lights: Vec<LightSpec>,
}

/// Why one lobe cannot be used, if it cannot (shared with scene files).
pub fn lobe_problem(l: &Sg64) -> Option<String> {
    if crate::scene::vec3::unit(l.direction).is_none() {
        return Some("direction must be a finite non-zero vector".into());
    }
    if !(l.sharpness.is_finite() && l.sharpness > 0.0 && l.sharpness <= 1e4) {
        return Some(format!("sharpness {} must be in (0, 1e4]", l.sharpness));
    }
    if !(l.amplitude.is_finite() && l.amplitude.min_element() >= 0.0) {
        return Some("amplitude must be finite and ≥ 0".into());
    }
    if l.amplitude.max_element() > crate::scene::RADIANCE_LIMIT {
        return Some(format!(
            "amplitude {} is above the radiance limit {:e}",
            l.amplitude,
            crate::scene::RADIANCE_LIMIT
        ));
    }
    None
}

/// Reads an environment file's lobes (directions normalised).
pub fn load_environment_file(path: &Path) -> Result<EstimatedLight, EnvFileError> {
    let text = std::fs::read_to_string(path).map_err(|x| EnvFileError {
        path: path.to_owned(),
        field: "file".into(),
        message: x.to_string(),
    })?;
    parse_environment_file(path, &text)
}

/// Parses the text of an environment file read from `path`.
pub fn parse_environment_file(path: &Path, text: &str) -> Result<EstimatedLight, EnvFileError> {
    let e = |field: &str, message: String| EnvFileError {
        path: path.to_owned(),
        field: field.to_owned(),
        message,
    };
    let spec: EnvFileSpec = parse_toml(text).map_err(|(k, m)| e(&k, m))?;
    check_format(
        &spec.format,
        spec.version,
        ENV_FILE_FORMAT,
        ENV_FILE_VERSION,
    )
    .map_err(|(k, m)| e(&k, m))?;
    let mut lobes = spec.lobes;
    for (i, l) in lobes.iter_mut().enumerate() {
        if let Some(m) = lobe_problem(l) {
            return Err(e(&format!("lobes[{i}]"), m));
        }
        l.direction = crate::scene::vec3::unit(l.direction).expect("checked above");
    }
    for (i, l) in spec.lights.iter().enumerate() {
        if !l.position.is_finite() {
            return Err(e(&format!("lights[{i}]"), "position must be finite".into()));
        }
        if !(l.intensity.is_finite() && l.intensity.min_element() >= 0.0) {
            return Err(e(
                &format!("lights[{i}]"),
                "intensity must be finite and ≥ 0".into(),
            ));
        }
    }
    let seen_lights = spec
        .seen_lights
        .into_iter()
        .enumerate()
        .map(|(i, l)| l.checked(&format!("seen_lights[{i}]")))
        .collect::<Result<_, _>>()
        .map_err(|(k, m)| e(&k, m))?;
    Ok(EstimatedLight {
        lobes,
        lights: spec.lights,
        seen_lights,
    })
}

/// The text of an environment file for `light`, estimated from scene
/// `source`, with `estimate` lines (`key = value` TOML) recording how.
pub fn environment_file_text(
    light: &EstimatedLight,
    source: &str,
    estimate: &[(String, String)],
) -> String {
    let mut s = String::from("# An environment light estimated by `inlay estimate-env` (format: passes/src/envest/file.rs).\n");
    s += &format!(
        "format = \"{ENV_FILE_FORMAT}\"\nversion = {ENV_FILE_VERSION}\nsource = {source:?}\n"
    );
    if !estimate.is_empty() {
        s += "\n[estimate]\n";
        for (k, v) in estimate {
            s += &format!("{k} = {v}\n");
        }
    }
    for l in &light.lobes {
        let d = l.direction;
        let a = l.amplitude;
        s += &format!(
            "\n[[lobes]]\ndirection = [{:e}, {:e}, {:e}]\nsharpness = {:e}\namplitude = [{:e}, {:e}, {:e}]\n",
            d.x, d.y, d.z, l.sharpness, a.x, a.y, a.z
        );
    }
    for l in &light.lights {
        let (p, i) = (l.position, l.intensity);
        s += &format!(
            "\n[[lights]]\nposition = [{:e}, {:e}, {:e}]\nintensity = [{:e}, {:e}, {:e}]\n",
            p.x, p.y, p.z, i.x, i.y, i.z
        );
    }
    for l in &light.seen_lights {
        let (c, r) = (l.centre, l.radiance);
        s += &format!(
            "\n[[seen_lights]]\ncentre = [{:e}, {:e}, {:e}]\nradius = {:e}\nradiance = [{:e}, {:e}, {:e}]\nviews = {}\nresidual = {:e}\n",
            c.x, c.y, c.z, l.radius, r.x, r.y, r.z, l.views, l.residual
        );
    }
    s
}
