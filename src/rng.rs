//! The one random generator of nlifs, shared bit for bit with the WGSL side
//! (`shaders/rng.wgsl`): a 32-bit PCG (RXS-M-XS output) with streams derived by hashing.
//! Chain `i` of frame `f` draws from `Pcg32::for_stream(seed, f, i)`, so every render is a pure
//! function of its seed.

/// LCG multiplier and increment of the 32-bit PCG, the same constants as in `rng.wgsl`.
pub(crate) const PCG_MUL: u32 = 747_796_405;
pub(crate) const PCG_INC: u32 = 2_891_336_453;
/// Multiplier of the RXS-M-XS output function.
pub(crate) const PCG_OUT_MUL: u32 = 277_803_737;

/// One PCG-RXS-M-XS round: used both as the generator's output function and as a hash.
#[inline(always)]
pub fn pcg_hash(input: u32) -> u32 {
    let state = input.wrapping_mul(PCG_MUL).wrapping_add(PCG_INC);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(PCG_OUT_MUL);
    (word >> 22) ^ word
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pcg32 {
    state: u32,
}

impl Pcg32 {
    /// The stream of chain `chain` in frame `frame` of a run seeded with `seed`.
    pub fn for_stream(seed: u32, frame: u32, chain: u32) -> Self {
        let state = pcg_hash(seed ^ pcg_hash(frame ^ pcg_hash(chain)));
        Self { state }
    }

    /// The generator's state, for kernels that advance many generators as vectors (the same
    /// steps as [`Self::next_u32`]).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code, reason = "used by the x86-64 vector kernels only"))]
    pub(crate) fn state(self) -> u32 {
        self.state
    }

    /// The generator whose [`Self::state`] is `state` (kernels hand their generators back).
    pub(crate) fn from_state(state: u32) -> Self {
        Self { state }
    }

    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MUL).wrapping_add(PCG_INC);
        let word = ((old >> ((old >> 28) + 4)) ^ old).wrapping_mul(PCG_OUT_MUL);
        (word >> 22) ^ word
    }

    /// Uniform in [0, 1) with 24 bits of resolution (exact in f32).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [0, 1) with 53 bits of resolution (two draws; the flames' chaos game).
    #[inline(always)]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() >> 5) as u64;
        let lo = (self.next_u32() >> 6) as u64;
        ((hi << 26) | lo) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_differ_and_repeat() {
        let mut a = Pcg32::for_stream(1, 0, 0);
        let mut b = Pcg32::for_stream(1, 0, 1);
        let mut a2 = Pcg32::for_stream(1, 0, 0);
        let xs: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        let ys: Vec<u32> = (0..8).map(|_| b.next_u32()).collect();
        let xs2: Vec<u32> = (0..8).map(|_| a2.next_u32()).collect();
        assert_ne!(xs, ys);
        assert_eq!(xs, xs2);
    }

    #[test]
    fn uniform_mean() {
        let mut r = Pcg32::for_stream(7, 3, 5);
        let n = 200_000;
        let mean: f64 = (0..n).map(|_| r.next_f32() as f64).sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1) is sqrt(1/12/n) = 6.5e-4; allow 5 sigma.
        assert!((mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt(), "mean {mean}");
    }
}
