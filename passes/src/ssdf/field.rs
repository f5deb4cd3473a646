//! An object's SSDF field (METHOD.md "SSDF field"): the PCA-compressed S
//! at the nodes of its grid, and S(d; x) anywhere — trilinear inside the
//! grid, and outside it one of three [`OutsideMode`]s (the paper's Fig. 7).
//! [`SsdfField::sample`] is the CPU mirror of `shaders/ssdf/ssdf.wgsl`.
//!
//! Layout (also the GPU's): per direction texel a row of 1 + k values (the
//! mean, then the k basis values), and per node k coefficients, so
//! `S(node, texel) = row[0] + Σ_c coef[c]·row[1 + c]`. Directions between
//! texel centres are read bilinearly, across the octahedral map's folded
//! edges.

use std::f64::consts::PI;

use glam::{DVec3, UVec3};
use serde::Deserialize;

use super::bake::SsdfSamples;
use super::grid::SsdfGrid;
use super::pca::pca;
use crate::probe::octahedral_bilinear;

/// How S is found at points outside the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum OutsideMode {
    /// The nearest node's S as is: the object never shrinks with distance
    /// (the paper's Fig. 7a: too much shadow far away).
    Clamp,
    /// S = +∞ (π): no shadow outside the grid (Fig. 7b).
    Infinity,
    /// The nearest node's S corrected for the displacement (Fig. 7c): the
    /// object seen from x_f is the one seen from the node x_b, turned so
    /// its centre lies where it does from x_f and shrunk by the ratio of
    /// the bounding sphere's angular radii.
    #[default]
    Correct,
}

impl OutsideMode {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            OutsideMode::Clamp => "clamp",
            OutsideMode::Infinity => "infinity",
            OutsideMode::Correct => "correct",
        }
    }

    /// The index the shaders use (0 clamp, 1 infinity, 2 correct).
    pub fn index(self) -> u32 {
        match self {
            OutsideMode::Clamp => 0,
            OutsideMode::Infinity => 1,
            OutsideMode::Correct => 2,
        }
    }

    /// Every mode.
    pub const ALL: [OutsideMode; 3] = [
        OutsideMode::Clamp,
        OutsideMode::Infinity,
        OutsideMode::Correct,
    ];
}

/// A compressed SSDF field in the object's own frame.
#[derive(Debug, Clone)]
pub struct SsdfField {
    /// The node lattice.
    pub grid: SsdfGrid,
    /// Side of the octahedral direction map.
    pub directions: u32,
    /// PCA components k.
    pub components: u32,
    /// Per direction texel: mean, then k basis values.
    pub texel_rows: Vec<f32>,
    /// Per node: k coefficients.
    pub coefficients: Vec<f32>,
    /// The [`ObjectMesh::geometry_key`](crate::object::ObjectMesh::geometry_key)
    /// of the mesh it was baked from.
    pub object: u64,
}

impl SsdfField {
    /// Compresses raw samples to `components` principal components.
    pub fn compress(samples: &SsdfSamples, components: u32) -> Self {
        let texels = (samples.directions * samples.directions) as usize;
        let nodes = samples.grid.count();
        let k = (components as usize).min(texels).min(nodes).max(1);
        let p = pca(&samples.values, nodes, texels, k, 0x55df);
        let mut texel_rows = Vec::with_capacity(texels * (k + 1));
        for t in 0..texels {
            texel_rows.push(p.mean[t]);
            texel_rows.extend((0..k).map(|c| p.basis[c * texels + t]));
        }
        Self {
            grid: samples.grid,
            directions: samples.directions,
            components: k as u32,
            texel_rows,
            coefficients: p.coefficients,
            object: samples.object,
        }
    }

    /// The field with only its first `components` principal components
    /// (at least 1; no more than it has). The components are ordered by
    /// decreasing variance, so this is the rank-`components` PCA of the
    /// same samples without baking them again (how a sweep over the PCA
    /// knob reuses one bake).
    pub fn truncated(&self, components: u32) -> Self {
        let k = self.components as usize;
        let kept = (components as usize).clamp(1, k);
        let texel_rows = self
            .texel_rows
            .chunks_exact(k + 1)
            .flat_map(|row| row[..=kept].iter().copied())
            .collect();
        let coefficients = self
            .coefficients
            .chunks_exact(k)
            .flat_map(|c| c[..kept].iter().copied())
            .collect();
        Self {
            grid: self.grid,
            directions: self.directions,
            components: kept as u32,
            texel_rows,
            coefficients,
            object: self.object,
        }
    }

    /// Number of direction texels.
    pub fn texels(&self) -> usize {
        (self.directions * self.directions) as usize
    }

    /// Bytes of the uncompressed samples (f32 per node and texel).
    pub fn raw_bytes(&self) -> u64 {
        (self.grid.count() * self.texels() * 4) as u64
    }

    /// Bytes of the compressed data (f32 rows and coefficients).
    pub fn compressed_bytes(&self) -> u64 {
        ((self.texel_rows.len() + self.coefficients.len()) * 4) as u64
    }

    /// The reconstructed S at node `node`, texel `texel`.
    pub fn node_value(&self, node: usize, texel: usize) -> f64 {
        let k = self.components as usize;
        self.texel_value(&self.coefficients[node * k..(node + 1) * k], texel)
    }

    fn texel_value(&self, coef: &[f32], texel: usize) -> f64 {
        let k = self.components as usize;
        let row = &self.texel_rows[texel * (k + 1)..(texel + 1) * (k + 1)];
        let mut s = row[0] as f64;
        for (c, r) in coef.iter().zip(&row[1..]) {
            s += *c as f64 * *r as f64;
        }
        s
    }

    /// S for coefficients `coef` along unit `d`, bilinear over the map.
    pub fn direction_value(&self, coef: &[f32], d: DVec3) -> f64 {
        octahedral_bilinear(self.directions, d, |t| self.texel_value(coef, t))
    }

    /// The trilinear blend of the coefficients of the 8 nodes around
    /// lattice position `l` (clamped into the grid).
    pub fn coefficients_at(&self, l: DVec3) -> Vec<f32> {
        let k = self.components as usize;
        let top = (self.grid.nodes - 1) as f64;
        let l = l.clamp(DVec3::ZERO, DVec3::splat(top));
        let base = l.floor().min(DVec3::splat(top - 1.0)).max(DVec3::ZERO);
        let f = l - base;
        let mut out = vec![0.0f32; k];
        for corner in 0..8u32 {
            let o = UVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
            let w = [f.x, f.y, f.z]
                .iter()
                .zip([o.x, o.y, o.z])
                .map(|(f, o)| if o == 1 { *f } else { 1.0 - f })
                .product::<f64>() as f32;
            let node = self.grid.index(base.as_uvec3() + o);
            for (acc, c) in out
                .iter_mut()
                .zip(&self.coefficients[node * k..(node + 1) * k])
            {
                *acc += w * c;
            }
        }
        out
    }

    /// S(d; x) at object-space point `x` for unit `d`.
    pub fn sample(&self, x: DVec3, d: DVec3, mode: OutsideMode) -> f64 {
        let l = self.grid.lattice(x);
        if self.grid.contains(x) {
            return self.direction_value(&self.coefficients_at(l), d);
        }
        if mode == OutsideMode::Infinity {
            return PI;
        }
        let top = (self.grid.nodes - 1) as f64;
        let node = l.round().clamp(DVec3::ZERO, DVec3::splat(top));
        let k = self.components as usize;
        let i = self.grid.index(node.as_uvec3());
        let coef = &self.coefficients[i * k..(i + 1) * k];
        if mode == OutsideMode::Clamp {
            return self.direction_value(coef, d);
        }
        let xb = self.grid.position(node.as_uvec3());
        let (o, r) = (self.grid.centre, self.grid.radius);
        let (df, db) = ((o - x).length(), (o - xb).length());
        let (cf, cb) = ((o - x) / df, (o - xb) / db);
        let shrink = (r / df).min(1.0).asin() / (r / db).min(1.0).asin();
        let alpha = super::silhouette::angle_between(d, cf);
        let sb = self.direction_value(coef, rotate_between(cf, cb, d));
        alpha - shrink * (alpha - sb)
    }
}

/// `v` turned by the smallest rotation taking unit `from` to unit `to`.
pub fn rotate_between(from: DVec3, to: DVec3, v: DVec3) -> DVec3 {
    let axis = from.cross(to);
    let c = from.dot(to);
    if c <= -1.0 + 1e-12 {
        return -v;
    }
    v * c + axis.cross(v) + axis * (axis.dot(v) / (1.0 + c))
}
