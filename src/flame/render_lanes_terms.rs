//! The lane game's xform maps (`render_lanes.rs`): the affine maps, and the sum of an xform's
//! terms over the lanes, each variation a vector loop of `variations_lanes.rs`'s formula.

use super::{Draws, LANES, LaneRng, Lanes, PointLanes, Scratch, Term32};
use crate::flame::trig32::{self, Exact32, Fast32};
use crate::flame::variations::{MAX_CONSTS, NEEDS_ANGLES, NEEDS_ATAN_XY, NEEDS_ATAN_YX, NEEDS_SQRT};
use crate::flame::variations_lanes::{self as lanes, Draw};

/// `c` applied to (`x`, `y`): x' = a·x + c·y + e, y' = b·x + d·y + f, as flam3 reads its coefs.
#[inline(always)]
pub(super) fn affine(c: &[f32; 6], x: f32, y: f32) -> [f32; 2] {
    [c[0] * x + c[2] * y + c[4], c[1] * x + c[3] * y + c[5]]
}

/// Where a term's weights are: its own (the same in every lane), or one a lane.
pub(super) trait TermWeights {
    /// Term `term`'s weight in lane `l`.
    fn weight(&self, term: usize, l: usize) -> f32;
}

impl TermWeights for [Term32] {
    #[inline(always)]
    fn weight(&self, term: usize, _: usize) -> f32 {
        self[term].weight
    }
}

impl TermWeights for [Lanes] {
    #[inline(always)]
    fn weight(&self, term: usize, l: usize) -> f32 {
        self[term][l]
    }
}

/// The sum of `terms`, weighted by `weights`, at the points `scratch.point.x`, `.y` (and `.r2`,
/// their squared radii), in (`x`, `y`); `needs`: the other quantities the terms read.
#[inline(always)]
pub(super) fn sum_terms<W: TermWeights + ?Sized>(
    terms: &[Term32],
    weights: &W,
    needs: u8,
    (x, y): (&mut Lanes, &mut Lanes),
    rng: &mut LaneRng,
    scratch: &mut Scratch,
) {
    let Scratch { point: p, draw, dx, dy, fast } = scratch;
    if needs & (NEEDS_SQRT | NEEDS_ANGLES) != 0 {
        for l in 0..LANES {
            p.r[l] = p.r2[l].sqrt();
        }
    }
    if needs & NEEDS_ATAN_XY != 0 {
        atan2_lanes(&mut p.a, &p.x, &p.y);
    }
    if needs & NEEDS_ANGLES != 0 {
        for l in 0..LANES {
            p.sa[l] = p.x[l] / p.r[l];
            p.ca[l] = p.y[l] / p.r[l];
        }
    }
    if needs & NEEDS_ATAN_YX != 0 {
        atan2_lanes(&mut p.ayx, &p.y, &p.x);
    }
    // The terms' sum, in place of the point (its quantities are in `p`).
    (*x, *y) = (Lanes::splat(0.0), Lanes::splat(0.0));
    for (term, t) in terms.iter().enumerate() {
        let k = &t.k;
        // One loop per variation, its number a constant, so that each is a vector loop; where
        // a lane's argument is beyond a core's range, that lane again with `Exact32`.
        macro_rules! term {
            ($v:literal) => {{
                match const { lanes::draw_of($v) } {
                    Draw::None => {}
                    Draw::Bit => draw.0[0] = rng.bits().0,
                    Draw::Uniform(n) => {
                        for d in &mut draw.0[..n] {
                            *d = rng.uniform().0;
                        }
                    }
                }
                let mut in_range = true;
                for l in 0..LANES {
                    let mut m = Fast32 { in_range: true };
                    [dx[l], dy[l]] =
                        lanes::eval::<$v, LANES>(weights.weight(term, l), k, &p.lane(l), &draw.0, l, &mut m);
                    fast[l] = m.in_range;
                    in_range &= m.in_range;
                }
                if !in_range {
                    let w = Lanes(std::array::from_fn(|l| weights.weight(term, l)));
                    exact_term::<$v>(&w, k, p, draw, fast, dx, dy);
                }
                for l in 0..LANES {
                    x[l] += dx[l];
                    y[l] += dy[l];
                }
            }};
        }
        macro_rules! by_variation {
            ($($v:literal)*) => {
                match t.variation {
                    $($v => term!($v),)*
                    _ => {}
                }
            };
        }
        // (flatten, 100, adds nothing in the plane.)
        by_variation!(
            0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32 33 34 35 36 37
            38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61 62 63 64 65 66 68 69 70 71 72
            73 74 75 76 77 78 79 80 81 82 83 84 85 86 87 88 89 90 91 92 93 94 95 96 97 98 99
        );
    }
}

/// Variation `V`'s terms with [`Exact32`] in the lanes not `fast`: where a core's argument was
/// out of its range. Out of line and cold: inlined, it slowed the vector loops it stands beside
/// (3×).
#[cold]
#[inline(never)]
fn exact_term<const V: u8>(
    w: &Lanes,
    k: &[f32; MAX_CONSTS],
    p: &PointLanes,
    draw: &Draws,
    fast: &Lanes<bool>,
    dx: &mut Lanes,
    dy: &mut Lanes,
) {
    for l in (0..LANES).filter(|&l| !fast[l]) {
        [dx[l], dy[l]] = lanes::eval::<V, LANES>(w[l], k, &p.lane(l), &draw.0, l, &mut Exact32);
    }
}

/// `out[l]` = atan2(`y[l]`, `x[l]`): `trig32`'s core; every lane again in f64 where one is not
/// finite.
#[inline(always)]
fn atan2_lanes(out: &mut Lanes, y: &Lanes, x: &Lanes) {
    let mut finite = true;
    for l in 0..LANES {
        let (a, ok) = trig32::atan2_core(y[l], x[l]);
        out[l] = a;
        finite &= ok;
    }
    if !finite {
        for l in 0..LANES {
            out[l] = f64::from(y[l]).atan2(f64::from(x[l])) as f32;
        }
    }
}
