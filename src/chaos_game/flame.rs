//! Flame functions (`kind = "flame"`, flam3's xforms) in the chaos game: their xforms compiled
//! once ([`FlameTable`]), applied in f64 to the orbit's f32 point with the orbit's own generator
//! (some variations draw random numbers) by [`CompiledIfs::map_with_rng`], and each one's colour
//! speed for the colour coordinate.
//!
//! flam3's rule for a point that leaves the plane (NaN, or a coordinate beyond ±10¹⁰) is kept:
//! the orbit is re-seeded at a random point of [−1, 1]², and that step is not drawn (its emitted
//! point is NaN, which the splat skips), as flam3 retries such a step without plotting it.
//!
//! An xform's `opacity` (its plotted weight w = 10^(log₂ opacity), flam3's) draws each of its
//! points with chance w, one more random draw after the xform where w < 1: flam3 adds the point
//! with weight w, which the sums of the accumulating modes get on average; opacity 0 hides the
//! function's points (the orbit still goes through it).
//!
//! A final xform (flam3's `<finalxform>`, the scene's `[final]`) maps the point that is drawn,
//! not the orbit: each step's drawn point is its image (a point it sends out of the plane is
//! drawn at a random point of [−1, 1]², as flam3 does), drawn with the colour coordinate
//! s_f·c_f + (1 − s_f)·c, while the orbit goes on from the point before it with c. With an
//! opacity o_f below 1 the final xform maps a drawn point with chance o_f (one more draw before
//! its own, flam3's raw opacity); a point it leaves is drawn as it is, with c. The colour sink
//! learns which from [`FINAL_LEFT_OUT`] in the point's function index.
//!
//! An IFS with a flame function runs on the general path (the lane and vector kernels take only
//! multilinear and affine maps), a step of all a chunk's orbits at a time
//! ([`CompiledIfs::map_flame_row`]): the orbits are grouped by the function they drew and a flame
//! function maps its group as one batch (`CompiledXform::apply_batch`, the direct renderer's
//! vector path), each orbit drawing its numbers in the order [`CompiledIfs::map_with_rng`]
//! draws them, so the points are the same bits; its other functions are mapped as always. The
//! kernel table holds, for a flame function, its pre-affine as one affine cell, so that the
//! tables stay well formed for every consumer.
//!
//! The GPU twin is the flame branch of `shaders/chaos_game.wgsl` with the xforms of
//! `shaders/variations.wgsl`: the same selection, the xform in f32 from the table
//! [`CompiledIfs::flame_ops`] (the constants prepared here in f64), the same re-seed and colour
//! speeds, and the same random draws in the same order (`flame_random` truncates each f64 draw
//! to 24 bits). `tests/gpu_flames.rs` checks the two step by step and as densities.

use glam::{Vec3, Vec3A};

use super::color_coord::{FINAL_LEFT_OUT, final_flag_fits};
use super::{CompiledIfs, ORBITS_PER_CHUNK};
use crate::flame::Xform;
use crate::flame::variations::{BatchScratch, ChainNumber, CompiledXform, FLAME_OP_NONE, FlameOp};
use crate::rng::Pcg32;
use crate::simd::SimdLevel;

const K: usize = ORBITS_PER_CHUNK;

/// flam3's limit of a coordinate in the plane (`badvalue`).
const BAD_VALUE: f64 = 1e10;

/// The compiled IFS's flame functions, by compiled function index (None: not a flame), and its
/// final xform.
#[derive(Clone, Debug)]
pub struct FlameTable {
    xforms: Vec<Option<Xform>>,
    compiled: Vec<Option<CompiledXform>>,
    final_xform: Option<(Xform, CompiledXform)>,
    /// The final xform's chance of mapping a drawn point (1: every point; see [`FINAL_LEFT_OUT`]).
    final_opacity: f32,
}

impl PartialEq for FlameTable {
    /// The compiled forms follow from the xforms.
    fn eq(&self, other: &Self) -> bool {
        self.xforms == other.xforms
            && self.final_xform.as_ref().map(|f| &f.0) == other.final_xform.as_ref().map(|f| &f.0)
    }
}

impl FlameTable {
    /// The table of `xforms` (one entry per compiled function) and `final_xform`; None when
    /// there is neither a flame function nor a final xform.
    pub(super) fn new(xforms: Vec<Option<Xform>>, final_xform: Option<&Xform>) -> Option<Self> {
        if xforms.iter().all(Option::is_none) && final_xform.is_none() {
            return None;
        }
        let compiled = xforms.iter().map(|x| x.as_ref().map(CompiledXform::new)).collect();
        let final_xform = final_xform.map(|x| (x.clone(), CompiledXform::new(x)));
        let final_opacity = match &final_xform {
            Some((x, _)) if final_flag_fits(xforms.len()) => x.opacity.clamp(0.0, 1.0) as f32,
            _ => 1.0,
        };
        Some(Self { xforms, compiled, final_xform, final_opacity })
    }

    /// The final xform's colour coordinate c_f (clamped to [0, 1]) and colour speed s_f: the
    /// drawn point's coordinate is s_f·c_f + (1 − s_f)·c.
    pub fn final_color(&self) -> Option<(f32, f32)> {
        self.final_xform.as_ref().map(|(x, _)| (x.color.clamp(0.0, 1.0) as f32, x.color_speed as f32))
    }

    /// The colour speeds of the compiled functions: a flame's `color_speed`, ½ for the others.
    pub(super) fn color_speeds(&self) -> Vec<f32> {
        self.xforms.iter().map(|x| x.as_ref().map_or(0.5, |x| x.color_speed as f32)).collect()
    }
}

/// The work space of [`CompiledIfs::map_flame_row`], kept between steps.
pub(super) struct FlameRow {
    /// The lanes grouped by function (a counting sort of the step's functions).
    order: [ChainNumber; K],
    /// Function f's lanes are `order[starts[f]..starts[f + 1]]`.
    starts: Vec<ChainNumber>,
    /// Whether lane k's step draws a point (not a flame function's re-seed or a point its
    /// opacity hides), which the final xform then maps.
    drawn: [bool; K],
    /// The group being mapped, in f64.
    x: [f64; K],
    y: [f64; K],
    scratch: Box<BatchScratch>,
}

impl FlameRow {
    pub(super) fn new(ifs: &CompiledIfs) -> Self {
        Self {
            order: [0; K],
            starts: vec![0; ifs.functions.len() + 1],
            drawn: [true; K],
            x: [0.0; K],
            y: [0.0; K],
            scratch: Box::default(),
        }
    }
}

/// The final xform's image of a drawn point `p` (z unchanged); a point it sends out of the
/// plane is drawn at a random point of [−1, 1]² instead (flam3's rule for the final xform).
#[inline(always)]
fn apply_final(f: &CompiledXform, p: Vec3, rng: &mut Pcg32) -> Vec3 {
    final_point(f.apply([p.x as f64, p.y as f64], rng), p.z, rng)
}

/// flam3's re-seed: a random point of [−1, 1]² (x drawn first), at depth `z`.
#[inline(always)]
fn reseeded(z: f32, rng: &mut Pcg32) -> Vec3 {
    let x = (rng.next_f64() * 2.0 - 1.0) as f32;
    Vec3::new(x, (rng.next_f64() * 2.0 - 1.0) as f32, z)
}

/// The point drawn for the final xform's image `q` of a point at depth `z`.
#[inline(always)]
fn final_point(q: [f64; 2], z: f32, rng: &mut Pcg32) -> Vec3 {
    if is_bad(q) {
        return reseeded(z, rng);
    }
    Vec3::new(q[0] as f32, q[1] as f32, z)
}

/// A draw in [0, 1) of 24 bits, as the GPU's `flame_random` reads one f64 draw (the same two
/// words of the stream, the top 24 bits of the first).
#[inline(always)]
fn random_24_bits(rng: &mut Pcg32) -> f32 {
    (rng.next_f64() * 16_777_216.0).floor() as f32 * (1.0 / 16_777_216.0)
}

/// Whether the final xform of opacity `opacity` maps this drawn point: always at 1, else a draw
/// (the GPU's `final_applies`).
#[inline(always)]
fn final_applies(opacity: f32, rng: &mut Pcg32) -> bool {
    opacity >= 1.0 || random_24_bits(rng) < opacity
}

#[inline(always)]
fn is_bad(v: [f64; 2]) -> bool {
    !(v[0].abs() <= BAD_VALUE && v[1].abs() <= BAD_VALUE)
}

impl CompiledIfs {
    /// Whether a function of this IFS is a flame.
    pub fn has_flames(&self) -> bool {
        self.flames.is_some()
    }

    /// The bit a drawn point that the final xform left carries in its function index:
    /// [`FINAL_LEFT_OUT`] where the colour is the palette's, else none.
    #[inline(always)]
    pub(super) fn final_left_out_bit(&self) -> u8 {
        if self.color_coords.is_some() { FINAL_LEFT_OUT } else { 0 }
    }

    /// Maps `p` by compiled function `fi` with the orbit's generator `rng`: returns the orbit's
    /// next point and the point to draw. For a flame function the xform (z unchanged), with
    /// flam3's re-seed of a point that leaves the plane (drawn as NaN, skipped), and, where its
    /// plotted weight w is below 1 (`opacity`), one more draw that keeps the point with chance w
    /// (else drawn as NaN): flam3 weighs the point by w, which the sums of the accumulating
    /// modes get on average. Any other function as [`Self::map_fast`], both points the same.
    ///
    /// With a final xform the point to draw is, where it is drawn at all, its image
    /// (`apply_final`), or with an opacity below 1 and its draw against, the point itself.
    #[inline(always)]
    pub fn map_with_rng(&self, fi: usize, p: Vec3, rng: &mut Pcg32) -> (Vec3, Vec3) {
        let (next, shown, _) = self.map_with_rng_final(fi, p, rng);
        (next, shown)
    }

    /// [`Self::map_with_rng`], and whether the final xform left the drawn point as it was (its
    /// opacity's draw; false where there is no final xform or the point is not drawn).
    #[inline(always)]
    pub(super) fn map_with_rng_final(&self, fi: usize, p: Vec3, rng: &mut Pcg32) -> (Vec3, Vec3, bool) {
        let Some(table) = &self.flames else {
            let q = self.map_fast(fi, p);
            return (q, q, false);
        };
        let (next, shown) = match &table.compiled[fi] {
            Some(x) => {
                let q = x.apply([p.x as f64, p.y as f64], rng);
                if is_bad(q) {
                    let next = reseeded(p.z, rng);
                    return (next, Vec3::NAN, false);
                }
                let q = Vec3::new(q[0] as f32, q[1] as f32, p.z);
                let weight = x.plotted_weight() as f32;
                if weight < 1.0 && !(random_24_bits(rng) < weight) {
                    return (q, Vec3::NAN, false);
                }
                (q, q)
            }
            None => {
                let q = self.map_fast(fi, p);
                (q, q)
            }
        };
        match &table.final_xform {
            Some((_, f)) if final_applies(table.final_opacity, rng) => (next, apply_final(f, shown, rng), false),
            Some(_) => (next, shown, true),
            None => (next, shown, false),
        }
    }

    /// [`Self::map_flame_row`] compiled for AVX-512 or AVX2 where `level` says the CPU has it
    /// (no FMA: the same bits); one copy of each, whatever the caller.
    #[inline(never)]
    pub(super) fn map_flame_row_on(
        &self,
        level: SimdLevel,
        fis: &mut [u8; K],
        rngs: &mut [Pcg32; K],
        pos: &mut [Vec3A; K],
        shown: &mut [Vec3A; K],
        w: &mut FlameRow,
    ) {
        #[cfg(target_arch = "x86_64")]
        match level {
            #[expect(unsafe_code, reason = "an AVX-512 function, entered after the CPU check")]
            // SAFETY: the CPU runs AVX-512F (`level` is `SimdLevel::detect`'s).
            SimdLevel::Avx512 => unsafe { return self.map_flame_row_avx512(fis, rngs, pos, shown, w) },
            #[expect(unsafe_code, reason = "an AVX2 function, entered after the CPU check")]
            // SAFETY: the CPU runs AVX2 (`level` is `SimdLevel::detect`'s).
            SimdLevel::Avx2 => unsafe { return self.map_flame_row_avx2(fis, rngs, pos, shown, w) },
            SimdLevel::Scalar => {}
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = level;
        self.map_flame_row(fis, rngs, pos, shown, w)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f")]
    fn map_flame_row_avx512(
        &self,
        fis: &mut [u8; K],
        rngs: &mut [Pcg32; K],
        pos: &mut [Vec3A; K],
        shown: &mut [Vec3A; K],
        w: &mut FlameRow,
    ) {
        self.map_flame_row(fis, rngs, pos, shown, w)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn map_flame_row_avx2(
        &self,
        fis: &mut [u8; K],
        rngs: &mut [Pcg32; K],
        pos: &mut [Vec3A; K],
        shown: &mut [Vec3A; K],
        w: &mut FlameRow,
    ) {
        self.map_flame_row(fis, rngs, pos, shown, w)
    }

    /// One step of every orbit of a chunk, lane k by compiled function `fis[k]`: its next point
    /// into `pos[k]` and the point to draw into `shown[k]`, the points and draws of
    /// [`Self::map_with_rng`] lane by lane. The lanes of a flame function are mapped as one
    /// batch where its variations batch (`CompiledXform::batches`), as are the final xform's
    /// drawn points; every lane draws its numbers in `map_with_rng`'s order. A lane whose drawn
    /// point the final xform left (its opacity) gets [`FINAL_LEFT_OUT`] in `fis[k]` where the
    /// colour is the palette's.
    #[inline(always)]
    pub(super) fn map_flame_row(
        &self,
        fis: &mut [u8; K],
        rngs: &mut [Pcg32; K],
        pos: &mut [Vec3A; K],
        shown: &mut [Vec3A; K],
        w: &mut FlameRow,
    ) {
        let Some(table) = &self.flames else {
            for k in 0..K {
                let q = self.map_fast(fis[k] as usize, pos[k].into());
                (pos[k], shown[k]) = (q.into(), q.into());
            }
            return;
        };
        // The counting sort: starts[f + 1] counts f's lanes, then holds where they end.
        let n = table.compiled.len();
        let starts = &mut w.starts[..=n];
        starts.fill(0);
        for &f in fis.iter() {
            starts[f as usize + 1] += 1;
        }
        for f in 0..n {
            starts[f + 1] += starts[f];
        }
        for (k, &f) in fis.iter().enumerate() {
            let slot = &mut starts[f as usize];
            w.order[*slot as usize] = k as ChainNumber;
            *slot += 1;
        }
        // starts[f] now holds where f's lanes end, the start of f + 1's.
        let mut first = 0;
        for (fi, compiled) in table.compiled.iter().enumerate() {
            let end = w.starts[fi] as usize;
            let group = &w.order[first..end];
            first = end;
            if group.is_empty() {
                continue;
            }
            let Some(x) = compiled else {
                for &k in group {
                    let q = self.map_fast(fi, pos[k as usize].into());
                    (pos[k as usize], shown[k as usize]) = (q.into(), q.into());
                    w.drawn[k as usize] = true;
                }
                continue;
            };
            let m = group.len();
            for (j, &k) in group.iter().enumerate() {
                (w.x[j], w.y[j]) = (f64::from(pos[k as usize].x), f64::from(pos[k as usize].y));
            }
            if x.batches() {
                x.apply_batch(&mut w.x[..m], &mut w.y[..m], group, rngs, &mut w.scratch);
            } else {
                x.apply_each(&mut w.x[..m], &mut w.y[..m], group, rngs);
            }
            let weight = x.plotted_weight() as f32;
            for (j, &k) in group.iter().enumerate() {
                let (k, q) = (k as usize, [w.x[j], w.y[j]]);
                let (rng, z) = (&mut rngs[k], pos[k].z);
                if is_bad(q) {
                    pos[k] = reseeded(z, rng).into();
                    (shown[k], w.drawn[k]) = (Vec3A::NAN, false);
                    continue;
                }
                let q = Vec3A::new(q[0] as f32, q[1] as f32, z);
                pos[k] = q;
                w.drawn[k] = weight >= 1.0 || random_24_bits(rng) < weight;
                shown[k] = if w.drawn[k] { q } else { Vec3A::NAN };
            }
        }
        if let Some((_, f)) = &table.final_xform {
            // The drawn points as one batch; a NaN point (a grid function's) on its own, so that
            // the batch is not redone with the exact functions for its sake. First each drawn
            // point's opacity draw; a point the final xform leaves is flagged for the colour.
            let flag = self.final_left_out_bit();
            let mut m = 0;
            for k in (0..K).filter(|&k| w.drawn[k]) {
                if !final_applies(table.final_opacity, &mut rngs[k]) {
                    fis[k] |= flag;
                } else if shown[k].is_nan() {
                    shown[k] = apply_final(f, shown[k].into(), &mut rngs[k]).into();
                } else {
                    (w.order[m], w.x[m], w.y[m]) = (k as ChainNumber, f64::from(shown[k].x), f64::from(shown[k].y));
                    m += 1;
                }
            }
            if f.batches() {
                f.apply_batch(&mut w.x[..m], &mut w.y[..m], &w.order[..m], rngs, &mut w.scratch);
            } else {
                f.apply_each(&mut w.x[..m], &mut w.y[..m], &w.order[..m], rngs);
            }
            for j in 0..m {
                let (k, q) = (w.order[j] as usize, [w.x[j], w.y[j]]);
                shown[k] = final_point(q, shown[k].z, &mut rngs[k]).into();
            }
        }
    }

    /// The GPU's flame table (`shaders/variations.wgsl`): one header per compiled function
    /// (its xform's for a flame function, else [`FLAME_OP_NONE`] with colour speed ½), the
    /// final xform's header where there is one (its colour coordinate c_f in place of the
    /// plotted weight, `k1.w`) and a [`FLAME_OP_NONE`] record of its opacity (`weight`), then
    /// the terms and post-affines ([`CompiledXform::gpu_ops`]).
    pub fn flame_ops(&self) -> Vec<FlameOp> {
        let n = self.functions.len();
        let none =
            FlameOp { kind: FLAME_OP_NONE, weight: 0.0, first: 0, count: 0, k: [[0.0; 4], [0.0, 0.0, 0.5, 1.0]] };
        let mut headers = vec![none; n];
        let mut records = Vec::new();
        if let Some(table) = &self.flames {
            let first = n + 2 * usize::from(table.final_xform.is_some());
            for (header, x) in headers.iter_mut().zip(&table.compiled) {
                if let Some(x) = x {
                    let (h, ops) = x.gpu_ops((first + records.len()) as u32);
                    *header = h;
                    records.extend(ops);
                }
            }
            if let (Some((_, f)), Some((c_f, _))) = (&table.final_xform, table.final_color()) {
                let (mut h, ops) = f.gpu_ops((first + records.len()) as u32);
                h.k[1][3] = c_f;
                headers.push(h);
                headers.push(FlameOp { weight: table.final_opacity, ..none });
                records.extend(ops);
            }
        }
        headers.extend(records);
        headers
    }

    /// Whether the IFS has a final xform (its header follows the functions' in
    /// [`Self::flame_ops`]).
    pub fn has_final_xform(&self) -> bool {
        self.flames.as_ref().is_some_and(|t| t.final_xform.is_some())
    }

    /// One step of an orbit's colour coordinate after compiled function `fi`:
    /// s·c_i + (1 − s)·c with the function's colour speed s (flames), else (c + c_i) / 2.
    #[inline(always)]
    pub(super) fn step_color_of(&self, c: f32, fi: usize, coords: &[f32]) -> f32 {
        match &self.color_speeds {
            Some(s) => super::color_coord::step_color_speed(c, coords[fi], s[fi]),
            None => super::step_color(c, coords[fi]),
        }
    }
}
