//! The flame chaos game in f32 lanes (every variation: `variations_lanes::SUPPORTED`), for
//! flames whose view f32 resolves: the points are not chains that keep flam3's draws, but a pool
//! of [`POINTS`] orbits in one queue per xform. A round maps each queue [`LANES`] points at a time
//! (contiguous loads, no gather), plots them, draws each one's next xform and appends it to that
//! xform's queue for the next round (a compress per xform, no scatter). Every phase runs on arrays of [`LANES`] f32 (two lanes where f64 has one), which
//! LLVM turns into vector code, and the elementary functions are f32 polynomials (`trig32.rs`).
//! Flames whose xforms share their terms (the same variations and parameters) need no queues:
//! their [`LANES`] orbits stay in their lanes, each mapped by its own xform's affine maps and
//! weights (`render_lanes_shared.rs`).
//!
//! The picture is the same flame as the f64 game's (same xforms, choice tables, colours,
//! camera, palette and bucket increments; `tests/flame_fidelity.rs` holds both to flam3's
//! renders), not the same bytes: the orbits differ from the first rounding on. It is still a
//! pure function of the seed, whatever the thread count and vector build (AVX-512, AVX2, none): the samples are cut into blocks of
//! [`BLOCK_SAMPLES`], each drawn from its own generators, and the sums are integers. A block
//! starts its points at random in [−1, 1]² and drops their first [`FUSE_ITERATIONS`] rounds, as
//! flam3's runs do; a point that leaves the plane is re-seeded and its step counted, not plotted
//! (flam3 retries the step instead: the difference is the share of such steps).

use std::sync::atomic::{AtomicU64, Ordering};

use super::super::render_base::WHITE_LEVEL;
use super::super::variations::MAX_CONSTS;
use super::super::variations_lanes::{DRAWS, SUPPORTED};
use super::{CHOICE_ENTRIES, ChaosGame, FUSE_ITERATIONS, GameXform};
use crate::flame::{PaletteMode, trig32};
use crate::rng::Pcg32;

/// Points mapped at once: four AVX-512 vectors of f32, whose independent work overlaps (a step
/// of 64 points took 25 % less time per point than one of 16, one of 32 15 %: measured).
const LANES: usize = 64;
/// Orbits a worker keeps in its queues (a queue's last vector is partial: the more points, the
/// fewer lanes idle).
const POINTS: usize = 4096;
/// Samples of one block (512 rounds of the pool), each block from its own generators.
pub(super) const BLOCK_SAMPLES: u64 = 1 << 21;
/// Most xforms the lane game takes (the next xform is found by comparisons with each's share).
const MAX_XFORMS: usize = 64;
/// The view is drawn in f32 only where f32's spacing at the view's farthest coordinate is below
/// 1/`RESOLUTION` of a bucket.
const RESOLUTION: f64 = 64.0;

/// One term in f32.
struct Term32 {
    variation: u8,
    weight: f32,
    k: [f32; MAX_CONSTS],
}

/// An xform in f32, as [`GameXform`] in f64.
struct Xform32 {
    coefs: [f32; 6],
    post: Option<[f32; 6]>,
    /// `pre_blur`'s weight (0: none).
    pre_blur: f32,
    needs: u8,
    terms: Vec<Term32>,
    color_held: f32,
    color_kept: f32,
    plotted_weight: f64,
    /// Its points' cell increments by step-palette entry (step mode).
    increments: Box<[Cell; 256]>,
}

impl Xform32 {
    /// `x` in f32; `None` when a term is not in [`SUPPORTED`].
    fn new(x: &GameXform, game: &ChaosGame) -> Option<Self> {
        let parts = x.map.parts();
        let f6 = |c: &[f64; 6]| c.map(|v| v as f32);
        let terms = parts
            .terms
            .iter()
            .map(|&(variation, weight, k)| {
                SUPPORTED.contains(&variation).then(|| Term32 {
                    variation,
                    weight: weight as f32,
                    k: k.map(|v| v as f32),
                })
            })
            .collect::<Option<Vec<_>>>()?;
        let increments =
            Box::new(std::array::from_fn(|i| Cell::of(game.increments_of((i as f64 + 0.5) / 256.0, x.plotted_weight))));
        Some(Self {
            coefs: f6(parts.coefs),
            post: parts.post.map(f6),
            pre_blur: parts.pre_blur as f32,
            needs: parts.needs,
            terms,
            color_held: x.color_held as f32,
            color_kept: x.color_kept as f32,
            plotted_weight: x.plotted_weight,
            increments,
        })
    }

    /// The xform's images of the lanes' points (`x`, `y`), in place, drawing from `rng`.
    #[inline(always)]
    fn apply(&self, x: &mut Lanes, y: &mut Lanes, rng: &mut LaneRng, scratch: &mut Scratch) {
        let p = &mut scratch.point;
        if self.pre_blur == 0.0 {
            for l in 0..LANES {
                let [tx, ty] = affine(&self.coefs, x[l], y[l]);
                (p.x[l], p.y[l], p.r2[l]) = (tx, ty, tx * tx + ty * ty);
            }
        } else {
            for l in 0..LANES {
                [p.x[l], p.y[l]] = affine(&self.coefs, x[l], y[l]);
            }
            pre_blur(&Lanes::splat(self.pre_blur), p, rng);
        }
        sum_terms(&self.terms, &*self.terms, self.needs, (x, y), rng, scratch);
        if let Some(c) = &self.post {
            for l in 0..LANES {
                [x[l], y[l]] = affine(c, x[l], y[l]);
            }
        }
    }

    /// The colour coordinate after this xform.
    #[inline(always)]
    fn color_of(&self, c: f32) -> f32 {
        self.color_held + self.color_kept * c
    }
}

/// The arrays an xform's map works in, kept by a worker from step to step (made afresh each
/// step, their 3.5 kB of zeros were a memset call, 4 % of the samples in perf): each step
/// writes the quantities and random numbers its terms read before they read them; the others
/// hold earlier steps' values.
struct Scratch {
    point: PointLanes,
    /// The terms' random numbers (each term draws its own; those that draw none read none).
    draw: Draws,
    /// A term's image.
    dx: Lanes,
    dy: Lanes,
    /// Whether each lane's arguments were within the f32 cores' ranges, in a term.
    fast: Lanes<bool>,
}

impl Scratch {
    fn new() -> Self {
        let zero = Lanes::splat(0.0);
        Self {
            point: PointLanes::default(),
            draw: Draws([[0.0; LANES]; DRAWS]),
            dx: zero,
            dy: zero,
            fast: Lanes::splat(true),
        }
    }
}

/// [`LANES`] generators, one a lane: nlifs's PCG, advanced as vectors.
struct LaneRng {
    state: Lanes<u32>,
}

impl LaneRng {
    fn new(seed: u32, block: u64) -> Self {
        let block = block as u32;
        Self { state: Lanes(std::array::from_fn(|l| Pcg32::for_stream(seed, block, 0x8000_0000 | l as u32).state())) }
    }

    #[inline(always)]
    fn next_u32(&mut self) -> Lanes<u32> {
        let mut out = Lanes::splat(0);
        for (o, s) in out.iter_mut().zip(self.state.iter_mut()) {
            let mut g = Pcg32::from_state(*s);
            *o = g.next_u32();
            *s = g.state();
        }
        out
    }

    /// Uniform in [0, 1), 24 bits.
    #[inline(always)]
    fn uniform(&mut self) -> Lanes {
        Lanes(self.next_u32().0.map(|u| (u >> 8) as f32 * (1.0 / 16_777_216.0)))
    }

    /// 0 or 1.
    #[inline(always)]
    fn bits(&mut self) -> Lanes {
        Lanes(self.next_u32().0.map(|u| (u & 1) as f32))
    }
}

/// The camera in f32: the histogram's bounds and buckets per unit.
struct Camera32 {
    rotation: Option<([[f32; 2]; 2], [f32; 2])>,
    bounds: [f32; 4],
    scale: [f32; 2],
    width: u32,
    last: [f32; 2],
    /// The first of [`LANES`] cells past the histogram's: where lane l's samples that add
    /// nothing go, its own cell (one cell for all was a chain of dependent adds).
    sink: u32,
}

/// The chaos game of a flame in f32 lanes.
pub(super) struct LaneGame<'a> {
    game: &'a ChaosGame,
    xforms: Vec<Xform32>,
    final_xform: Option<(Xform32, f32)>,
    /// Per choice row, the first entry of each xform after the first: the next xform is the count
    /// of those at or below the drawn entry.
    firsts: Vec<[u32; MAX_XFORMS]>,
    camera: Camera32,
    /// What keeps a worker's cells from wrapping (none set aside yet).
    overflow: Overflow,
    /// Whether its xforms share their terms: blocks run without queues
    /// ([`Self::run_block_shared`]).
    shared: bool,
}

impl<'a> LaneGame<'a> {
    /// `game` in f32 lanes; where it cannot be, why (in a user's words): it has more than
    /// [`MAX_XFORMS`] xforms, its choice table is not in xform order, f32 does not resolve its
    /// view ([`RESOLUTION`]), an entry of its palette is not opaque ([`Cell`]), its histogram is
    /// too large for the cells' u32 indices, or its increments are so large that a block could
    /// carry a cell past 2^31 ([`Overflow`]: opacities above 1.5, whose points weigh more than 4).
    pub fn new(game: &'a ChaosGame) -> Result<Self, &'static str> {
        let n = game.xforms.len();
        if n > MAX_XFORMS {
            return Err("more than 64 xforms");
        }
        let cam = &game.camera;
        let far = cam.bounds.iter().chain(&cam.center).fold(0f64, |m, v| m.max(v.abs()));
        let bucket = 1.0 / cam.x_scale.max(cam.y_scale);
        let cells = cam.hist_width as u64 * cam.hist_height as u64;
        if !(far * f64::from(f32::EPSILON) * RESOLUTION <= bucket) {
            return Err("a view too deep or too far from the origin for f32");
        }
        if game.dmap.iter().any(|c| c[3] != WHITE_LEVEL) {
            return Err("a palette entry that is not opaque");
        }
        if cam.hist_width.max(cam.hist_height) >= 1 << 23 || cells + LANES as u64 > u64::from(u32::MAX) {
            return Err("a histogram too large for the lanes' 32-bit bucket indices");
        }
        const UNSUPPORTED: &str = "a variation the lanes do not hold";
        let xforms =
            game.xforms.iter().map(|x| Xform32::new(x, game)).collect::<Option<Vec<_>>>().ok_or(UNSUPPORTED)?;
        let final_xform = match &game.final_xform {
            Some(f) => Some((Xform32::new(f, game).ok_or(UNSUPPORTED)?, f.opacity as f32)),
            None => None,
        };
        let mut firsts = Vec::new();
        for row in game.choice.chunks_exact(CHOICE_ENTRIES) {
            if row.windows(2).any(|w| w[1] < w[0]) {
                return Err("a choice table out of xform order");
            }
            let mut f = [CHOICE_ENTRIES as u32; MAX_XFORMS];
            for (j, first) in f.iter_mut().enumerate().take(n).skip(1) {
                *first = row.partition_point(|&e| usize::from(e) < j) as u32;
            }
            firsts.push(f);
        }
        let rotation = cam.rotation.map(|r| (r.map(|row| row.map(|v| v as f32)), cam.center.map(|v| v as f32)));
        let camera = Camera32 {
            rotation,
            bounds: cam.bounds.map(|v| v as f32),
            scale: [cam.x_scale as f32, cam.y_scale as f32],
            width: cam.hist_width as u32,
            last: [cam.hist_width as f32 - 1.0, cam.hist_height as f32 - 1.0],
            sink: (cam.hist_width * cam.hist_height) as u32,
        };
        // A linear palette's increment blends two entries' (the larger bounds it).
        let largest = game
            .xforms
            .iter()
            .flat_map(|x| game.dmap.iter().map(|&c| super::increments(c, x.plotted_weight)))
            .flatten()
            .max()
            .unwrap_or(0);
        let overflow = Overflow::new(largest, BLOCK_SAMPLES).ok_or("an xform's opacity above 1.5")?;
        let shared = !super::queues_only() && shared::share_terms(&xforms);
        Ok(Self { game, xforms, final_xform, firsts, camera, overflow, shared })
    }

    /// One worker's part of `samples`: blocks taken in turn from `next` until none is left. Its
    /// histogram of `cells` cells and its re-seeds.
    pub fn run_part(
        &self,
        seed: u32,
        samples: u64,
        next: &AtomicU64,
        cells: usize,
        progress: &(dyn Fn(u64) + Sync),
    ) -> (Vec<Cell>, u64) {
        // The samples that add nothing go to cells past the picture's, one a lane.
        // Every page written (other workers update theirs at random).
        let mut histogram = crate::platform::zeroed_pages::<Cell>(cells + LANES);
        let bad = self.run_worker(seed, samples, next, &mut histogram, progress);
        histogram.truncate(cells);
        (histogram, bad)
    }

    /// [`Self::run_part`]'s blocks into `histogram`, whose last cells are the sinks: with queues, or
    /// without where the xforms share their terms. Returns the re-seeds.
    fn run_worker(
        &self,
        seed: u32,
        samples: u64,
        next: &AtomicU64,
        histogram: &mut [Cell],
        progress: &(dyn Fn(u64) + Sync),
    ) -> u64 {
        if self.shared {
            self.run_shared(seed, samples, next, histogram, progress)
        } else {
            self.run_queued(seed, samples, next, histogram, progress)
        }
    }

    // Each game has its own builds: neither's loops share a function with the other's.
    vector_builds! {
        /// [`Self::run_worker`] with queues.
        fn run_queued(Cell) => run_blocks, run_blocks_avx512, run_blocks_avx2
    }

    vector_builds! {
        /// [`Self::run_worker`] without queues ([`Self::run_block_shared`]).
        fn run_shared(Cell) => run_blocks_shared, run_blocks_shared_avx512, run_blocks_shared_avx2
    }

    /// [`Self::run_queued`]'s body; `wide`: the CPU runs AVX-512F (the queues' compress).
    #[inline(always)]
    fn run_blocks(
        &self,
        seed: u32,
        samples: u64,
        next_block: &AtomicU64,
        histogram: &mut [Cell],
        progress: &(dyn Fn(u64) + Sync),
        wide: bool,
    ) -> u64 {
        let mut queues = Queues::new(self.xforms.len(), wide);
        self.each_block(seed, samples, next_block, histogram, progress, &mut queues)
    }

    /// [`Self::run_shared`]'s body.
    #[inline(always)]
    fn run_blocks_shared(
        &self,
        seed: u32,
        samples: u64,
        next_block: &AtomicU64,
        histogram: &mut [Cell],
        progress: &(dyn Fn(u64) + Sync),
        _wide: bool,
    ) -> u64 {
        self.each_block(seed, samples, next_block, histogram, progress, &mut shared::WithoutQueues)
    }

    /// Blocks taken in turn from `next_block` until none is left, each run by `game` and its cells
    /// kept from wrapping ([`Overflow`]). Returns the re-seeds.
    #[inline(always)]
    fn each_block(
        &self,
        seed: u32,
        samples: u64,
        next_block: &AtomicU64,
        histogram: &mut [Cell],
        progress: &(dyn Fn(u64) + Sync),
        game: &mut impl BlockGame,
    ) -> u64 {
        let blocks = samples.div_ceil(BLOCK_SAMPLES);
        let mut overflow = self.overflow.clone();
        let mut bad = 0;
        loop {
            let block = next_block.fetch_add(1, Ordering::Relaxed);
            if block >= blocks {
                overflow.finish(histogram);
                return bad;
            }
            let n = BLOCK_SAMPLES.min(samples - block * BLOCK_SAMPLES);
            overflow.before_block(n, histogram);
            bad += game.run_block(self, seed, block, n, histogram);
            progress(n);
        }
    }

    /// Block `block`: [`POINTS`] orbits until `n` samples are drawn after their fuse.
    #[inline(always)]
    fn run_block(&self, seed: u32, block: u64, n: u64, q: &mut Queues, histogram: &mut [Cell]) -> u64 {
        let xforms = self.xforms.len();
        let mut start = Pcg32::for_stream(seed, block as u32, 0x7FFF_FFFF);
        let mut rng = LaneRng::new(seed, block);
        let mut scratch = Scratch::new();
        q.clear();
        for _ in 0..POINTS {
            let (p, color, j) = self.start_point(&mut start);
            q.push(j, p, color);
        }
        let mut pending = InFlight::new(self.camera.sink);
        let mut bad = 0;
        let mut drawn = 0u64;
        let mut round = -FUSE_ITERATIONS;
        while drawn < n {
            let plot = round >= 0;
            'round: for j in 0..xforms {
                q.clear_tail(j);
                let len = q.len[j];
                for at in (0..len).step_by(LANES) {
                    let mut count = (len - at).min(LANES);
                    if plot {
                        count = count.min((n - drawn) as usize);
                        drawn += count as u64;
                    }
                    bad += self.step(j, at, count, plot, q, (&mut rng, &mut scratch), &mut pending, histogram);
                    if plot && drawn >= n {
                        break 'round;
                    }
                }
            }
            q.next_round();
            round += 1;
        }
        pending.finish(histogram);
        bad
    }

    /// A block's starting point drawn from `start`: at random in [−1, 1]², its colour, and its
    /// first xform (by weight).
    #[inline(always)]
    fn start_point(&self, start: &mut Pcg32) -> ([f32; 2], f32, usize) {
        let p = [start.next_f32() * 2.0 - 1.0, start.next_f32() * 2.0 - 1.0];
        let color = start.next_f32();
        (p, color, self.next_xform(0, start.next_u32() & (CHOICE_ENTRIES as u32 - 1)))
    }

    /// The next xform after xform `row` − 1 (0: by weight) for choice-table entry `entry`.
    #[inline(always)]
    fn next_xform(&self, row: usize, entry: u32) -> usize {
        let firsts = &self.firsts[row.min(self.firsts.len() - 1)];
        firsts[1..self.xforms.len()].iter().map(|&f| usize::from(entry >= f)).sum()
    }

    /// Points `at..at + count` of xform `j`'s queue: mapped, re-seeded where they left the plane,
    /// plotted when `plot`, and queued to their next xforms. Returns the re-seeds.
    #[inline(always)]
    #[expect(clippy::too_many_arguments, reason = "one step of the round's state")]
    fn step<'s>(
        &'s self,
        j: usize,
        at: usize,
        count: usize,
        plot: bool,
        q: &mut Queues,
        (rng, scratch): (&mut LaneRng, &mut Scratch),
        pending: &mut InFlight<'s>,
        histogram: &mut [Cell],
    ) -> u64 {
        let xf = &self.xforms[j];
        let (mut x, mut y, mut c) = q.load(j, at);
        xf.apply(&mut x, &mut y, rng, scratch);
        for c in c.iter_mut() {
            *c = xf.color_of(*c);
        }
        let (bad, reseeds) = self.reseed(count, &mut x, &mut y, rng);
        if plot && xf.plotted_weight != 0.0 {
            self.plot(xf, count, &bad, (&x, &y, &c), (rng, scratch), pending, histogram);
        }
        // Each point's next xform, and the point queued to it.
        let next = self.next_xforms(&Lanes::splat(j as u32), rng);
        q.append(&next, count, &x, &y, &c);
        reseeds
    }

    /// The lanes below `count` whose point left the plane, re-seeded at random in [−1, 1]²,
    /// and their number.
    #[inline(always)]
    fn reseed(&self, count: usize, x: &mut Lanes, y: &mut Lanes, rng: &mut LaneRng) -> (Lanes<bool>, u64) {
        let mut bad = Lanes::splat(false);
        let mut any_bad = false;
        for l in 0..LANES {
            bad[l] = !((x[l].abs() <= 1e10) & (y[l].abs() <= 1e10)) & (l < count);
            any_bad |= bad[l];
        }
        let mut reseeds = 0;
        if any_bad {
            let (rx, ry) = (rng.uniform(), rng.uniform());
            for l in 0..LANES {
                if bad[l] {
                    x[l] = rx[l] * 2.0 - 1.0;
                    y[l] = ry[l] * 2.0 - 1.0;
                    reseeds += 1;
                }
            }
        }
        (bad, reseeds)
    }

    /// Each lane's next xform after its xform `now` (with xaos the choice row is that xform's).
    #[inline(always)]
    fn next_xforms(&self, now: &Lanes<u32>, rng: &mut LaneRng) -> Lanes<u32> {
        let entries = rng.next_u32();
        if !self.game.xaos {
            return self.next_by_row(0, &entries);
        }
        if now.iter().all(|&j| j == now[0]) {
            return self.next_by_row(now[0] as usize + 1, &entries);
        }
        let mut next = Lanes::splat(0u32);
        for j in 0..self.xforms.len() {
            let by_row = self.next_by_row(j + 1, &entries);
            for l in 0..LANES {
                let keep = 0u32.wrapping_sub(u32::from(now[l] == j as u32));
                next[l] = (by_row[l] & keep) | (next[l] & !keep);
            }
        }
        next
    }

    /// Each lane's next xform by choice row `row` for the lane's drawn choice-table entry. (A
    /// method, not a closure: a closure's body is not built with its caller's vector features.)
    #[inline(always)]
    fn next_by_row(&self, row: usize, entries: &Lanes<u32>) -> Lanes<u32> {
        let mut next = Lanes::splat(0u32);
        for &first in &self.firsts[row][1..self.xforms.len()] {
            for l in 0..LANES {
                next[l] += u32::from((entries[l] & (CHOICE_ENTRIES as u32 - 1)) >= first);
            }
        }
        next
    }

    /// Adds the points that plot (lanes below `count`, not re-seeded, in view) to their buckets:
    /// the final xform's image where there is one (applied by its opacity), the colour looked
    /// up, the bucket prefetched now and added with the next vector.
    #[inline(always)]
    #[expect(clippy::too_many_arguments, reason = "one step of the round's state")]
    fn plot<'s>(
        &'s self,
        xf: &'s Xform32,
        count: usize,
        bad: &Lanes<bool>,
        (x, y, c): (&Lanes, &Lanes, &Lanes),
        (rng, scratch): (&mut LaneRng, &mut Scratch),
        pending: &mut InFlight<'s>,
        histogram: &mut [Cell],
    ) {
        // The points plotted: the orbits' own (not copied) or the final xform's images.
        let (mut fx, mut fy, mut fc);
        let (sx, sy, sc) = match &self.final_xform {
            None => (x, y, c),
            Some((f, opacity)) => {
                (fx, fy, fc) = (*x, *y, *c);
                f.apply(&mut fx, &mut fy, rng, scratch);
                let applies = if *opacity == 1.0 { Lanes::splat(1.0) } else { rng.uniform() };
                let (rx, ry) = (rng.uniform(), rng.uniform());
                for l in 0..LANES {
                    if (applies[l] < *opacity) | (*opacity == 1.0) {
                        fc[l] = f.color_of(c[l]);
                        let out = !((fx[l].abs() <= 1e10) & (fy[l].abs() <= 1e10));
                        fx[l] = if out { rx[l] * 2.0 - 1.0 } else { fx[l] };
                        fy[l] = if out { ry[l] * 2.0 - 1.0 } else { fy[l] };
                    } else {
                        (fx[l], fy[l]) = (x[l], y[l]);
                    }
                }
                (&fx, &fy, &fc)
            }
        };
        let cam = &self.camera;
        let (mut tx, mut ty);
        let (sx, sy) = match &cam.rotation {
            None => (sx, sy),
            Some((r, center)) => {
                (tx, ty) = (Lanes::splat(0.0), Lanes::splat(0.0));
                for l in 0..LANES {
                    let d = [sx[l] - center[0], sy[l] - center[1]];
                    tx[l] = d[0] * r[0][0] + d[1] * r[0][1] + center[0];
                    ty[l] = d[0] * r[1][0] + d[1] * r[1][1] + center[1];
                }
                (&tx, &ty)
            }
        };
        // This vector's buckets and entries written in place of the oldest vector's, whose adds
        // are done first.
        let pending = pending.take(histogram);
        let b = &cam.bounds;
        for l in 0..LANES {
            let inside = (sx[l] >= b[0]) & (sy[l] >= b[1]) & (sx[l] <= b[2]) & (sy[l] <= b[3]);
            let i = whole((sx[l] - b[0]) * cam.scale[0], cam.last[0]);
            let k = whole((sy[l] - b[1]) * cam.scale[1], cam.last[1]);
            let adds = inside & !bad[l] & (l < count);
            // A sample that adds nothing goes to its lane's sink, past the histogram's cells.
            pending.bucket[l] = if adds { i + k * cam.width } else { cam.sink + l as u32 };
            pending.entry[l] = whole(sc[l] * 256.0, 255.0) as u8;
        }
        for &b in pending.bucket.iter() {
            histogram[b as usize].prefetch();
        }
        if self.game.palette_mode == PaletteMode::Step {
            pending.increments = Increments::Step(&xf.increments);
        } else {
            pending.increments = Increments::Own;
            for (inc, &c) in pending.own.iter_mut().zip(sc) {
                *inc = Cell::of(self.game.increments_of(f64::from(c), xf.plotted_weight));
            }
        }
    }
}

/// How a worker runs a block: with its [`Queues`], or without ([`shared::WithoutQueues`]). (A
/// trait, not a closure: a closure's body is not built with its caller's vector features.)
trait BlockGame {
    /// Block `block` of `n` samples of `game` into `histogram`; its re-seeds.
    fn run_block(&mut self, game: &LaneGame, seed: u32, block: u64, n: u64, histogram: &mut [Cell]) -> u64;
}

impl BlockGame for Queues {
    #[inline(always)]
    fn run_block(&mut self, game: &LaneGame, seed: u32, block: u64, n: u64, histogram: &mut [Cell]) -> u64 {
        game.run_block(seed, block, n, self, histogram)
    }
}

/// `pre_blur` of weight `w` (a lane's) on the affine images `p.x`, `p.y`: each moved by a
/// pseudo-Gaussian distance of scale w (four uniform draws) in a uniform direction; and their
/// squared radii `p.r2`.
#[inline(always)]
fn pre_blur(w: &Lanes, p: &mut PointLanes, rng: &mut LaneRng) {
    let (u0, u1, u2, u3, turn) = (rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
    for l in 0..LANES {
        let g = w[l] * (u0[l] + u1[l] + u2[l] + u3[l] - 2.0);
        let (s, c, _) = trig32::sin_cos_core(turn[l] * (2.0 * std::f32::consts::PI));
        let (tx, ty) = (p.x[l] + g * c, p.y[l] + g * s);
        (p.x[l], p.y[l], p.r2[l]) = (tx, ty, tx * tx + ty * ty);
    }
}

/// `v` clamped to [0, `last`] (NaN: 0) and truncated, for `last` < 2^23: with operations vector
/// loops have (2^23 added puts the whole part in the low bits).
#[inline(always)]
fn whole(v: f32, last: f32) -> u32 {
    const TWO_23: f32 = 8_388_608.0;
    let v = v.max(0.0).min(last);
    (v.trunc() + TWO_23).to_bits() & 0x7F_FFFF
}

#[path = "render_lanes_arrays.rs"]
mod arrays;
use arrays::{Draws, Lanes, PointLanes};

#[path = "render_lanes_cells.rs"]
mod cells;
pub(super) use cells::Cell;
use cells::{InFlight, Increments, Overflow};

#[path = "render_lanes_terms.rs"]
mod terms;
use terms::{affine, sum_terms};

#[path = "render_lanes_shared.rs"]
mod shared;

#[path = "render_lanes_queues.rs"]
mod queues;
use queues::Queues;

#[cfg(test)]
#[path = "render_lanes_tests.rs"]
mod tests;
