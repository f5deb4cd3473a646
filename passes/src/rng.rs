//! A small deterministic random number generator (PCG32) so that bakes and
//! reference renders are reproducible from a seed, independent of threads.

/// PCG-XSH-RR 32-bit generator.
#[derive(Debug, Clone)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// A generator for `seed` on stream `stream` (e.g. a pixel or node index).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6364136223846793005).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform number in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        ((hi | lo) as f64) * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform numbers in [0, 1).
    pub fn next_2d(&mut self) -> [f64; 2] {
        [self.next_f64(), self.next_f64()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_in_unit_interval_and_reproducible() {
        let mut a = Pcg32::new(7, 3);
        let mut b = Pcg32::new(7, 3);
        let mut sum = 0.0;
        for _ in 0..10_000 {
            let x = a.next_f64();
            assert_eq!(x, b.next_f64());
            assert!((0.0..1.0).contains(&x));
            sum += x;
        }
        assert!((sum / 10_000.0 - 0.5).abs() < 0.01);
        assert_ne!(Pcg32::new(7, 4).next_u32(), Pcg32::new(7, 3).next_u32());
    }
}
