//! The lights seen past a trained field's bounds, in a TOML file beside
//! it (`FIELD.lights.toml`):
//!
//! ```toml
//! format = "inlay-seen-lights"   # required, exactly this
//! version = 1                    # required, this reader's SEEN_LIGHTS_VERSION
//! [[lights]]                     # any number; none draws nothing
//! centre = [0.198, 2.894, 0.298] # finite (scene units)
//! radius = 0.0296                # finite, > 0
//! radiance = [8022, 7420, 6418]  # RGB radiance, finite, ≥ 0
//! views = 13                     # optional: training views that saw it
//! residual = 0.017               # optional: its spots' light left unexplained
//! ```

use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::SeenLight;
use crate::toml_file::{check_format, parse_toml};

/// The `format` value of a seen-lights file.
pub const SEEN_LIGHTS_FORMAT: &str = "inlay-seen-lights";

/// The version this reader understands.
pub const SEEN_LIGHTS_VERSION: u32 = 1;

/// Where the lights seen with the field file `field` are kept:
/// FIELD.lights.toml beside it.
pub fn seen_lights_path(field: &Path) -> PathBuf {
    field.with_extension("lights.toml")
}

/// Why a seen-lights file cannot be used: the file, the key and what.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: `{key}`: {message}", path.display())]
pub struct SeenLightsError {
    /// The file.
    pub path: PathBuf,
    /// The key (or `file`, or a TOML line).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

/// One light as a file holds it: the seen-lights file's `[[lights]]`,
/// and the environment file's `[[seen_lights]]` (the lights an estimate
/// took as known).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightSpec {
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    centre: DVec3,
    radius: f64,
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    radiance: DVec3,
    #[serde(default)]
    views: usize,
    #[serde(default)]
    residual: f64,
}

impl LightSpec {
    /// How `l` is written.
    pub(crate) fn of(l: &SeenLight) -> Self {
        Self {
            centre: l.centre,
            radius: l.radius,
            radiance: l.radiance,
            views: l.views,
            residual: l.residual,
        }
    }

    /// The light, or the key (under `prefix`) that is wrong and why.
    pub(crate) fn checked(self, prefix: &str) -> Result<SeenLight, (String, String)> {
        let key = |k: &str| format!("{prefix}.{k}");
        if !self.centre.is_finite() {
            return Err((key("centre"), "must be finite".into()));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err((
                key("radius"),
                format!("{} must be finite and > 0", self.radius),
            ));
        }
        if !(self.radiance.is_finite() && self.radiance.min_element() >= 0.0) {
            return Err((key("radiance"), "must be finite and ≥ 0".into()));
        }
        if self.radiance.max_element() > crate::scene::RADIANCE_LIMIT {
            return Err((
                key("radiance"),
                format!(
                    "{} is above the radiance limit {:e}",
                    self.radiance,
                    crate::scene::RADIANCE_LIMIT
                ),
            ));
        }
        Ok(SeenLight {
            centre: self.centre,
            radius: self.radius,
            radiance: self.radiance,
            views: self.views,
            residual: self.residual,
        })
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    format: String,
    version: u32,
    #[serde(default)]
    lights: Vec<LightSpec>,
}

/// The text of a seen-lights file holding `lights`.
pub fn seen_lights_text(lights: &[SeenLight]) -> String {
    let spec = FileSpec {
        format: SEEN_LIGHTS_FORMAT.into(),
        version: SEEN_LIGHTS_VERSION,
        lights: lights.iter().map(LightSpec::of).collect(),
    };
    toml::to_string(&spec).expect("plain numbers and strings serialise")
}

/// Reads a seen-lights file.
pub fn load_seen_lights(path: &Path) -> Result<Vec<SeenLight>, SeenLightsError> {
    let text = std::fs::read_to_string(path).map_err(|x| SeenLightsError {
        path: path.to_owned(),
        key: "file".into(),
        message: x.to_string(),
    })?;
    parse_seen_lights(path, &text)
}

/// Parses the text of a seen-lights file read from `path`.
pub fn parse_seen_lights(path: &Path, text: &str) -> Result<Vec<SeenLight>, SeenLightsError> {
    let e = |key: &str, message: String| SeenLightsError {
        path: path.to_owned(),
        key: key.to_owned(),
        message,
    };
    let spec: FileSpec = parse_toml(text).map_err(|(k, m)| e(&k, m))?;
    check_format(
        &spec.format,
        spec.version,
        SEEN_LIGHTS_FORMAT,
        SEEN_LIGHTS_VERSION,
    )
    .map_err(|(k, m)| e(&k, m))?;
    spec.lights
        .into_iter()
        .enumerate()
        .map(|(i, l)| {
            l.checked(&format!("lights[{i}]"))
                .map_err(|(k, m)| e(&k, m))
        })
        .collect()
}
