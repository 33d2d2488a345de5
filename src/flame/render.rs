//! A flame rendered as flam3 renders it (its `rect.c`): the chaos game into a supersampled
//! histogram, then density estimation, the spatial filter and the log-density tone map
//! (`render_density.rs`, `render_filter.rs`, `render_tone.rs`; the histogram's geometry in
//! `render_layout.rs`, the camera in `render_camera.rs`, the workers' state in
//! `render_chains.rs`, what the stages share in `render_base.rs`).
//!
//! The chaos game keeps flam3's semantics so that the pictures agree: the next xform is drawn
//! from a table of 16384 entries built from the weights (one row per previous xform when the
//! flame has xaos); each run of 10 000 samples starts from a random point in [−1, 1]² and drops
//! its first 15 iterations; a point that leaves the plane (NaN or |v| > 1e10) is re-seeded at
//! random and its step retried up to four times; the final xform maps a plotted copy while the
//! orbit goes on from the point before it; an xform's `opacity` weighs its points by
//! 10^(log₂ opacity) as flam3's does. The histogram holds flam3's integer buckets (palette
//! colour × 255 × weight, rounded down, and 255 × weight for the count), so the sum over
//! chains is exact and the picture is the same bytes for a seed whatever the thread count:
//! run `k` draws from `Pcg32::for_stream(seed, 0, k)`, and threads take runs in any order.
//!
//! A worker advances 256 runs together (its chains), one iteration of each per round: one run's
//! iterations depend on each other, the chains' do not, so the core overlaps their work. In a
//! round the chains are grouped by the xform they drew (`Round::group`), and an xform whose
//! variations all batch (the arithmetic and the smooth ones) maps its group as one batch in
//! vector registers (the vector path, `CompiledXform::apply_batch`); each sample's bucket is
//! prefetched when it is computed and added 16 samples later, when it is in cache. Each chain draws its random numbers in flam3's
//! order and goes through the same operations, so the sums, and the picture, are the same bits
//! as one run after another.
//!
//! That is the f64 chaos game. A flame whose view f32 resolves and whose palette is opaque runs
//! instead in f32 lanes (`render_lanes.rs`, every variation): the same flame and the same
//! picture within flam3's own noise, not the same bytes, many times faster.
//! `NLIFS_FLAME_F64=1` keeps every flame on the f64 game, and `NLIFS_FLAME_QUEUES=1` keeps the
//! lane game on its queues where the xforms share their terms (`render_lanes_shared.rs`).

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

pub use super::render_base::RenderError;
use super::render_base::{Bucket, WHITE_LEVEL, whole_u32};
use super::render_camera::Camera;
pub use super::render_chains::FUSE_ITERATIONS;
use super::render_chains::{CHAINS, Chains, Round};
use super::render_layout::Layout;
use super::variations::{BatchScratch, ChainNumber, CompiledXform};
use super::{Flame, PaletteMode, Xform};
use crate::rng::Pcg32;

/// Samples of one run of the chaos game (flam3's `sub_batch_size`).
pub const RUN_SAMPLES: u64 = 10_000;
/// Entries of the xform choice table (flam3's `CHOOSE_XFORM_GRAIN`).
const CHOICE_ENTRIES: usize = 16_384;
/// Samples between a bucket's prefetch and its add: enough for the line to arrive, few enough
/// that the prefetches do not queue up.
const IN_FLIGHT: usize = 16;

/// An 8-bit RGBA picture, rows top to bottom (flam3-render's PNG: alpha 255, the background
/// composited).
#[derive(Clone, Debug, PartialEq)]
pub struct FlameImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// Samples plotted or thrown (after the fuse), as flam3 counts them.
    pub samples: u64,
    /// Points re-seeded because an xform sent them out of the plane.
    pub bad_values: u64,
}

/// The samples flam3 draws for a flame: quality × 4^zoom × width × height.
pub fn sample_count(flame: &Flame) -> u64 {
    let density = flame.quality * 4f64.powf(flame.zoom);
    (density * f64::from(flame.size[0]) * f64::from(flame.size[1])).max(0.0) as u64
}

/// Renders `flame` with the chaos game seeded by `seed` on rayon's current pool;
/// `progress(samples)` is called as runs finish, from any thread.
pub fn render(flame: &Flame, seed: u32, progress: &(dyn Fn(u64) + Sync)) -> Result<FlameImage, RenderError> {
    let layout = Layout::new(flame)?;
    let game = ChaosGame::new(flame, &layout)?;
    let samples = sample_count(flame);
    let (histogram, bad_values) = game.run(seed, samples, &layout, progress);
    // The accumulation buffer's rows made into pixels as they become final.
    let mut tone_map = super::render_tone::ToneMap::new(flame, &layout);
    let take = &mut |rows: &super::render_density::AccRows<'_>| tone_map.take(rows);
    match &histogram {
        Histogram::Buckets(buckets) => super::render_density::accumulate(flame, &layout, buckets, take)?,
        Histogram::Cells(cells) => super::render_density::accumulate(flame, &layout, cells, take)?,
    }
    drop(histogram);
    let rgba = tone_map.finish();
    Ok(FlameImage { width: flame.size[0], height: flame.size[1], rgba, samples, bad_values })
}

/// Whether `flame`'s chaos game runs in f32 lanes (`render_lanes.rs`): see [`lanes_refusal`].
pub fn runs_in_lanes(flame: &Flame) -> bool {
    lanes_refusal(flame).is_none()
}

/// Why `flame`'s chaos game does not run in f32 lanes (`render_lanes.rs`) but in the f64 game,
/// in a user's words; `None` where it runs in lanes. Every variation runs in lanes; a flame does
/// not where it has more than 64 xforms, a view f32 does not resolve, a palette entry that is
/// not opaque, or `NLIFS_FLAME_F64` is set.
pub fn lanes_refusal(flame: &Flame) -> Option<String> {
    if f64_only() {
        return Some("NLIFS_FLAME_F64 is set".into());
    }
    let game = Layout::new(flame).and_then(|layout| ChaosGame::new(flame, &layout));
    match game {
        Ok(game) => lanes::LaneGame::new(&game).err().map(str::to_string),
        Err(e) => Some(e.to_string()),
    }
}

/// A worker's entry, `$dispatch(&self, seed, samples, next, histogram: &mut [$cell], progress) -> u64`, that
/// runs `$worker` (the same arguments and `wide`: whether the CPU runs AVX-512F) compiled for
/// AVX-512 (`$avx512`: F, VL, DQ and BW, for the 128- and 256-bit forms of the cell adds and
/// lane tests) or AVX2 (`$avx2`) where the CPU has it, else as it is: the f64 and the lane
/// chaos games' one dispatch. `$worker` is `#[inline(always)]`, so each build is its own vector
/// code.
macro_rules! vector_builds {
    ($(#[$doc:meta])* $vis:vis fn $dispatch:ident($cell:ty) => $worker:ident, $avx512:ident, $avx2:ident) => {
        $(#[$doc])*
        $vis fn $dispatch(
            &self,
            seed: u32,
            samples: u64,
            next: &AtomicU64,
            histogram: &mut [$cell],
            progress: &(dyn Fn(u64) + Sync),
        ) -> u64 {
            #[cfg(target_arch = "x86_64")]
            {
                use crate::simd::SimdLevel;
                match SimdLevel::detect() {
                    #[expect(unsafe_code, reason = "an AVX-512 function, entered after the CPU check")]
                    // SAFETY: the CPU runs AVX-512 F, VL, DQ and BW, and POPCNT (detected).
                    SimdLevel::Avx512 => unsafe {
                        return self.$avx512(seed, samples, next, histogram, progress);
                    },
                    #[expect(unsafe_code, reason = "an AVX2 function, entered after the CPU check")]
                    // SAFETY: the CPU runs AVX2 and POPCNT (detected).
                    SimdLevel::Avx2 => unsafe {
                        return self.$avx2(seed, samples, next, histogram, progress);
                    },
                    SimdLevel::Scalar => {}
                }
            }
            self.$worker(seed, samples, next, histogram, progress, false)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,avx512f,avx512vl,avx512dq,avx512bw,popcnt")]
        fn $avx512(
            &self,
            seed: u32,
            samples: u64,
            next: &AtomicU64,
            histogram: &mut [$cell],
            progress: &(dyn Fn(u64) + Sync),
        ) -> u64 {
            self.$worker(seed, samples, next, histogram, progress, true)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,popcnt")]
        fn $avx2(
            &self,
            seed: u32,
            samples: u64,
            next: &AtomicU64,
            histogram: &mut [$cell],
            progress: &(dyn Fn(u64) + Sync),
        ) -> u64 {
            self.$worker(seed, samples, next, histogram, progress, false)
        }
    };
}

/// An xform as the chaos game uses it.
struct GameXform {
    map: CompiledXform,
    /// The colour update c' = s · colour + (1 − s) · c (s the colour speed) as
    /// `color_held + color_kept · c`, its two products' first computed once.
    color_held: f64,
    color_kept: f64,
    /// flam3's `vis_adjusted`: the weight of its points in the histogram.
    plotted_weight: f64,
    /// The final xform's chance of being applied (its raw opacity).
    opacity: f64,
}

impl GameXform {
    fn new(x: &Xform) -> Self {
        let plotted_weight = x.plotted_weight();
        Self {
            map: CompiledXform::new(x),
            color_held: x.color_speed * x.color,
            color_kept: 1.0 - x.color_speed,
            plotted_weight,
            opacity: x.opacity,
        }
    }

    /// The colour coordinate after this xform, from `c` before it.
    #[inline(always)]
    fn color_of(&self, c: f64) -> f64 {
        self.color_held + self.color_kept * c
    }
}

/// The chaos game of one flame: its xforms, choice tables, camera and palette.
struct ChaosGame {
    xforms: Vec<GameXform>,
    final_xform: Option<GameXform>,
    /// Row 0: by weight; row i + 1 (with xaos): after xform i.
    choice: Vec<u16>,
    xaos: bool,
    camera: Camera,
    palette_mode: PaletteMode,
    /// The palette × 255 (flam3's `dmap`).
    dmap: Vec<[f64; 4]>,
    /// The buckets' increments of a point of weight 1 at each palette entry (step mode).
    step_increments: Vec<Bucket>,
}

impl ChaosGame {
    fn new(flame: &Flame, layout: &Layout) -> Result<Self, RenderError> {
        for (index, x) in flame.xforms.iter().enumerate() {
            if x.weight < 0.0 || x.weight.is_nan() {
                return Err(RenderError::NegativeWeight { index, weight: x.weight });
            }
        }
        let weights: Vec<f64> = flame.xforms.iter().map(|x| x.weight).collect();
        let first = choice_row(&weights).ok_or_else(|| RenderError::Empty(flame.name.clone()))?;
        let n = flame.xforms.len();
        let chaos = |i: usize, j: usize| flame.xforms[i].chaos.get(j).copied().unwrap_or(1.0);
        let xaos = (0..n).any(|i| (0..n).any(|j| (chaos(i, j) - 1.0).abs() > 1e-10));
        let mut choice = first;
        if xaos {
            for i in 0..n {
                let row_weights: Vec<f64> = (0..n).map(|j| weights[j] * chaos(i, j).max(0.0)).collect();
                // A row with nothing to go to: flam3 refuses the flame; this falls back to the
                // weights, so that such an xform behaves as without xaos.
                let row = choice_row(&row_weights).unwrap_or_else(|| choice[..CHOICE_ENTRIES].to_vec());
                choice.extend_from_slice(&row);
            }
        }
        let dmap: Vec<[f64; 4]> = flame.palette.iter().map(|c| c.map(|v| v * WHITE_LEVEL)).collect();
        let step_increments = dmap.iter().map(|c| increments(*c, 1.0)).collect();
        Ok(Self {
            xforms: flame.xforms.iter().map(GameXform::new).collect(),
            final_xform: flame.final_xform.as_ref().map(GameXform::new),
            choice,
            xaos,
            camera: Camera::new(flame, layout),
            palette_mode: flame.palette_mode,
            dmap,
            step_increments,
        })
    }

    /// All runs of `samples`, on rayon's pool: the summed histogram and the re-seeds. In f32 lanes
    /// where the lane game takes the flame, else in f64 ([`Self::run_f64`]).
    fn run(&self, seed: u32, samples: u64, layout: &Layout, progress: &(dyn Fn(u64) + Sync)) -> (Histogram, u64) {
        let Some(lanes) = (if f64_only() { None } else { lanes::LaneGame::new(self).ok() }) else {
            return self.run_f64(seed, samples, layout, progress);
        };
        let next_block = AtomicU64::new(0);
        let cells = layout.hist_width * layout.hist_height;
        let workers = workers_for(samples.div_ceil(lanes::BLOCK_SAMPLES));
        let parts: Vec<_> =
            (0..workers).into_par_iter().map(|_| lanes.run_part(seed, samples, &next_block, cells, progress)).collect();
        let (cells, bad) = sum_parts(cells, parts, lanes::Cell::add_saturating);
        (Histogram::Cells(cells), bad)
    }

    /// [`Self::run`] by the f64 chaos game, whatever the flame: chains that draw as flam3's do.
    fn run_f64(&self, seed: u32, samples: u64, layout: &Layout, progress: &(dyn Fn(u64) + Sync)) -> (Histogram, u64) {
        let next_run = AtomicU64::new(0);
        let cells = layout.hist_width * layout.hist_height;
        let parts: Vec<(Vec<Bucket>, u64)> = (0..workers_for(samples.div_ceil(RUN_SAMPLES)))
            .into_par_iter()
            .map(|_| {
                // Every page written (several workers update theirs at random).
                let mut histogram = crate::platform::zeroed_pages::<Bucket>(cells);
                let bad = self.run_chains_dispatch(seed, samples, &next_run, &mut histogram, progress);
                (histogram, bad)
            })
            .collect();
        let (buckets, bad) = sum_parts(cells, parts, add);
        (Histogram::Buckets(buckets), bad)
    }

    /// The next run not yet taken, if any: its generator, starting point and colour, and its
    /// sample count.
    fn start_run(&self, seed: u32, samples: u64, next_run: &AtomicU64) -> Option<(Pcg32, [f64; 2], f64, i64)> {
        let runs = samples.div_ceil(RUN_SAMPLES);
        let run = next_run.fetch_add(1, Ordering::Relaxed);
        if run >= runs {
            return None;
        }
        let mut rng = Pcg32::for_stream(seed, 0, run as u32);
        let p = [uniform11(&mut rng), uniform11(&mut rng)];
        let color = rng.next_f64();
        let n = RUN_SAMPLES.min(samples - run * RUN_SAMPLES);
        Some((rng, p, color, n as i64))
    }

    vector_builds! {
        /// [`Self::run_chains`] compiled for AVX-512 or AVX2 when the CPU has it (no FMA: the same
        /// bits).
        fn run_chains_dispatch(Bucket) => run_chains, run_chains_avx512, run_chains_avx2
    }

    /// One worker: [`CHAINS`] runs advanced together, each taking the next run when its own is
    /// done, until no run is left. Returns the re-seeds.
    ///
    /// A round is one iteration of every chain, in phases, each a loop over the chains (the
    /// draws, the settling and the buckets vector loops): each chain draws its xform; the chains are grouped by xform and each group mapped by
    /// [`CompiledXform::apply_batch`] (the vector path); the re-seeds (chain by chain only in a
    /// round that has one) and the final xform's draw; the final xform's points as one batch;
    /// the buckets; and the adds, whose buckets are prefetched [`IN_FLIGHT`] samples ahead.
    /// Each chain draws the same numbers in the same order as flam3's loop does, so the sums
    /// are those of one run after another.
    #[inline(always)]
    fn run_chains(
        &self,
        seed: u32,
        samples: u64,
        next_run: &AtomicU64,
        histogram: &mut [Bucket],
        progress: &(dyn Fn(u64) + Sync),
        wide: bool,
    ) -> u64 {
        let mut c = Chains::new();
        let mut r = Round::new(self.xforms.len());
        let mut bad = 0;
        let mut scratch = BatchScratch::default();
        // The last IN_FLIGHT samples' buckets (prefetched) and increments, not yet added.
        let mut in_flight = [EMPTY_SLOT; IN_FLIGHT];
        let mut next_in_flight = 0;
        loop {
            // The previous round's adds; finished runs hand their chain to the next run, or
            // the last live chain moves into their place.
            for k in (0..c.live).rev() {
                if c.i[k] >= c.n[k] {
                    if c.n[k] > 0 {
                        progress(c.n[k] as u64);
                    }
                    match self.start_run(seed, samples, next_run) {
                        Some(run) => c.start(k, run),
                        None => {
                            c.live -= 1;
                            c.move_chain(c.live, k);
                        }
                    }
                }
            }
            // (At most CHAINS, which the compiler then knows: no bounds checks in the loops.)
            let live = c.live.min(CHAINS);
            if live == 0 {
                for (b, inc) in &in_flight {
                    add(&mut histogram[*b], inc);
                }
                return bad;
            }
            self.choose(&mut c, &mut r, wide);
            // Each group mapped by its xform.
            for &x in &r.drawn {
                let (start, m) = (r.start[x] as usize, r.count[x] as usize);
                let members = &r.order[start..start + m];
                let xf = &self.xforms[x];
                for (j, &k) in members.iter().enumerate() {
                    (r.gx[j], r.gy[j]) = (c.x[k as usize], c.y[k as usize]);
                }
                if xf.map.batches() {
                    xf.map.apply_batch(&mut r.gx[..m], &mut r.gy[..m], members, &mut c.rng, &mut scratch);
                } else {
                    xf.map.apply_each(&mut r.gx[..m], &mut r.gy[..m], members, &mut c.rng);
                }
                for (j, &k) in members.iter().enumerate() {
                    (c.x[k as usize], c.y[k as usize]) = (r.gx[j], r.gy[j]);
                }
                r.count[x] = 0;
            }
            bad += self.settle(&mut c, &mut r);
            if let Some(f) = &self.final_xform {
                self.apply_final(f, &mut c, &mut r, &mut scratch);
            }
            self.find_buckets(&mut c, &mut r);
            // The adds, each bucket prefetched IN_FLIGHT samples before its add; a sample that
            // adds nothing adds 0 to bucket 0.
            for k in 0..live {
                let b = r.bucket[k] as usize;
                prefetch(&histogram[b]);
                // Whether it adds is as good as random: a mask, not a branch.
                let weight = r.weight[k];
                let mask = 0u32.wrapping_sub(u32::from(r.adds[k]));
                let inc = if self.palette_mode == PaletteMode::Step && weight == 1.0 {
                    self.step_increments[r.step_entry[k] as usize]
                } else {
                    self.increments_of(r.shown_color[k], weight)
                }
                .map(|v| v & mask);
                let (earlier, earlier_inc) = std::mem::replace(&mut in_flight[next_in_flight], (b, inc));
                add(&mut histogram[earlier], &earlier_inc);
                next_in_flight = (next_in_flight + 1) % IN_FLIGHT;
            }
        }
    }

    /// Each live chain's xform (its draw from its generator, a vector loop, then the choice
    /// table), the chains grouped by xform ([`Round::group`]), and each chain's next colour and
    /// plotted weight (a vector loop over the xforms' constants).
    #[inline(always)]
    fn choose(&self, c: &mut Chains, r: &mut Round, wide: bool) {
        // (At most CHAINS, which the compiler then knows: no bounds checks in the loops.)
        let live = c.live.min(CHAINS);
        for (entry, rng) in r.entry[..live].iter_mut().zip(&mut c.rng[..live]) {
            *entry = rng.next_u32() & (CHOICE_ENTRIES as u32 - 1);
        }
        for k in 0..live {
            let row = if self.xaos { c.last[k] } else { 0 };
            r.chosen[k] = u32::from(self.choice[row * CHOICE_ENTRIES + r.entry[k] as usize]);
        }
        r.group(live, self.xforms.len(), wide);
        let n = self.xforms.len();
        for k in 0..live {
            // (Below n by the choice table; the min spares the bounds check a branch.)
            let xf = &self.xforms[(r.chosen[k] as usize).min(n - 1)];
            r.next_color[k] = xf.color_of(c.color[k]);
            r.weight[k] = xf.plotted_weight;
        }
    }

    /// The chains' mapped points (the groups' batches wrote them into the chains) re-seeded
    /// where they left the plane (a retried step plots nothing), the chains' colours, and what
    /// each shows before the final xform. Returns the re-seeds. Chain by chain only in a round
    /// with a point out of the plane; otherwise vector loops. (A chain goes on from its mapped
    /// or re-seeded point whether its step plots or not, so the mapped point needs no copy.)
    #[inline(always)]
    fn settle(&self, c: &mut Chains, r: &mut Round) -> u64 {
        // (At most CHAINS, which the compiler then knows: no bounds checks in the loops.)
        let live = c.live.min(CHAINS);
        let any_bad = c.x[..live].iter().zip(&c.y[..live]).fold(false, |any, (&x, &y)| any | is_bad([x, y]));
        let mut bad = 0;
        if any_bad {
            for k in 0..live {
                r.plot[k] = false;
                if is_bad([c.x[k], c.y[k]]) {
                    [c.x[k], c.y[k]] = [uniform11(&mut c.rng[k]), uniform11(&mut c.rng[k])];
                    bad += 1;
                    c.consecutive_bad[k] += 1;
                    if c.consecutive_bad[k] < 5 {
                        continue;
                    }
                }
                c.consecutive_bad[k] = 0;
                c.last[k] = r.chosen[k] as usize + 1;
                r.plot[k] = true;
            }
        } else {
            c.consecutive_bad[..live].fill(0);
            r.plot[..live].fill(true);
            for (last, &chosen) in c.last[..live].iter_mut().zip(&r.chosen[..live]) {
                *last = chosen as usize + 1;
            }
        }
        c.color[..live].copy_from_slice(&r.next_color[..live]);
        r.sx[..live].copy_from_slice(&c.x[..live]);
        r.sy[..live].copy_from_slice(&c.y[..live]);
        r.shown_color[..live].copy_from_slice(&r.next_color[..live]);
        bad
    }

    /// The final xform: each plotting chain's draw, then the points of those that apply it,
    /// as one batch, into what they show (a point out of the plane shown at random).
    #[inline(always)]
    fn apply_final(&self, f: &GameXform, c: &mut Chains, r: &mut Round, scratch: &mut BatchScratch) {
        r.finals.clear();
        for k in 0..c.live {
            if r.plot[k] && (f.opacity == 1.0 || c.rng[k].next_f64() < f.opacity) {
                r.finals.push(k as ChainNumber);
            }
        }
        let m = r.finals.len();
        if m == 0 {
            return;
        }
        for (j, &k) in r.finals.iter().enumerate() {
            (r.gx[j], r.gy[j]) = (r.sx[k as usize], r.sy[k as usize]);
        }
        if f.map.batches() {
            f.map.apply_batch(&mut r.gx[..m], &mut r.gy[..m], &r.finals, &mut c.rng, scratch);
        } else {
            f.map.apply_each(&mut r.gx[..m], &mut r.gy[..m], &r.finals, &mut c.rng);
        }
        for (j, &k) in r.finals.iter().enumerate() {
            let k = k as usize;
            r.shown_color[k] = f.color_of(r.next_color[k]);
            (r.sx[k], r.sy[k]) = (r.gx[j], r.gy[j]);
            if is_bad([r.sx[k], r.sy[k]]) {
                (r.sx[k], r.sy[k]) = (uniform11(&mut c.rng[k]), uniform11(&mut c.rng[k]));
            }
        }
    }

    /// Each live chain's bucket and whether it adds to it (its step counts, it is past the
    /// fuse, its point is in view and its xform's plotted weight is not 0), a vector loop;
    /// counts the chains' steps; the step palette's entry of each.
    #[inline(always)]
    fn find_buckets(&self, c: &mut Chains, r: &mut Round) {
        // (At most CHAINS, which the compiler then knows: no bounds checks in the loops.)
        let live = c.live.min(CHAINS);
        if let Some(rotation) = &self.camera.rotation {
            for (x, y) in r.sx[..live].iter_mut().zip(&mut r.sy[..live]) {
                [*x, *y] = self.camera.rotate(rotation, [*x, *y]);
            }
        }
        for k in 0..live {
            let (b, inside) = self.camera.bucket_of_rotated([r.sx[k], r.sy[k]]);
            let adds = r.plot[k] & inside & (c.i[k] >= 0) & (r.weight[k] != 0.0);
            r.adds[k] = adds;
            r.bucket[k] = if adds { b } else { 0 };
            c.i[k] += i64::from(r.plot[k]);
            // The step palette's entry, as `increments_of` finds it (NaN converts to 0 there,
            // and `max` gives 0 here, where `clamp` would keep it).
            #[expect(clippy::manual_clamp, reason = "NaN must give 0")]
            let entry = whole_u32((r.shown_color[k] * 256.0).max(0.0).min(255.0));
            r.step_entry[k] = entry;
        }
    }

    /// The buckets' increments of a sample of palette coordinate `color` plotted with `weight`.
    #[inline(always)]
    fn increments_of(&self, color: f64, weight: f64) -> Bucket {
        let index = color * 256.0;
        match self.palette_mode {
            PaletteMode::Step => {
                let i = (index.clamp(0.0, 255.0)) as usize;
                if weight == 1.0 { self.step_increments[i] } else { increments(self.dmap[i], weight) }
            }
            PaletteMode::Linear => {
                let (i, frac) = if index < 0.0 || index.is_nan() {
                    (0, 0.0)
                } else if index >= 255.0 {
                    (254, 1.0)
                } else {
                    let i = index as usize;
                    (i, index - i as f64)
                };
                let (a, b) = (self.dmap[i], self.dmap[i + 1]);
                increments(std::array::from_fn(|c| a[c] * (1.0 - frac) + b[c] * frac), weight)
            }
        }
    }
}

/// An empty slot of the samples in flight: 0 added to bucket 0.
const EMPTY_SLOT: (usize, Bucket) = (0, [0; 5]);

/// The histogram a chaos game drew: the f64 game's buckets or the lane game's cells, each read
/// in place by the density estimate.
#[derive(Debug, PartialEq)]
enum Histogram {
    Buckets(Vec<Bucket>),
    Cells(Vec<lanes::Cell>),
}

#[cfg(test)]
impl Histogram {
    /// Every cell as a bucket.
    fn buckets(&self) -> Vec<Bucket> {
        use super::render_base::HistogramCell;
        match self {
            Self::Buckets(buckets) => buckets.clone(),
            Self::Cells(cells) => cells.iter().map(|c| c.bucket()).collect(),
        }
    }
}

/// The workers' histograms of `cells` cells of type `T` summed into the first (`add`), each
/// dropped once added; and their re-seeds. Summing in the cells' own type keeps the peak memory
/// at the workers' histograms.
fn sum_parts<T: Send + Sync + Copy + bytemuck::Zeroable>(
    cells: usize,
    parts: Vec<(Vec<T>, u64)>,
    add: impl Fn(&mut T, &T) + Sync,
) -> (Vec<T>, u64) {
    let mut parts = parts.into_iter();
    let Some((mut total, mut bad)) = parts.next() else { return (crate::platform::zeroed_pages(cells), 0) };
    for (part, part_bad) in parts {
        bad += part_bad;
        total.par_iter_mut().zip(part.par_iter()).for_each(|(t, p)| add(t, p));
    }
    (total, bad)
}

#[inline(always)]
fn add(bucket: &mut Bucket, inc: &Bucket) {
    for k in 0..5 {
        bucket[k] = bucket[k].saturating_add(inc[k]);
    }
}

/// Asks for `bucket`'s cache lines ahead of the add (a bucket of 20 bytes may span two).
#[inline(always)]
fn prefetch(bucket: &Bucket) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let first: *const i8 = bucket.as_ptr().cast();
        let last: *const i8 = bucket[4..].as_ptr().cast();
        #[expect(unsafe_code, reason = "a prefetch is a hint: it reads nothing and cannot fault")]
        // SAFETY: both pointers are into `bucket`, a live reference; prefetching never
        // dereferences them.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(first);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = bucket;
}

/// flam3's integer bucket increments of a colour (× 255) at a plotted weight.
#[inline(always)]
fn increments(color: [f64; 4], weight: f64) -> Bucket {
    if weight == 1.0 {
        [color[0] as u32, color[1] as u32, color[2] as u32, color[3] as u32, WHITE_LEVEL as u32]
    } else {
        [
            (weight * color[0]) as u32,
            (weight * color[1]) as u32,
            (weight * color[2]) as u32,
            (weight * color[3]) as u32,
            (weight * WHITE_LEVEL) as u32,
        ]
    }
}

/// flam3's choice table: entry e picks the xform whose cumulative weight interval holds
/// e · total / 16384. `None` when the weights sum to 0.
fn choice_row(weights: &[f64]) -> Option<Vec<u16>> {
    let total: f64 = weights.iter().sum();
    if !(total > 0.0) || weights.is_empty() {
        return None;
    }
    let step = total / CHOICE_ENTRIES as f64;
    let mut row = Vec::with_capacity(CHOICE_ENTRIES);
    let mut j = 0;
    let mut t = weights[0];
    let mut r = 0.0;
    for _ in 0..CHOICE_ENTRIES {
        while r >= t && j + 1 < weights.len() {
            j += 1;
            t += weights[j];
        }
        row.push(j as u16);
        r += step;
    }
    Some(row)
}

/// Workers for `runs` runs (or blocks): rayon's threads, at most one a run.
fn workers_for(runs: u64) -> usize {
    rayon::current_num_threads().max(1).min(runs.max(1) as usize)
}

#[inline(always)]
fn uniform11(rng: &mut Pcg32) -> f64 {
    rng.next_f64() * 2.0 - 1.0
}

/// Whether `NLIFS_FLAME_F64` asks for the f64 chaos game, whose chains draw as flam3's do, for
/// every flame (otherwise flames it can take run in f32 lanes: `render_lanes.rs`).
fn f64_only() -> bool {
    std::env::var_os("NLIFS_FLAME_F64").is_some_and(|v| v != "0")
}

/// Whether `NLIFS_FLAME_QUEUES` asks the lane game to queue the points of every flame, also
/// those whose xforms share their terms (`render_lanes_shared.rs`): for comparisons.
fn queues_only() -> bool {
    std::env::var_os("NLIFS_FLAME_QUEUES").is_some_and(|v| v != "0")
}

/// flam3's `badvalue`: NaN or beyond ±1e10.
#[inline(always)]
fn is_bad(p: [f64; 2]) -> bool {
    let bad = |v: f64| v.is_nan() || !(-1e10..=1e10).contains(&v);
    bad(p[0]) || bad(p[1])
}

#[path = "render_lanes.rs"]
mod lanes;

#[cfg(test)]
#[path = "render_tests.rs"]
mod tests;
