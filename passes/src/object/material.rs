//! glTF metallic-roughness materials, scene-file overrides, and their
//! evaluation at a surface point (texture lookups included) for the CPU
//! references.

use glam::{DVec3, DVec4};
use serde::Deserialize;

use super::texture::Texture;
use crate::brdf::SurfaceMaterial;

/// A glTF 2.0 metallic-roughness material.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name (messages).
    pub name: String,
    /// Base colour factor (linear RGBA).
    pub base_colour: DVec4,
    /// Roughness factor.
    pub roughness: f64,
    /// Metallic factor.
    pub metallic: f64,
    /// Base colour texture (sRGB), multiplied with the factor.
    pub base_colour_texture: Option<usize>,
    /// Metallic-roughness texture (linear; roughness in G, metallic in B).
    pub metallic_roughness_texture: Option<usize>,
}

impl Default for Material {
    /// glTF's default material: white, fully metallic and rough.
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_colour: DVec4::ONE,
            roughness: 1.0,
            metallic: 1.0,
            base_colour_texture: None,
            metallic_roughness_texture: None,
        }
    }
}

/// Scene-file replacements for an object's materials; a value given
/// replaces the factor and drops the texture of that channel.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialOverride {
    /// Base colour (linear RGB in [0, 1]).
    #[serde(default, deserialize_with = "crate::scene::vec3::exact_opt")]
    pub base_color: Option<DVec3>,
    /// Roughness in [0, 1].
    pub roughness: Option<f64>,
    /// Metallic in [0, 1].
    pub metallic: Option<f64>,
}

impl MaterialOverride {
    /// What is wrong with it (field, message), if anything.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        if let Some(c) = self.base_color {
            if !(c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= 1.0) {
                return Some(("base_color", format!("{c} must lie in [0, 1]")));
            }
        }
        for (name, v) in [("roughness", self.roughness), ("metallic", self.metallic)] {
            if let Some(v) = v {
                if !(0.0..=1.0).contains(&v) {
                    return Some((name, format!("{v} must lie in [0, 1]")));
                }
            }
        }
        None
    }

    /// `m` with the override applied.
    pub fn apply(&self, m: &Material) -> Material {
        let mut out = m.clone();
        if let Some(c) = self.base_color {
            out.base_colour = c.extend(1.0);
            out.base_colour_texture = None;
        }
        if self.roughness.is_some() || self.metallic.is_some() {
            // The texture holds both channels: kept only when neither is overridden.
            out.metallic_roughness_texture = None;
        }
        if let Some(r) = self.roughness {
            out.roughness = r;
        }
        if let Some(x) = self.metallic {
            out.metallic = x;
        }
        out
    }
}

/// sRGB-encoded [0, 1] to linear.
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Material {
    /// The BRDF parameters at texture coordinates `uv` (bilinear lookups,
    /// as the G-buffer pass samples), clamped to their domains.
    pub fn at(&self, uv: [f64; 2], textures: &[Texture]) -> SurfaceMaterial {
        let mut albedo = self.base_colour.truncate();
        if let Some(t) = self.base_colour_texture.and_then(|i| textures.get(i)) {
            // Vulkan decodes sRGB per texel before filtering.
            let s = t.sample_with(uv, |b| srgb_to_linear(b as f64 / 255.0));
            albedo *= DVec3::new(s[0], s[1], s[2]);
        }
        let (mut roughness, mut metallic) = (self.roughness, self.metallic);
        if let Some(t) = self
            .metallic_roughness_texture
            .and_then(|i| textures.get(i))
        {
            let s = t.sample_with(uv, |b| b as f64 / 255.0);
            roughness *= s[1];
            metallic *= s[2];
        }
        SurfaceMaterial {
            albedo,
            roughness,
            metallic,
        }
        .clamped()
    }
}
