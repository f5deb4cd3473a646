//! The method's passes — NeRF ray march, incident-light probe trace, SG
//! Levenberg–Marquardt fit, object G-buffer and SG shading, compositing and
//! shadows (`docs/METHOD.md` in the repository) — each with its CPU reference, and
//! the math they share. Every pass is a pass of the engine's frame graph and
//! uses only the engine's safe API.
//!
//! So far: radiance fields ([`field`]), scene files and recipes ([`scene`]),
//! baking recipes into fields and ground-truth images ([`bake`]), the ray
//! march ([`march`]), spherical Gaussians ([`sg`]), the incident-light
//! probe ([`probe`]) and its Levenberg–Marquardt SG fit ([`sgfit`]), glTF
//! objects ([`object`]), their BRDF and SG shading ([`brdf`]), and the
//! G-buffer, shading and compositing passes ([`gbuffer`], [`shade`],
//! [`composite`]).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bake;
pub mod brdf;
pub mod camera;
pub mod composite;
pub mod dataset;
pub mod edge_aa;
pub mod eigen;
pub mod envest;
pub mod field;
pub mod frame;
pub mod gbuffer;
pub mod geometry;
pub mod lighting;
pub mod march;
pub mod object;
pub mod probe;
pub mod rng;
pub mod scene;
pub mod sg;
pub mod sgfit;
pub mod shade;
pub mod shaders;
pub mod shadow;
pub mod sky_behind;
pub mod ssdf;
pub mod toml_file;
pub mod train;
