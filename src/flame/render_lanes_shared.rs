//! The lane game without queues (`render_lanes.rs`), for flames whose xforms share their terms
//! (the same variations with the same parameters, in the same order; weights may differ) and
//! their plotted weight: [`LANES`] orbits that stay in their lanes. A step takes each lane's
//! pre-affine map, `pre_blur` and term weights, colour and post map (if it has one) from the
//! xform it drew (every xform's affine maps are done for every lane, a few operations each) and
//! sums the terms once for all lanes. Nothing is queued: no point is stored for the next round
//! and loaded again.

use super::super::FUSE_ITERATIONS;
use super::{
    BlockGame, Cell, InFlight, LANES, LaneGame, LaneRng, Lanes, Scratch, Xform32, affine, pre_blur, sum_terms,
};
use crate::rng::Pcg32;

/// Most xforms a flame has for the shared-terms game (each one's affine maps are done for every
/// lane).
pub(super) const MAX_SHARED_XFORMS: usize = 8;

/// Whether `xforms` share their terms and plotted weight.
pub(super) fn share_terms(xforms: &[Xform32]) -> bool {
    let Some(first) = xforms.first() else { return false };
    xforms.len() <= MAX_SHARED_XFORMS
        && xforms.iter().all(|x| {
            x.terms.len() == first.terms.len()
                && x.terms.iter().zip(&first.terms).all(|(a, b)| a.variation == b.variation && a.k == b.k)
                && x.plotted_weight == first.plotted_weight
        })
}

/// The shared-terms game's blocks ([`LaneGame::run_block_shared`]).
pub(super) struct WithoutQueues;

impl BlockGame for WithoutQueues {
    #[inline(always)]
    fn run_block(&mut self, game: &LaneGame, seed: u32, block: u64, n: u64, histogram: &mut [Cell]) -> u64 {
        game.run_block_shared(seed, block, n, histogram)
    }
}

/// `a` where `pick`, else `b` (a blend, not a branch, in the vector loops).
#[inline(always)]
fn select(pick: bool, a: f32, b: f32) -> f32 {
    let keep = 0u32.wrapping_sub(u32::from(pick));
    f32::from_bits((a.to_bits() & keep) | (b.to_bits() & !keep))
}

impl LaneGame<'_> {
    /// Block `block` of a flame whose xforms share their terms ([`share_terms`]): [`LANES`]
    /// orbits until `n` samples are drawn after their fuse. Returns the re-seeds.
    #[inline(always)]
    pub(super) fn run_block_shared(&self, seed: u32, block: u64, n: u64, histogram: &mut [Cell]) -> u64 {
        let mut start = Pcg32::for_stream(seed, block as u32, 0x7FFF_FFFF);
        let mut rng = LaneRng::new(seed, block);
        let mut scratch = Scratch::new();
        let (mut x, mut y, mut c, mut xform) =
            (Lanes::splat(0.0), Lanes::splat(0.0), Lanes::splat(0.0), Lanes::splat(0u32));
        for l in 0..LANES {
            let ([px, py], color, j) = self.start_point(&mut start);
            (x[l], y[l], c[l], xform[l]) = (px, py, color, j as u32);
        }
        let first = &self.xforms[0];
        // Each term's weight in each lane, as its xform has it.
        let mut weights = vec![Lanes::splat(0.0); first.terms.len()];
        let posts = self.xforms.iter().any(|x| x.post.is_some());
        let blurred = self.xforms.iter().any(|x| x.pre_blur != 0.0);
        let mut pending = InFlight::new(self.camera.sink);
        let mut bad = 0;
        let mut drawn = 0u64;
        let mut round = -FUSE_ITERATIONS;
        while drawn < n {
            let plot = round >= 0;
            let count = if plot { (n - drawn).min(LANES as u64) as usize } else { LANES };
            if plot {
                drawn += count as u64;
            }
            // Each lane's xform's pre-affine map, term weights and colour.
            let p = &mut scratch.point;
            let before = c;
            for l in 0..LANES {
                [p.x[l], p.y[l]] = affine(&first.coefs, x[l], y[l]);
                c[l] = first.color_of(before[l]);
            }
            for (w, t) in weights.iter_mut().zip(&first.terms) {
                *w = Lanes::splat(t.weight);
            }
            for (j, xf) in self.xforms.iter().enumerate().skip(1) {
                for l in 0..LANES {
                    let here = xform[l] == j as u32;
                    let [tx, ty] = affine(&xf.coefs, x[l], y[l]);
                    p.x[l] = select(here, tx, p.x[l]);
                    p.y[l] = select(here, ty, p.y[l]);
                    c[l] = select(here, xf.color_of(before[l]), c[l]);
                }
                for (w, t) in weights.iter_mut().zip(&xf.terms) {
                    for l in 0..LANES {
                        w[l] = select(xform[l] == j as u32, t.weight, w[l]);
                    }
                }
            }
            if blurred {
                let mut blur = Lanes::splat(first.pre_blur);
                for (j, xf) in self.xforms.iter().enumerate().skip(1) {
                    for l in 0..LANES {
                        blur[l] = select(xform[l] == j as u32, xf.pre_blur, blur[l]);
                    }
                }
                pre_blur(&blur, p, &mut rng);
            } else {
                for l in 0..LANES {
                    p.r2[l] = p.x[l] * p.x[l] + p.y[l] * p.y[l];
                }
            }
            sum_terms(&first.terms, &*weights, first.needs, (&mut x, &mut y), &mut rng, &mut scratch);
            if posts {
                let (sx, sy) = (x, y);
                for (j, xf) in self.xforms.iter().enumerate() {
                    let Some(post) = &xf.post else { continue };
                    for l in 0..LANES {
                        let here = xform[l] == j as u32;
                        let [px, py] = affine(post, sx[l], sy[l]);
                        x[l] = select(here, px, x[l]);
                        y[l] = select(here, py, y[l]);
                    }
                }
            }
            let (reseeded, reseeds) = self.reseed(count, &mut x, &mut y, &mut rng);
            bad += reseeds;
            if plot && first.plotted_weight != 0.0 {
                self.plot(first, count, &reseeded, (&x, &y, &c), (&mut rng, &mut scratch), &mut pending, histogram);
            }
            xform = self.next_xforms(&xform, &mut rng);
            round += 1;
        }
        pending.finish(histogram);
        bad
    }
}
