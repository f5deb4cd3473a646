//! The probe's knobs: direction map, resolution and rays per texel.

use super::direction_map::{DirectionMap, MapKind};

/// How finely the incident light at the object is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeKnobs {
    /// Layout of the probe image.
    pub map: MapKind,
    /// Resolution n: n × n texels (octahedral) or 2n × n (equirect).
    pub resolution: u32,
    /// Rays per texel side s: each texel is the mean of s × s stratified
    /// rays over its solid angle (1: one ray through its centre, a point
    /// sample that catches or misses a light smaller than a texel).
    pub supersampling: u32,
    /// Texels a warm update traces: one of each `stride` × `stride` block,
    /// a different one each update ([`Self::phase_offset`]), the rest kept
    /// from the updates before; 1 traces every texel (the paper's). A cold
    /// fit always traces every texel, and an object that stops has its
    /// probe completed where it stands within `stride`² − 1 frames.
    pub stride: u32,
}

impl Default for ProbeKnobs {
    /// Octahedral 32 × 32 with 6 × 6 rays per texel: 36864 rays, texels
    /// of about 0.012 sr (6° across) holding their mean radiance. With
    /// 6 × 6 a light smaller than a texel sliding across the map changes
    /// the probe's energy by under 1 % (4 × 4: 2 %, one ray: 10 %;
    /// `tests/probe_integration.rs`). A warm update traces a quarter of
    /// the texels (stride 2): a dragged object's frame traces 9216 rays,
    /// and its lighting settles 3 frames later than with the whole probe
    /// once it stops (docs/benchmarks.md, issue 26's fourth pass).
    fn default() -> Self {
        Self {
            map: MapKind::Octahedral,
            resolution: 32,
            supersampling: 6,
            stride: 2,
        }
    }
}

impl ProbeKnobs {
    /// The direction map these knobs describe.
    pub fn direction_map(&self) -> DirectionMap {
        DirectionMap::new(self.map, self.resolution)
    }

    /// Rays traced per probe.
    pub fn rays(&self) -> usize {
        self.direction_map().texels() * (self.supersampling as usize).pow(2)
    }

    /// The updates it takes to trace every texel: `stride`².
    pub fn phases(&self) -> u32 {
        self.stride * self.stride
    }

    /// Which texel of each `stride` × `stride` block the `n`-th update
    /// traces (n mod `stride`²), as (column, row) in the block: the order
    /// of a Bayer matrix, so that each update's texels and the ones it
    /// follows spread evenly over the map (2 × 2: (0, 0), (1, 1), (1, 0),
    /// (0, 1)).
    pub fn phase_offset(&self, n: u32) -> (u32, u32) {
        let s = self.stride.max(1);
        let n = n % (s * s);
        // Bit-reverse-interleave n into the Bayer order: its bits, from
        // the lowest, alternately give x ^ y and y, high to low.
        let bits = s.trailing_zeros();
        let (mut x, mut y) = (0, 0);
        for b in 0..bits {
            let xy = (n >> (2 * b)) & 1;
            let yb = (n >> (2 * b + 1)) & 1;
            let shift = bits - 1 - b;
            x |= (xy ^ yb) << shift;
            y |= xy << shift;
        }
        (x, y)
    }

    /// Why the knobs cannot be used, naming the knob.
    pub fn check(&self) -> Result<(), (String, String)> {
        if !(4..=256).contains(&self.resolution) {
            return Err((
                "resolution".into(),
                format!("{} must be in 4..=256", self.resolution),
            ));
        }
        if !(1..=16).contains(&self.supersampling) {
            return Err((
                "supersampling".into(),
                format!(
                    "{} must be in 1..=16 (rays per texel side)",
                    self.supersampling
                ),
            ));
        }
        if ![1, 2, 4].contains(&self.stride) {
            return Err((
                "stride".into(),
                format!(
                    "{} must be 1, 2 or 4 (a warm update traces one texel of each stride × stride block)",
                    self.stride
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over `stride`² updates every texel of a block is traced once, and
    /// consecutive updates' texels lie apart.
    #[test]
    fn phases_cover_each_block_once() {
        for stride in [1u32, 2, 4] {
            let k = ProbeKnobs {
                stride,
                ..ProbeKnobs::default()
            };
            let mut seen = std::collections::HashSet::new();
            for n in 0..k.phases() {
                let (x, y) = k.phase_offset(n);
                assert!(x < stride && y < stride);
                assert!(
                    seen.insert((x, y)),
                    "stride {stride}: phase {n} repeats ({x}, {y})"
                );
            }
            assert_eq!(k.phase_offset(k.phases()), k.phase_offset(0));
        }
        let k = ProbeKnobs {
            stride: 2,
            ..ProbeKnobs::default()
        };
        let order: Vec<_> = (0..4).map(|n| k.phase_offset(n)).collect();
        assert_eq!(order, [(0, 0), (1, 1), (1, 0), (0, 1)]);
        assert!(ProbeKnobs { stride: 3, ..k }.check().is_err());
    }
}
