//! Every n-th pixel of every n-th row of a picture: how the CPU's reads of
//! a trained field along its training pixels (the spread of a view's
//! surfaces, the search for planes, the completion) keep their cost
//! bounded on a large capture.

/// The least n for which every n-th pixel of every n-th row of `pixels`
/// pixels is at most `most` of them (about: n² × that where rows do not
/// divide evenly).
pub fn lattice_stride(pixels: u64, most: u64) -> u32 {
    ((pixels as f64 / most.max(1) as f64).sqrt().ceil() as u32).max(1)
}

/// Every `stride`-th pixel of every `stride`-th row of a `width` ×
/// `height` picture, from its first pixel, row by row: the lattice's
/// `i`-th pixel is the picture's [`Lattice::pixel`]`(i)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lattice {
    /// The picture's width in pixels.
    pub width: u32,
    /// The picture's height in pixels.
    pub height: u32,
    /// The step between the lattice's pixels along a row and between its
    /// rows (1: every pixel).
    pub stride: u32,
}

impl Lattice {
    /// The lattice of `stride` (taken as 1 where 0) over a `width` ×
    /// `height` picture.
    pub fn new(width: u32, height: u32, stride: u32) -> Lattice {
        Lattice {
            width,
            height,
            stride: stride.max(1),
        }
    }

    /// The lattice's pixels along a row.
    pub fn columns(&self) -> u32 {
        self.width.div_ceil(self.stride)
    }

    /// The lattice's rows.
    pub fn rows(&self) -> u32 {
        self.height.div_ceil(self.stride)
    }

    /// The lattice's pixels.
    pub fn len(&self) -> u32 {
        self.columns() * self.rows()
    }

    /// Whether the lattice holds no pixel (an empty picture).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The picture's index (row by row) of the lattice's `i`-th pixel.
    pub fn pixel(&self, i: u32) -> u32 {
        let c = self.columns();
        (i / c) * self.stride * self.width + (i % c) * self.stride
    }

    /// The lattice's index of the picture's pixel `p`, where it lies on
    /// the lattice.
    pub fn index(&self, p: u32) -> Option<u32> {
        let (x, y) = (p % self.width, p / self.width);
        (x % self.stride == 0 && y % self.stride == 0)
            .then(|| (y / self.stride) * self.columns() + x / self.stride)
    }

    /// The lattice's indices of the pixels around the picture's pixel at
    /// column `x` and row `y`: itself where it lies on the lattice,
    /// otherwise the lattice's columns and rows on either side of it (two
    /// or four pixels; one or two at the picture's last column or row,
    /// past the lattice's last; none on an empty lattice).
    pub fn around(&self, x: u32, y: u32) -> impl Iterator<Item = u32> {
        let s = self.stride;
        let span = |at: u32, last: u32| {
            let i = at / s;
            i..=if at % s == 0 { i } else { (i + 1).min(last) }
        };
        let columns = span(x, self.columns().saturating_sub(1));
        let c = self.columns();
        // An empty lattice (of an empty picture) has no pixel around any.
        let most = if self.is_empty() { 0 } else { 4 };
        span(y, self.rows().saturating_sub(1))
            .flat_map(move |j| columns.clone().map(move |i| j * c + i))
            .take(most)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stride is the least that keeps the lattice under its cap.
    #[test]
    fn a_stride_keeps_the_lattice_under_its_cap() {
        assert_eq!(lattice_stride(0, 10), 1);
        assert_eq!(lattice_stride(10, 10), 1);
        assert_eq!(lattice_stride(11, 10), 2);
        assert_eq!(lattice_stride(100 * 800 * 800, 1 << 20), 8);
        assert_eq!(lattice_stride(5, 0), 3, "a cap of 0 read as 1");
    }

    /// On a 7 × 5 picture at stride 3, the lattice is columns 0, 3, 6 of
    /// rows 0 and 3, each pixel found where the picture's index says and
    /// its index found back; a pixel between takes the lattice pixels on
    /// either side, and one past the last lattice row or column only
    /// those before it.
    #[test]
    fn a_lattice_walks_its_pixels_and_finds_those_around_any_other() {
        let l = Lattice::new(7, 5, 3);
        assert_eq!((l.columns(), l.rows(), l.len()), (3, 2, 6));
        let pixels: Vec<u32> = (0..l.len()).map(|i| l.pixel(i)).collect();
        assert_eq!(pixels, [0, 3, 6, 21, 24, 27]);
        for (i, &p) in pixels.iter().enumerate() {
            assert_eq!(l.index(p), Some(i as u32));
        }
        assert_eq!((0..35).filter(|&p| l.index(p).is_some()).count(), 6);
        let around = |x, y| l.around(x, y).collect::<Vec<_>>();
        assert_eq!(around(3, 3), [4]);
        assert_eq!(around(4, 0), [1, 2]);
        assert_eq!(around(4, 1), [1, 2, 4, 5]);
        assert_eq!(around(0, 4), [3], "past the last row");
        assert_eq!(around(6, 2), [2, 5]);
        let every = Lattice::new(4, 2, 0);
        assert_eq!((every.stride, every.len()), (1, 8));
        let empty = Lattice::new(0, 3, 2);
        assert!(empty.is_empty());
        assert_eq!(
            empty.around(0, 0).count(),
            0,
            "no pixel around on an empty lattice"
        );
    }
}
