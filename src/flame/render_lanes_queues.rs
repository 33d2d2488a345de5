//! The lane chaos game's queues (`render_lanes.rs`): its pool of points, one queue per xform,
//! this round's and the next's.

use super::{LANES, Lanes, POINTS};

/// The points' queues, one per xform, this round's and the next's: x, y and colour, each
/// xform's stretch [`POINTS`] + [`LANES`] long (a vector may be loaded or stored past the last
/// point), in [`Lanes`] on cache lines of their own: a step's loads are whole lines.
pub(super) struct Queues {
    stride: usize,
    /// Whether the CPU runs AVX-512F: the appends compress.
    wide: bool,
    x: Vec<Lanes>,
    y: Vec<Lanes>,
    c: Vec<Lanes>,
    pub(super) len: Vec<usize>,
    next_x: Vec<Lanes>,
    next_y: Vec<Lanes>,
    next_c: Vec<Lanes>,
    next_len: Vec<usize>,
}

/// The values of `lanes`, one after another.
fn flat(lanes: &mut [Lanes]) -> &mut [f32] {
    bytemuck::cast_slice_mut(lanes)
}

impl Queues {
    pub(super) fn new(xforms: usize, wide: bool) -> Self {
        let stride = POINTS + LANES;
        let zeros = vec![Lanes::splat(0.0); stride / LANES * xforms];
        Self {
            stride,
            wide,
            x: zeros.clone(),
            y: zeros.clone(),
            c: zeros.clone(),
            len: vec![0; xforms],
            next_x: zeros.clone(),
            next_y: zeros.clone(),
            next_c: zeros,
            next_len: vec![0; xforms],
        }
    }

    pub(super) fn clear(&mut self) {
        self.next_len.fill(0);
        self.len.fill(0);
    }

    /// Queues a starting point for the first round.
    pub(super) fn push(&mut self, j: usize, p: [f32; 2], color: f32) {
        let at = j * self.stride + self.len[j];
        (flat(&mut self.x)[at], flat(&mut self.y)[at], flat(&mut self.c)[at]) = (p[0], p[1], color);
        self.len[j] += 1;
    }

    /// The [`LANES`] points from `at`, a multiple of [`LANES`], of xform `j`'s queue (past its
    /// end: the point (1, 1), [`Self::clear_tail`]).
    #[inline(always)]
    pub(super) fn load(&self, j: usize, at: usize) -> (Lanes, Lanes, Lanes) {
        debug_assert!(at.is_multiple_of(LANES));
        let k = (j * self.stride + at) / LANES;
        (self.x[k], self.y[k], self.c[k])
    }

    /// Sets the [`LANES`] places past the end of xform `j`'s queue, which its last vector loads,
    /// to the point (1, 1) of colour 0: they take part in that vector's range tests, and the
    /// AVX-512 and portable appends leave different values there, so that without this the two
    /// builds' pictures would differ. Not the origin, where r² = 0 is outside the fast
    /// logarithm's range: those lanes went again through the exact functions (`wedge_julia`'s
    /// power, 3 % of its flame's time), for points that are never plotted.
    pub(super) fn clear_tail(&mut self, j: usize) {
        let from = j * self.stride + self.len[j].min(POINTS);
        flat(&mut self.x)[from..from + LANES].fill(1.0);
        flat(&mut self.y)[from..from + LANES].fill(1.0);
        flat(&mut self.c)[from..from + LANES].fill(0.0);
    }

    /// Appends lanes `0..count` to the next round's queues of their xforms `next`: with `wide`
    /// (the CPU runs AVX-512F), one compress a quantity per xform.
    #[inline(always)]
    pub(super) fn append(&mut self, next: &Lanes<u32>, count: usize, x: &Lanes, y: &Lanes, c: &Lanes) {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = self.wide;
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            #[expect(unsafe_code, reason = "an AVX-512 function, entered after the CPU check")]
            // SAFETY: `wide` is set only where the CPU runs AVX-512F and POPCNT (`vector_builds!`).
            unsafe {
                self.append_avx512(next, count, x, y, c)
            };
            return;
        }
        let (next_x, next_y, next_c) = (flat(&mut self.next_x), flat(&mut self.next_y), flat(&mut self.next_c));
        for l in 0..count.min(LANES) {
            let j = next[l] as usize;
            let at = j * self.stride + self.next_len[j];
            next_x[at] = x[l];
            next_y[at] = y[l];
            next_c[at] = c[l];
            self.next_len[j] += 1;
        }
    }

    /// [`Self::append`] with AVX-512F: per xform and per vector of 16 lanes, the lanes going to it
    /// compressed and stored (in lane order, as the portable append; the xform's length is kept
    /// in a register across its vectors, not stored and loaded again).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,popcnt")]
    #[inline]
    fn append_avx512(&mut self, next: &Lanes<u32>, count: usize, x: &Lanes, y: &Lanes, c: &Lanes) {
        use std::arch::x86_64::*;
        const PARTS: usize = LANES / 16;
        const _: () = assert!(LANES.is_multiple_of(16), "the lanes are whole AVX-512 vectors");
        #[expect(unsafe_code, reason = "unaligned vector loads and stores of 16 lanes")]
        // SAFETY: the loads read 16 lanes from `16 p` < LANES of arrays of LANES, a multiple of
        // 16; each store writes 16 floats at `at`, within xform j's stretch: the pool's points
        // number at most POINTS, so a queue's length is at most POINTS and the stretch is
        // POINTS + LANES long.
        unsafe {
            let part = |v: &Lanes, p: usize| _mm512_loadu_ps(v[16 * p..].as_ptr());
            let valid: [__mmask16; PARTS] = std::array::from_fn(|p| {
                let left = count.saturating_sub(16 * p);
                if left >= 16 { 0xFFFF } else { (1 << left) - 1 }
            });
            let next: [__m512i; PARTS] = std::array::from_fn(|p| _mm512_loadu_si512(next[16 * p..].as_ptr().cast()));
            for j in 0..self.next_len.len() {
                let mut len = self.next_len[j];
                for p in 0..PARTS {
                    let hits = _mm512_mask_cmpeq_epi32_mask(valid[p], next[p], _mm512_set1_epi32(j as i32));
                    if hits == 0 {
                        continue;
                    }
                    let at = j * self.stride + len.min(POINTS);
                    debug_assert!(at + 16 <= self.next_x.len() * LANES);
                    let store = |to: &mut Vec<Lanes>, v| _mm512_storeu_ps(to.as_mut_ptr().cast::<f32>().add(at), v);
                    store(&mut self.next_x, _mm512_maskz_compress_ps(hits, part(x, p)));
                    store(&mut self.next_y, _mm512_maskz_compress_ps(hits, part(y, p)));
                    store(&mut self.next_c, _mm512_maskz_compress_ps(hits, part(c, p)));
                    len += hits.count_ones() as usize;
                }
                self.next_len[j] = len;
            }
        }
    }

    pub(super) fn next_round(&mut self) {
        std::mem::swap(&mut self.x, &mut self.next_x);
        std::mem::swap(&mut self.y, &mut self.next_y);
        std::mem::swap(&mut self.c, &mut self.next_c);
        std::mem::swap(&mut self.len, &mut self.next_len);
        self.next_len.fill(0);
    }
}
