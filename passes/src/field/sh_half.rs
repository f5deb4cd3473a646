//! How a field's view-dependent coefficients are stored: as f16, three
//! halves (r, g, b) a coefficient, after dividing by a power of two, the
//! field's `unscale`, chosen so that the largest magnitude stays within
//! [`SH_HALF_LIMIT`] (a field within the radiance limit, 1e6, would
//! otherwise overflow f16's 65 504). The device holds them so, each node's
//! split over two bindings ([`split_sh`]; `grid_sh` and `grid_sh_rest` in
//! `shaders/field/grid.wgsl`), and so do field files, version 2; a
//! [`super::GridField`] holds them already rounded to this precision
//! ([`quantise_sh`]), so the CPU references read what the device reads.
//!
//! Precision: a half keeps 11 significant bits, a relative error of at
//! most 2⁻¹¹ (0.05 %) of each coefficient, and values below 2⁻¹⁴·unscale
//! lose relative precision gradually (subnormals) down to 2⁻²⁴·unscale:
//! at unscale 1 (every field whose coefficients stay under 32 768) that
//! is 6·10⁻⁸ in radiance, far below any colour a photograph resolves.

use half::f16;

/// The largest magnitude stored: coefficients are divided by the power of
/// two that brings the largest of them to at most this (half of f16's
/// largest finite value, so rounding can never overflow).
pub const SH_HALF_LIMIT: f32 = 32768.0;

/// Bytes one further coefficient (r, g, b) takes stored.
pub const SH_HALF_BYTES: u64 = 6;

/// The power of two (≥ 1) the stored halves are multiplied by to give the
/// coefficients `sh`.
pub fn sh_unscale(sh: &[[f32; 3]]) -> f32 {
    let largest = sh.iter().flatten().fold(
        0.0f32,
        |m, v| if v.is_finite() { m.max(v.abs()) } else { m },
    );
    let mut unscale = 1.0f32;
    while largest / unscale > SH_HALF_LIMIT {
        unscale *= 2.0;
    }
    unscale
}

/// Rounds `sh` in place to what [`pack_sh`] stores and unpacking gives
/// back (each value v becomes f16(v / unscale) · unscale, exactly).
pub fn quantise_sh(sh: &mut [[f32; 3]]) {
    let unscale = sh_unscale(sh);
    for v in sh.iter_mut().flatten() {
        *v = f16::from_f32(*v / unscale).to_f32() * unscale;
    }
}

/// The halves of `coefficients` divided by `unscale`, two to a word (the
/// lower half first), with a word of padding at the end so that a reader
/// may always load the word after the one it needs.
pub fn pack_sh(coefficients: &[[f32; 3]], unscale: f32) -> Vec<u32> {
    let halves: Vec<u16> = coefficients
        .iter()
        .flatten()
        .map(|&v| f16::from_f32(v / unscale).to_bits())
        .collect();
    let mut words: Vec<u32> = halves
        .chunks(2)
        .map(|p| p[0] as u32 | (p.get(1).copied().unwrap_or(0) as u32) << 16)
        .collect();
    words.push(0);
    words
}

/// Coefficient `j` of the `count` of pool node `n` from words [`pack_sh`]
/// wrote (the CPU mirror of how `field_sh_node` in grid.wgsl reads them).
pub fn unpack_sh(words: &[u32], unscale: f32, count: usize, n: usize, j: usize) -> [f32; 3] {
    let h = 3 * (count * n + j);
    let half = |i: usize| {
        let w = words[i / 2];
        f16::from_bits((w >> (16 * (i % 2))) as u16).to_f32() * unscale
    };
    [half(h), half(h + 1), half(h + 2)]
}

/// Of a node's `count` further coefficients, how many the first of the
/// device's two coefficient bindings holds (the rest are in the second):
/// split so that degree 2 at 256³ nodes fits lavapipe's 128 MiB bindings
/// where one binding of all eight would not.
pub fn sh_first_count(count: usize) -> usize {
    count.div_ceil(2)
}

/// `coefficients` (`count` a node, node after node) split per node into
/// the first [`sh_first_count`] of each node's and the rest.
pub fn split_sh(coefficients: &[[f32; 3]], count: usize) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let first = sh_first_count(count);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for node in coefficients.chunks(count.max(1)) {
        a.extend_from_slice(&node[..first.min(node.len())]);
        b.extend_from_slice(&node[first.min(node.len())..]);
    }
    (a, b)
}

/// Coefficient `j` of the `count` of pool node `n` from the two bindings'
/// words, [`pack_sh`] of each half of [`split_sh`] (the CPU mirror of
/// how `field_sh_node` in grid.wgsl reads them).
pub fn unpack_split_sh(
    first: &[u32],
    rest: &[u32],
    unscale: f32,
    count: usize,
    n: usize,
    j: usize,
) -> [f32; 3] {
    let a = sh_first_count(count);
    if j < a {
        unpack_sh(first, unscale, a, n, j)
    } else {
        unpack_sh(rest, unscale, count - a, n, j - a)
    }
}

/// The halves as little-endian bytes, three a coefficient, no padding (a
/// field file's layout).
pub fn sh_half_bytes(coefficients: &[[f32; 3]], unscale: f32) -> Vec<u8> {
    coefficients
        .iter()
        .flatten()
        .flat_map(|&v| f16::from_f32(v / unscale).to_le_bytes())
        .collect()
}

/// The coefficients from [`sh_half_bytes`]' bytes (a multiple of 6).
pub fn sh_from_half_bytes(bytes: &[u8], unscale: f32) -> Vec<[f32; 3]> {
    bytes
        .chunks_exact(6)
        .map(|c| {
            let h = |i: usize| f16::from_le_bytes([c[2 * i], c[2 * i + 1]]).to_f32() * unscale;
            [h(0), h(1), h(2)]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Split over two bindings, every coefficient of every node reads back
    /// as from one, for each degree's count (3 and 8) and one.
    #[test]
    fn split_coefficients_read_back_as_unsplit() {
        for count in [1usize, 3, 8] {
            let nodes = 5;
            let coefficients: Vec<[f32; 3]> = (0..count * nodes)
                .map(|i| {
                    let x = i as f32;
                    [0.25 * x - 3.0, -0.125 * x, 0.5 + x]
                })
                .collect();
            let unscale = sh_unscale(&coefficients);
            let whole = pack_sh(&coefficients, unscale);
            let (a, b) = split_sh(&coefficients, count);
            assert_eq!(a.len(), sh_first_count(count) * nodes);
            assert_eq!(a.len() + b.len(), coefficients.len());
            let (a, b) = (pack_sh(&a, unscale), pack_sh(&b, unscale));
            for n in 0..nodes {
                for j in 0..count {
                    assert_eq!(
                        unpack_split_sh(&a, &b, unscale, count, n, j),
                        unpack_sh(&whole, unscale, count, n, j),
                        "count {count}, node {n}, coefficient {j}"
                    );
                }
            }
        }
    }

    /// Quantised values come back exactly through both layouts, and the
    /// rounding is within half a unit in the last place of a half.
    #[test]
    fn stored_coefficients_come_back_as_quantised() {
        let original: Vec<[f32; 3]> = (0..7)
            .map(|i| {
                let x = i as f32;
                [0.1 * x - 0.3, 1.0e-3 * x, -(x * x) * 0.377]
            })
            .collect();
        let mut sh = original.clone();
        quantise_sh(&mut sh);
        for (a, b) in original.iter().flatten().zip(sh.iter().flatten()) {
            assert!((a - b).abs() <= a.abs() * 2f32.powi(-11) + 1e-7, "{a} {b}");
        }
        let u = sh_unscale(&sh);
        assert_eq!(u, 1.0);
        let words = pack_sh(&sh, u);
        for (n, c) in sh.iter().enumerate() {
            assert_eq!(unpack_sh(&words, u, 1, n, 0), *c);
        }
        assert_eq!(sh_from_half_bytes(&sh_half_bytes(&sh, u), u), sh);
    }

    /// Coefficients beyond f16's range are scaled by a power of two, not
    /// overflowed: the radiance limit's 1e6 comes back within f16's
    /// precision, and a small coefficient beside it keeps its value to
    /// the scaled subnormals' step.
    #[test]
    fn a_field_as_bright_as_the_radiance_limit_does_not_overflow() {
        let mut sh = vec![[1.0e6, -1.0e6, 0.5], [3.0e-3, 0.0, -7.0]];
        let u = sh_unscale(&sh);
        assert_eq!(u, 32.0);
        quantise_sh(&mut sh);
        assert!(sh.iter().flatten().all(|v| v.is_finite()));
        assert!((sh[0][0] - 1.0e6).abs() <= 1.0e6 * 2f32.powi(-11));
        assert!((sh[1][2] + 7.0).abs() <= 7.0 * 2f32.powi(-11));
        assert!((sh[1][0] - 3.0e-3).abs() <= 32.0 * 2f32.powi(-24));
        let words = pack_sh(&sh, u);
        assert_eq!(unpack_sh(&words, u, 2, 0, 0), sh[0]);
        assert_eq!(unpack_sh(&words, u, 2, 0, 1), sh[1]);
    }

    /// An odd number of halves leaves the last word's upper half zero, and
    /// the padding word is there.
    #[test]
    fn the_words_end_with_padding() {
        let words = pack_sh(&[[1.0, 2.0, 3.0]], 1.0);
        assert_eq!(words.len(), 3);
        assert_eq!(words[1] >> 16, 0);
        assert_eq!(words[2], 0);
    }
}
