//! The state a worker of the flame chaos game (`render.rs`) keeps: its chains, and the arrays of
//! one round, one entry per chain, so that the round's phases are loops over the chains that
//! the compiler can turn into vector loops.

use super::variations::ChainNumber;
use crate::rng::Pcg32;

/// Runs one worker advances together: their iterations are independent, so the core overlaps
/// them, and it maps the chains that drew one xform as a batch in vector registers.
pub(super) const CHAINS: usize = super::variations::BATCH;

/// Iterations dropped at the start of every run (flam3's `FUSE_27`): a run starts at
/// iteration −`FUSE_ITERATIONS` and plots from 0.
pub const FUSE_ITERATIONS: i64 = 15;

/// The runs one worker advances together, chain by chain in arrays; chains `0..live` are
/// running.
pub(super) struct Chains {
    pub live: usize,
    pub rng: [Pcg32; CHAINS],
    pub x: [f64; CHAINS],
    pub y: [f64; CHAINS],
    pub color: [f64; CHAINS],
    /// The previous xform + 1 (0 at the start): the xaos row.
    pub last: [usize; CHAINS],
    pub consecutive_bad: [u32; CHAINS],
    /// The iteration, from −[`FUSE_ITERATIONS`]; the run ends at `n`.
    pub i: [i64; CHAINS],
    pub n: [i64; CHAINS],
}

impl Chains {
    /// Every chain live and finished, so that the first round starts a run on each.
    pub fn new() -> Self {
        Self {
            live: CHAINS,
            rng: [Pcg32::from_state(0); CHAINS],
            x: [0.0; CHAINS],
            y: [0.0; CHAINS],
            color: [0.0; CHAINS],
            last: [0; CHAINS],
            consecutive_bad: [0; CHAINS],
            i: [0; CHAINS],
            n: [0; CHAINS],
        }
    }

    pub fn start(&mut self, k: usize, (rng, p, color, n): (Pcg32, [f64; 2], f64, i64)) {
        (self.rng[k], [self.x[k], self.y[k]], self.color[k]) = (rng, p, color);
        (self.last[k], self.consecutive_bad[k], self.i[k], self.n[k]) = (0, 0, -FUSE_ITERATIONS, n);
    }

    /// Chain `from`'s state into chain `to`.
    pub fn move_chain(&mut self, from: usize, to: usize) {
        self.rng[to] = self.rng[from];
        (self.x[to], self.y[to], self.color[to]) = (self.x[from], self.y[from], self.color[from]);
        (self.last[to], self.consecutive_bad[to]) = (self.last[from], self.consecutive_bad[from]);
        (self.i[to], self.n[to]) = (self.i[from], self.n[from]);
    }
}

/// One round's quantities, chain by chain (index k) or, for a group being mapped, member by
/// member (index j).
pub(super) struct Round {
    /// Each chain's entry into the choice table, and the xform it picks.
    pub entry: [u32; CHAINS],
    pub chosen: [u32; CHAINS],
    /// Per xform: chains that drew it, and where its group starts in `order`.
    pub count: Vec<ChainNumber>,
    pub start: Vec<ChainNumber>,
    /// The xforms drawn this round.
    pub drawn: Vec<usize>,
    /// The chains grouped by xform ([`Self::group`]; room for one vector past the last), and
    /// each chain's place in its group.
    pub order: [ChainNumber; CHAINS + 16],
    pub rank: [ChainNumber; CHAINS],
    /// A group's points, member by member, as the batch maps them.
    pub gx: [f64; CHAINS],
    pub gy: [f64; CHAINS],
    /// Each chain's colour after its xform, and its xform's plotted weight.
    pub next_color: [f64; CHAINS],
    pub weight: [f64; CHAINS],
    /// Whether the chain's step counts (a retried step after a re-seed does not).
    pub plot: [bool; CHAINS],
    /// What the chain shows: its point, or the final xform's copy of it, and the colour.
    pub sx: [f64; CHAINS],
    pub sy: [f64; CHAINS],
    pub shown_color: [f64; CHAINS],
    /// The chains that apply the final xform this round.
    pub finals: Vec<ChainNumber>,
    /// The bucket each chain adds to (0 where it adds nothing) and whether it adds.
    pub bucket: [u32; CHAINS],
    pub adds: [bool; CHAINS],
    /// The entry of the step palette each chain's colour picks.
    pub step_entry: [u32; CHAINS],
}

impl Round {
    pub fn new(xforms: usize) -> Self {
        Self {
            entry: [0; CHAINS],
            chosen: [0; CHAINS],
            count: vec![0; xforms],
            start: vec![0; xforms],
            drawn: Vec::with_capacity(CHAINS),
            order: [0; CHAINS + 16],
            rank: [0; CHAINS],
            gx: [0.0; CHAINS],
            gy: [0.0; CHAINS],
            next_color: [0.0; CHAINS],
            weight: [0.0; CHAINS],
            plot: [false; CHAINS],
            sx: [0.0; CHAINS],
            sy: [0.0; CHAINS],
            shown_color: [0.0; CHAINS],
            finals: Vec::with_capacity(CHAINS),
            bucket: [0; CHAINS],
            adds: [false; CHAINS],
            step_entry: [0; CHAINS],
        }
    }
}

/// Most xforms [`Round::group`] sorts with one pass over the chains each.
#[cfg(target_arch = "x86_64")]
const VECTOR_GROUPING_XFORMS: usize = 64;

impl Round {
    /// Chains `0..live` grouped by the xform they drew (`chosen`, each below `xforms`): the
    /// xforms drawn (`drawn`), each group's size and start (`count`, `start`) and the chains
    /// group by group (`order`), each group in chain order. `count` is 0 for every xform before.
    /// With `wide` (the CPU runs AVX-512F), one compare and compress of 16 chains at a time
    /// per xform, for up to 64 xforms; otherwise a counting sort.
    #[inline(always)]
    pub fn group(&mut self, live: usize, xforms: usize, wide: bool) {
        let live = live.min(CHAINS);
        self.drawn.clear();
        #[cfg(target_arch = "x86_64")]
        if wide && xforms <= VECTOR_GROUPING_XFORMS {
            #[expect(unsafe_code, reason = "an AVX-512 function, entered after the CPU check")]
            // SAFETY: `wide` is set only where the CPU runs AVX-512F.
            unsafe {
                self.group_avx512(live, xforms)
            };
            return;
        }
        let _ = (wide, xforms);
        for k in 0..live {
            let x = self.chosen[k] as usize;
            if self.count[x] == 0 {
                self.drawn.push(x);
            }
            self.rank[k] = self.count[x];
            self.count[x] += 1;
        }
        let mut at: ChainNumber = 0;
        for &x in &self.drawn {
            self.start[x] = at;
            at += self.count[x];
        }
        // (With the ranks, no store here feeds a later load, as a running `start[x] += 1` did.)
        for (k, (&x, &rank)) in self.chosen[..live].iter().zip(&self.rank[..live]).enumerate() {
            self.order[(self.start[x as usize] + rank) as usize] = k as ChainNumber;
        }
    }

    /// [`Self::group`] with AVX-512F: per xform, the chains that drew it, 16 at a time,
    /// compressed into `order`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn group_avx512(&mut self, live: usize, xforms: usize) {
        use std::arch::x86_64::*;
        let live = live.min(CHAINS);
        let lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let mut at = 0;
        for x in 0..xforms.min(self.count.len()).min(self.start.len()) {
            let first = at;
            let wanted = _mm512_set1_epi32(x as i32);
            for block in (0..live).step_by(16) {
                let valid: __mmask16 = if live - block >= 16 { 0xFFFF } else { (1 << (live - block)) - 1 };
                #[expect(unsafe_code, reason = "unaligned vector load and store of 16 lanes")]
                // SAFETY: `block < live <= CHAINS`, and the load is masked to the lanes below
                // `live`; `at` counts chains placed so far, at most `live`, and order has
                // CHAINS + 16 entries.
                unsafe {
                    let chosen = _mm512_maskz_loadu_epi32(valid, self.chosen.as_ptr().add(block).cast());
                    let hits = _mm512_mask_cmpeq_epi32_mask(valid, chosen, wanted);
                    let chains = _mm512_add_epi32(lanes, _mm512_set1_epi32(block as i32));
                    let packed = _mm512_maskz_compress_epi32(hits, chains);
                    _mm512_storeu_si512(self.order.as_mut_ptr().add(at).cast(), packed);
                    at += hits.count_ones() as usize;
                }
            }
            let count = at - first;
            if count > 0 {
                self.drawn.push(x);
                self.start[x] = first as ChainNumber;
                self.count[x] = count as ChainNumber;
            }
        }
    }
}
