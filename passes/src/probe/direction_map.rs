//! Direction maps: how the texels of a probe image cover the sphere of
//! directions. Mirrored by `shaders/common/direction_map.wgsl`.

use std::f64::consts::PI;

use glam::DVec3;
use serde::Deserialize;

/// Cells per texel side of the midpoint rule for an octahedral texel's
/// solid angle ([`DirectionMap::solid_angle`]); `DM_SOLID_ANGLE_CELLS` in
/// the shader.
pub const SOLID_ANGLE_CELLS: u32 = 4;

/// The layout of a probe image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MapKind {
    /// Latitude–longitude, 2n × n texels, +Y up (φ = atan2(z, x) across,
    /// θ from +Y down), like the scenes' environment maps. Texels shrink
    /// towards the poles.
    Equirect,
    /// The octahedral map, n × n texels: (u, v) ∈ [−1, 1]² is the point
    /// (u, 1 − |u| − |v|, v) of the octahedron |x| + |y| + |z| = 1, the
    /// lower half folded over the corners. Texel solid angles vary by at
    /// most a factor of about 5 (equirect: unbounded).
    Octahedral,
}

impl MapKind {
    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            MapKind::Equirect => "equirect",
            MapKind::Octahedral => "octahedral",
        }
    }
}

/// A direction map of a given size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionMap {
    /// The layout.
    pub kind: MapKind,
    /// Texels across.
    pub width: u32,
    /// Texels down.
    pub height: u32,
}

impl DirectionMap {
    /// A map whose resolution knob is `n`: 2n × n (equirect) or n × n (octahedral).
    pub fn new(kind: MapKind, n: u32) -> Self {
        let width = match kind {
            MapKind::Equirect => 2 * n,
            MapKind::Octahedral => n,
        };
        Self {
            kind,
            width,
            height: n,
        }
    }

    /// Number of texels.
    pub fn texels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The unit direction through the centre of texel (x, y).
    pub fn direction(&self, x: u32, y: u32) -> DVec3 {
        let u = (x as f64 + 0.5) / self.width as f64;
        let v = (y as f64 + 0.5) / self.height as f64;
        self.direction_and_density(u, v).0
    }

    /// The map coordinates (u, v) of sub-sample (i, j) of texel (x, y)
    /// when each texel is split into `side` × `side` equal cells: the
    /// cell's centre. With `side` = 1 it is the texel's centre. Mirrored
    /// by `dm_subsample_uv`.
    pub fn subsample_uv(&self, x: u32, y: u32, i: u32, j: u32, side: u32) -> (f64, f64) {
        let s = side as f64;
        (
            (x as f64 + (i as f64 + 0.5) / s) / self.width as f64,
            (y as f64 + (j as f64 + 0.5) / s) / self.height as f64,
        )
    }

    /// The largest texel's solid angle (sr).
    pub fn max_solid_angle(&self) -> f64 {
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .map(|(x, y)| self.solid_angle(x, y))
            .fold(0.0, f64::max)
    }

    /// The unit direction at map coordinates (u, v) ∈ [0, 1]² and the
    /// solid angle per unit of map area there, dω/(du dv) (4π on average):
    /// sin θ · 2π² for equirect, 4/|p|³ for the octahedral map.
    pub fn direction_and_density(&self, u: f64, v: f64) -> (DVec3, f64) {
        match self.kind {
            MapKind::Equirect => {
                let (phi, theta) = (2.0 * PI * u, PI * v);
                let d = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                (d, 2.0 * PI * PI * theta.sin())
            }
            MapKind::Octahedral => {
                let p = octahedron_point(2.0 * u - 1.0, 2.0 * v - 1.0);
                let len = p.length();
                (p / len, 4.0 / len.powi(3))
            }
        }
    }

    /// The solid angle of texel (x, y): exact for equirect; for the
    /// octahedral map the midpoint rule on dω = du dv / |p|³ (p the
    /// octahedron point) over a [`SOLID_ANGLE_CELLS`]² grid of cells in
    /// the texel, within 0.4 % of the exact value for every texel at n = 32
    /// (one midpoint per texel is off by up to 6 % on the texels the fold
    /// |u| + |v| = 1 crosses, where dω/(du dv) has a kink).
    pub fn solid_angle(&self, x: u32, y: u32) -> f64 {
        match self.kind {
            MapKind::Equirect => {
                let h = self.height as f64;
                let (t0, t1) = (PI * y as f64 / h, PI * (y as f64 + 1.0) / h);
                2.0 * PI / self.width as f64 * (t0.cos() - t1.cos())
            }
            MapKind::Octahedral => {
                let c = SOLID_ANGLE_CELLS;
                let mut sum = 0.0;
                for j in 0..c {
                    for i in 0..c {
                        let (u, v) = self.subsample_uv(x, y, i, j, c);
                        sum += self.direction_and_density(u, v).1;
                    }
                }
                sum / (c * c) as f64 / self.texels() as f64
            }
        }
    }

    /// The texel containing unit direction `d` (for writing probes of known
    /// content in tests and tools).
    pub fn texel_of(&self, d: DVec3) -> (u32, u32) {
        let (u, v) = match self.kind {
            MapKind::Equirect => {
                let phi = d.z.atan2(d.x).rem_euclid(2.0 * PI);
                (phi / (2.0 * PI), d.y.clamp(-1.0, 1.0).acos() / PI)
            }
            MapKind::Octahedral => octahedral_uv(d),
        };
        let x = ((u * self.width as f64) as u32).min(self.width - 1);
        let y = ((v * self.height as f64) as u32).min(self.height - 1);
        (x, y)
    }
}

/// The octahedral map coordinates (u, v) ∈ [0, 1]² of unit direction `d`
/// (the inverse of the map's direction). Mirrored by `octahedral_uv` in
/// `shaders/common/octahedral_map.wgsl`.
pub fn octahedral_uv(d: DVec3) -> (f64, f64) {
    let p = d / (d.x.abs() + d.y.abs() + d.z.abs());
    let (mut a, mut b) = (p.x, p.z);
    if p.y < 0.0 {
        let (fa, fb) = ((1.0 - b.abs()) * a.signum(), (1.0 - a.abs()) * b.signum());
        a = fa;
        b = fb;
    }
    (0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// The texel (x, y) of an n × n octahedral map for indices up to one
/// outside it: the map's edges fold onto themselves (u = ±1 mirrored about
/// v = 0, v = ±1 about u = 0). Mirrored by `ssdf_wrap` in the shader.
pub fn wrap_octahedral(mut x: i64, mut y: i64, n: i64) -> (i64, i64) {
    if x < 0 {
        x = 0;
        y = n - 1 - y;
    } else if x >= n {
        x = n - 1;
        y = n - 1 - y;
    }
    if y < 0 {
        y = 0;
        x = n - 1 - x;
    } else if y >= n {
        y = n - 1;
        x = n - 1 - x;
    }
    (x.clamp(0, n - 1), y.clamp(0, n - 1))
}

/// The bilinear read along unit `d` of an n × n octahedral map whose texel
/// `y·n + x` holds `value(y·n + x)`; neighbours across the map's edges
/// come from [`wrap_octahedral`]. Used for SSDF direction maps, cached
/// opacity maps and the field light's tables. Its texels and weights are
/// mirrored by `octahedral_bilinear` in `shaders/common/octahedral_map.wgsl`.
pub fn octahedral_bilinear(n: u32, d: DVec3, mut value: impl FnMut(usize) -> f64) -> f64 {
    let n = n as i64;
    let (u, v) = octahedral_uv(d);
    let (px, py) = (u * n as f64 - 0.5, v * n as f64 - 0.5);
    let (x0, y0) = (px.floor(), py.floor());
    let (fx, fy) = (px - x0, py - y0);
    let mut s = 0.0;
    for (dx, dy, w) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let (x, y) = wrap_octahedral(x0 as i64 + dx, y0 as i64 + dy, n);
        s += w * value((y * n + x) as usize);
    }
    s
}

/// The point of the octahedron |x| + |y| + |z| = 1 for (u, v) ∈ [−1, 1]²:
/// (u, 1 − |u| − |v|, v) inside the diamond |u| + |v| ≤ 1, folded to the
/// lower half outside it.
fn octahedron_point(u: f64, v: f64) -> DVec3 {
    let y = 1.0 - u.abs() - v.abs();
    if y >= 0.0 {
        DVec3::new(u, y, v)
    } else {
        DVec3::new(
            (1.0 - v.abs()) * u.signum(),
            y,
            (1.0 - u.abs()) * v.signum(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_angles_cover_the_sphere() {
        for (kind, n, tol) in [
            (MapKind::Equirect, 8, 1e-12),
            (MapKind::Equirect, 64, 1e-12),
            (MapKind::Octahedral, 16, 3e-4),
            (MapKind::Octahedral, 64, 2e-5),
        ] {
            let map = DirectionMap::new(kind, n);
            let mut total = 0.0;
            for y in 0..map.height {
                for x in 0..map.width {
                    total += map.solid_angle(x, y);
                    let d = map.direction(x, y);
                    assert!((d.length() - 1.0).abs() < 1e-12);
                    assert_eq!(map.texel_of(d), (x, y), "{kind:?} {n} texel ({x}, {y})");
                }
            }
            assert!(
                (total / (4.0 * PI) - 1.0).abs() < tol,
                "{kind:?} {n}: {total}"
            );
        }
    }

    #[test]
    fn octahedral_texels_are_nearly_uniform() {
        let map = DirectionMap::new(MapKind::Octahedral, 32);
        let w: Vec<f64> = (0..32 * 32)
            .map(|i| map.solid_angle(i % 32, i / 32))
            .collect();
        let (lo, hi) = w
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(hi / lo < 5.3, "{}", hi / lo);
    }
}
