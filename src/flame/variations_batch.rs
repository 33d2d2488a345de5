//! The batch path of [`CompiledXform`]: up to [`BATCH`] points mapped at once, each quantity a
//! loop over the points, so that the affine maps, the shared quantities and the arithmetic and
//! smooth variations run in vector registers (the chaos game's AVX-512 and AVX2 builds,
//! `flame/render.rs`); and the point-by-point path of a group, out of line.

use super::{CompiledXform, DRAWS, NEEDS_ANGLES, NEEDS_ATAN_XY, NEEDS_ATAN_YX, NEEDS_SQRT, Point, basic, plugins};
use crate::flame::{apply_coefs, trig};
use crate::rng::Pcg32;

/// Most points [`CompiledXform::apply_batch`] maps in one call.
pub const BATCH: usize = 256;

/// A chain's (or lane's) number, as the batch's callers list the points' generators.
pub type ChainNumber = u32;
const _: () = assert!(BATCH as u64 <= ChainNumber::MAX as u64 + 1, "chain numbers fit");

/// The work space of [`CompiledXform::apply_batch`], [`Point`]'s quantities as one array each
/// (so that the loops over them are vector loops), kept by the caller between calls.
#[derive(Clone, Debug)]
pub struct BatchScratch {
    tx: [f64; BATCH],
    ty: [f64; BATCH],
    sumsq: [f64; BATCH],
    sqrt: [f64; BATCH],
    atan_xy: [f64; BATCH],
    sina: [f64; BATCH],
    cosa: [f64; BATCH],
    atan_yx: [f64; BATCH],
    ox: [f64; BATCH],
    oy: [f64; BATCH],
    /// One term's contribution, and its random draws (`basic::smooth_draw`).
    dx: [f64; BATCH],
    dy: [f64; BATCH],
    draw: [[f64; DRAWS]; BATCH],
}

impl Default for BatchScratch {
    fn default() -> Self {
        let zero = [0.0; BATCH];
        Self {
            tx: zero,
            ty: zero,
            sumsq: zero,
            sqrt: zero,
            atan_xy: zero,
            sina: zero,
            cosa: zero,
            atan_yx: zero,
            ox: zero,
            oy: zero,
            dx: zero,
            dy: zero,
            draw: [[0.0; DRAWS]; BATCH],
        }
    }
}

/// Whether `basic::eval_smooth` or `plugins::eval_smooth` holds variation `v`'s formula.
fn smooth(v: u8) -> bool {
    if v < plugins::FIRST { basic::smooth(v) } else { plugins::smooth(v) }
}

/// The random numbers variation `v`'s smooth formula takes, drawn from `rng`.
#[inline(always)]
fn smooth_draw(v: u8, rng: &mut Pcg32) -> [f64; DRAWS] {
    if v < plugins::FIRST { basic::smooth_draw(v, rng) } else { plugins::smooth_draw(v, rng) }
}

/// Whether variation `v`'s formula takes random numbers ([`smooth_draw`]).
const fn smooth_draws(v: u8) -> bool {
    if v < plugins::FIRST { basic::smooth_draw_count(v) > 0 } else { plugins::smooth_draw_count(v) > 0 }
}

/// Variation `v`'s smooth formula (`basic::eval_smooth`, `plugins::eval_smooth`).
#[inline(always)]
fn eval_smooth(
    v: u8,
    w: f64,
    k: &[f64; 8],
    pt: &Point,
    draw: [f64; DRAWS],
    m: &mut impl trig::Elementary,
) -> Option<[f64; 2]> {
    if v < plugins::FIRST {
        basic::eval_smooth(v, w, k, pt, draw, m)
    } else {
        plugins::eval_smooth(v, w, k, pt, draw, m)
    }
}

/// `out[j]` = atan2(`y[j]`, `x[j]`): `trig`'s branch-free core, a vector loop; where a lane's
/// arguments are not finite, every lane again by `trig::atan2`, which gives the same bits for
/// the others.
#[inline(always)]
fn atan2_lanes(out: &mut [f64], y: &[f64], x: &[f64]) {
    let mut finite = true;
    for ((out, &y), &x) in out.iter_mut().zip(y).zip(x) {
        let (a, ok) = trig::atan2_core(y, x);
        *out = a;
        finite &= ok;
    }
    if !finite {
        for ((out, &y), &x) in out.iter_mut().zip(y).zip(x) {
            *out = trig::atan2(y, x);
        }
    }
}

impl CompiledXform {
    /// [`Self::apply`] of each point (`x[j]`, `y[j]`) in place, drawing from `rngs[chain[j]]`: the
    /// point-by-point path of the chaos game's groups. Not inlined: inside the chaos game's
    /// vector build, next to [`Self::apply_batch`]'s loops, the scalar code was compiled
    /// worse (spiral-julian 2.0 → 2.6 s).
    #[inline(never)]
    pub fn apply_each(&self, x: &mut [f64], y: &mut [f64], chain: &[ChainNumber], rngs: &mut [Pcg32]) {
        for ((x, y), &k) in x.iter_mut().zip(y.iter_mut()).zip(chain) {
            [*x, *y] = self.apply([*x, *y], &mut rngs[k as usize]);
        }
    }

    /// Whether [`Self::apply_batch`] gains over [`Self::apply`] point by point: every term is
    /// one of the arithmetic variations or the smooth ones (`basic::eval_smooth`), computed in
    /// vector registers. (With the others the batch's bookkeeping measured slower than the
    /// point-by-point path.)
    #[inline]
    pub fn batches(&self) -> bool {
        self.terms.iter().all(|t| matches!(t.variation, 0 | 2 | 4 | 5 | 10) || smooth(t.variation))
    }

    /// [`Self::apply`] of up to [`BATCH`] points at once, in place: point j is
    /// (`x[j]`, `y[j]`) and draws its random numbers from `rngs[chain[j]]`. Each quantity is
    /// computed for all the points in a loop of its own, so the affine maps, the shared
    /// quantities, the arithmetic variations (linear, spherical, horseshoe, polar, hyperbolic)
    /// and the smooth ones (`basic::eval_smooth`, with `trig`'s functions) run in vector
    /// registers; the other variations run point by point. Every point goes through the same
    /// operations in the same order as in `apply`, and draws the same numbers in the same
    /// order from its generator, so the results are the same bits.
    #[inline(always)]
    pub fn apply_batch(
        &self,
        x: &mut [f64],
        y: &mut [f64],
        chain: &[ChainNumber],
        rngs: &mut [Pcg32],
        s: &mut BatchScratch,
    ) {
        let m = x.len().min(y.len()).min(chain.len()).min(BATCH);
        let (x, y, chain) = (&mut x[..m], &mut y[..m], &chain[..m]);
        for j in 0..m {
            [s.tx[j], s.ty[j]] = apply_coefs(&self.coefs, [x[j], y[j]]);
        }
        if self.pre_blur != 0.0 {
            for j in 0..m {
                let [dx, dy] = plugins::pre_blur_offset(self.pre_blur, &mut rngs[chain[j] as usize]);
                s.tx[j] += dx;
                s.ty[j] += dy;
            }
        }
        let needs = |flag: u8| self.needs & flag != 0;
        for j in 0..m {
            s.sumsq[j] = s.tx[j] * s.tx[j] + s.ty[j] * s.ty[j];
        }
        // (The terms that read none of r, sina and cosa see r = 0.)
        let sqrt = needs(NEEDS_SQRT | NEEDS_ANGLES);
        if sqrt {
            for j in 0..m {
                s.sqrt[j] = s.sumsq[j].sqrt();
            }
        }
        if needs(NEEDS_ATAN_XY) {
            atan2_lanes(&mut s.atan_xy[..m], &s.tx[..m], &s.ty[..m]);
        }
        if needs(NEEDS_ANGLES) {
            for j in 0..m {
                s.sina[j] = s.tx[j] / s.sqrt[j];
                s.cosa[j] = s.ty[j] / s.sqrt[j];
            }
        }
        if needs(NEEDS_ATAN_YX) {
            atan2_lanes(&mut s.atan_yx[..m], &s.ty[..m], &s.tx[..m]);
        }
        // The quantities `apply` leaves at 0 stay 0 here, whatever earlier calls left.
        let (xy, angles, yx) = (needs(NEEDS_ATAN_XY), needs(NEEDS_ANGLES), needs(NEEDS_ATAN_YX));
        let point = |s: &BatchScratch, j: usize| Point {
            tx: s.tx[j],
            ty: s.ty[j],
            sumsq: s.sumsq[j],
            sqrt: if sqrt { s.sqrt[j] } else { 0.0 },
            atan_xy: if xy { s.atan_xy[j] } else { 0.0 },
            sina: if angles { s.sina[j] } else { 0.0 },
            cosa: if angles { s.cosa[j] } else { 0.0 },
            atan_yx: if yx { s.atan_yx[j] } else { 0.0 },
        };
        s.ox[..m].fill(0.0);
        s.oy[..m].fill(0.0);
        for t in &self.terms {
            let w = t.weight;
            // One loop per arithmetic variation, its number a constant, so that each is a
            // straight vector loop.
            macro_rules! each {
                ($v:literal) => {
                    for j in 0..m {
                        let d = basic::eval_arithmetic($v, w, &point(s, j)).unwrap_or_default();
                        s.ox[j] += d[0];
                        s.oy[j] += d[1];
                    }
                };
            }
            // The smooth variations (`basic::eval_smooth`) likewise, their sin, cos, tan, exp
            // and pow `trig`'s cores; where a lane's argument is beyond a core's range, every
            // lane again with `trig`'s exact functions, which give the same bits for the others.
            // julia's, julian's and juliascope's random numbers are drawn first, one per point,
            // as `apply` draws them.
            macro_rules! smooth {
                ($v:literal) => {{
                    // (A variation that draws nothing does not read `s.draw`.)
                    if const { smooth_draws($v) } {
                        for j in 0..m {
                            s.draw[j] = smooth_draw($v, &mut rngs[chain[j] as usize]);
                        }
                    }
                    let mut in_range = true;
                    for j in 0..m {
                        let mut lane = trig::InRange { in_range: true };
                        let d = eval_smooth($v, w, &t.k, &point(s, j), s.draw[j], &mut lane).unwrap_or_default();
                        s.dx[j] = d[0];
                        s.dy[j] = d[1];
                        in_range &= lane.in_range;
                    }
                    if !in_range {
                        for j in 0..m {
                            let d =
                                eval_smooth($v, w, &t.k, &point(s, j), s.draw[j], &mut trig::Exact).unwrap_or_default();
                            s.dx[j] = d[0];
                            s.dy[j] = d[1];
                        }
                    }
                    for j in 0..m {
                        s.ox[j] += s.dx[j];
                        s.oy[j] += s.dy[j];
                    }
                }};
            }
            // The arithmetic and the smooth variations, each number a constant in its arm.
            macro_rules! by_variation {
                (arithmetic: $($a:literal)*; smooth: $($n:literal)*; other $v:ident => $other:block) => {
                    match t.variation {
                        $($a => each!($a),)*
                        $($n => smooth!($n),)*
                        $v => $other
                    }
                };
            }
            by_variation! {
                arithmetic: 0 2 4 5 10;
                smooth: 1 3 6 7 8 9 11 12 13 14 15 16 17 18 19 20 23 24 27 28 29 30 31 32 33 34 35 36 37
                    39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 60 63 64 66 69 70 71 72 73 74 75 76 77
                    78 79 80 81 82 83 84 85 86 87 88 89 90 91 92 93 94 95 96 97 98 99;
                other
                v => {
                    for j in 0..m {
                        let rng = &mut rngs[chain[j] as usize];
                        let pt = point(s, j);
                        let d = if v < plugins::FIRST {
                            basic::eval(v, w, &t.k, &pt, rng)
                        } else {
                            plugins::eval(v, w, &t.k, &pt, rng)
                        };
                        s.ox[j] += d[0];
                        s.oy[j] += d[1];
                    }
                }
            }
        }
        for j in 0..m {
            [x[j], y[j]] = match &self.post {
                Some(post) => apply_coefs(post, [s.ox[j], s.oy[j]]),
                None => [s.ox[j], s.oy[j]],
            };
        }
    }
}
