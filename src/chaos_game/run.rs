//! Running the chaos game: one chunk of orbits ([`run_chunk`], on the fastest path the IFS and
//! the CPU allow), a whole [`ChunkPlan`] in parallel ([`run_parallel`]), and the short
//! deterministic runs that estimate the attractor's extent for framing.

use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;

use super::color_coord::{C_START, ColorCoordSink};
use super::flame::FlameRow;
use super::lanes::LaneKernel;
use super::plan::ChunkPlan;
use super::sink::{CollectSink, PointBatch, PointSink};
#[cfg(all(test, target_arch = "x86_64"))]
use super::x86;
use super::{CompiledIfs, ORBITS_PER_CHUNK, STEPS_PER_BATCH};
use crate::rng::Pcg32;

/// Runs chunk `chunk` of a chaos game: [`ORBITS_PER_CHUNK`] orbits, `steps` points each after
/// the transient, into `sink`. Orbit (lane) `k` of chunk `c` is chain `c · ORBITS_PER_CHUNK + k`
/// and draws from the random stream (seed, frame, chain), as chain i of the GPU does. With
/// palette colour the points carry their quantized colour coordinate in place of the function.
pub fn run_chunk(ifs: &CompiledIfs, seed: u32, frame: u32, chunk: u32, steps: usize, sink: &mut impl PointSink) {
    run_chunk_on(ifs, Path::Fastest, seed, frame, chunk, steps, sink)
}

/// Which implementation [`run_chunk_on`] takes; all give the same points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Path {
    /// The fastest the IFS and the CPU allow.
    Fastest,
    /// Not the vector kernel (for tests).
    #[cfg(test)]
    Portable,
    /// The vector kernel with this coefficient lookup (for tests).
    #[cfg(all(test, target_arch = "x86_64"))]
    Simd(x86::Lookup),
}

pub(super) fn run_chunk_on(
    ifs: &CompiledIfs,
    path: Path,
    seed: u32,
    frame: u32,
    chunk: u32,
    steps: usize,
    sink: &mut impl PointSink,
) {
    let mut chains = ChunkChains::start(ifs, seed, frame, chunk);
    run_chains(ifs, path, &mut chains, ifs.transient, steps, sink);
}

/// Advances the chains `skip` steps not emitted, then `steps` into `sink`, on `path`; with
/// colour coordinates (palette colour) the skipped steps run through the colour sink, which
/// carries c through them and drops their points (`chaos_game/color_coord.rs`).
pub(super) fn run_chains(
    ifs: &CompiledIfs,
    path: Path,
    chains: &mut ChunkChains,
    skip: u32,
    steps: usize,
    sink: &mut impl PointSink,
) {
    let ChunkChains { rngs, pos, colors, rows } = chains;
    let orbits = Orbits { rngs, pos, rows, transient: skip, steps };
    match &ifs.color_coords {
        None => run_kernel(ifs, path, orbits, sink),
        Some(coords) => {
            let final_color = ifs.flames.as_ref().and_then(|t| t.final_color());
            let speeds = ifs.color_speeds.as_deref();
            let mut colored = ColorCoordSink::new(coords, speeds, final_color, colors, skip as usize, sink)
                .interpolated(ifs.palette_linear);
            run_kernel(ifs, path, Orbits { transient: 0, steps: skip as usize + steps, ..orbits }, &mut colored);
        }
    }
}

/// The kernel of `path` on `orbits` (left where they end): their transient steps not emitted,
/// then their steps into `sink`.
fn run_kernel(ifs: &CompiledIfs, path: Path, orbits: Orbits<'_>, sink: &mut impl PointSink) {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = &ifs.simd {
        let lookup = match path {
            Path::Fastest => Some(simd.lookup),
            #[cfg(test)]
            Path::Portable => None,
            #[cfg(test)]
            Path::Simd(lookup) => Some(lookup),
        };
        if let Some(lookup) = lookup {
            let Orbits { rngs, pos, transient, steps, .. } = orbits;
            let mut states = rngs.map(Pcg32::state);
            let mut xyz = pos.map(|p| p.to_array());
            simd.run_kept(lookup, &mut states, &mut xyz, transient, steps, sink);
            *rngs = states.map(Pcg32::from_state);
            *pos = xyz.map(Vec3A::from_array);
            return;
        }
    }
    #[cfg(all(test, target_arch = "x86_64"))]
    assert!(!matches!(path, Path::Simd(_)), "no vector kernel for this IFS");
    run_orbits(ifs, path, orbits, sink);
}

/// The portable kernels on `orbits`: the lane kernel where the IFS has one, else the general
/// loop (per-cell selection for adaptive probabilities, per previous function with xaos;
/// flame functions with the orbit's generator, `chaos_game/flame.rs`, a step of all the
/// orbits at a time except on the test's portable path).
fn run_orbits(
    ifs: &CompiledIfs,
    #[cfg_attr(not(test), expect(unused_variables, reason = "only the tests' portable path reads it"))] path: Path,
    orbits: Orbits<'_>,
    sink: &mut impl PointSink,
) {
    match &ifs.lanes {
        Some(lanes) => run_lanes(lanes, orbits, sink),
        #[cfg(test)]
        None if ifs.has_flames() && path == Path::Portable => {
            let sel = &ifs.selection;
            orbits.run_shown(sink, |rng, p, row| {
                let fi = sel.select(sel.row_of(p.into(), *row), rng.next_u32());
                sel.step_row(row, fi);
                let (next, shown, left) = ifs.map_with_rng_final(fi, p.into(), rng);
                let flag = if left { ifs.final_left_out_bit() as usize } else { 0 };
                (next.into(), shown.into(), fi | flag)
            })
        }
        None if ifs.has_flames() => flame_rows(ifs, orbits, sink),
        None => {
            let sel = &ifs.selection;
            orbits.run(sink, |rng, p, row| {
                let fi = sel.select(sel.row_of(p.into(), *row), rng.next_u32());
                sel.step_row(row, fi);
                (ifs.map_fast(fi, p.into()).into(), fi)
            })
        }
    }
}

/// The orbits of an IFS with flame functions, a step of all of them at a time: every lane
/// selects its function, then the lanes are mapped ([`CompiledIfs::map_flame_row_on`], compiled
/// for the CPU's vector level).
#[inline(always)]
fn flame_rows(ifs: &CompiledIfs, orbits: Orbits<'_>, sink: &mut impl PointSink) {
    orbits.run_rows(sink, &mut FlameStep { ifs, work: FlameRow::new(ifs), level: crate::simd::SimdLevel::detect() })
}

/// [`flame_rows`]'s step, with the work space of its batches.
struct FlameStep<'a> {
    ifs: &'a CompiledIfs,
    work: FlameRow,
    level: crate::simd::SimdLevel,
}

impl RowStep for FlameStep<'_> {
    #[inline(always)]
    fn step(&mut self, lanes: Lanes<'_>, shown: &mut [Vec3A; ORBITS_PER_CHUNK], fs: &mut [u8; ORBITS_PER_CHUNK]) {
        let sel = &self.ifs.selection;
        let each = lanes.rngs.iter_mut().zip(lanes.pos.iter()).zip(lanes.rows.iter_mut()).zip(fs.iter_mut());
        for (((rng, p), row), f) in each {
            let fi = sel.select(sel.row_of((*p).into(), *row), rng.next_u32());
            sel.step_row(row, fi);
            *f = fi as u8;
        }
        self.ifs.map_flame_row_on(self.level, fs, lanes.rngs, lanes.pos, shown, &mut self.work);
    }
}

/// One step of all the lanes of a chunk ([`Orbits::run_rows`]): each lane's next point left in
/// `lanes.pos`, the point it emits in `shown` and its function in `fs`.
pub(super) trait RowStep {
    fn step(&mut self, lanes: Lanes<'_>, shown: &mut [Vec3A; ORBITS_PER_CHUNK], fs: &mut [u8; ORBITS_PER_CHUNK]);
}

/// The state of a chunk's lanes that a [`RowStep`] advances.
pub(super) struct Lanes<'a> {
    pub rngs: &'a mut [Pcg32; ORBITS_PER_CHUNK],
    pub pos: &'a mut [Vec3A; ORBITS_PER_CHUNK],
    pub rows: &'a mut [u16; ORBITS_PER_CHUNK],
}

/// A step of each lane by itself, by a closure of the lane.
struct EachLane<F>(F);

impl<F: Fn(&mut Pcg32, Vec3A, &mut u16) -> (Vec3A, Vec3A, usize)> RowStep for EachLane<F> {
    #[inline(always)]
    fn step(&mut self, lanes: Lanes<'_>, shown: &mut [Vec3A; ORBITS_PER_CHUNK], fs: &mut [u8; ORBITS_PER_CHUNK]) {
        for k in 0..ORBITS_PER_CHUNK {
            let (q, s, fi) = (self.0)(&mut lanes.rngs[k], lanes.pos[k], &mut lanes.rows[k]);
            (lanes.pos[k], shown[k], fs[k]) = (q, s, fi as u8);
        }
    }
}

/// The orbits of one chunk, advanced one step at a time across all lanes (independent lanes
/// give the CPU instruction-level parallelism).
pub(super) struct Orbits<'a> {
    rngs: &'a mut [Pcg32; ORBITS_PER_CHUNK],
    pos: &'a mut [Vec3A; ORBITS_PER_CHUNK],
    /// Each orbit's xaos row ([`ChunkChains::rows`]).
    rows: &'a mut [u16; ORBITS_PER_CHUNK],
    transient: u32,
    steps: usize,
}

impl Orbits<'_> {
    #[inline(always)]
    pub(super) fn run(self, sink: &mut impl PointSink, step: impl Fn(&mut Pcg32, Vec3A, &mut u16) -> (Vec3A, usize)) {
        self.run_shown(sink, |rng, p, row| {
            let (q, fi) = step(rng, p, row);
            (q, q, fi)
        })
    }

    /// [`Self::run`] with a step that gives the orbit's next point and the point to emit apart
    /// (they differ where a flame function re-seeds the orbit).
    #[inline(always)]
    pub(super) fn run_shown(
        self,
        sink: &mut impl PointSink,
        step: impl Fn(&mut Pcg32, Vec3A, &mut u16) -> (Vec3A, Vec3A, usize),
    ) {
        self.run_rows(sink, &mut EachLane(step))
    }

    /// The orbits advanced a step of all the lanes at a time by `step`: the transient steps
    /// not emitted, then the steps into `sink`, [`STEPS_PER_BATCH`] rows a batch.
    #[inline(always)]
    pub(super) fn run_rows(self, sink: &mut impl PointSink, step: &mut impl RowStep) {
        const K: usize = ORBITS_PER_CHUNK;
        let Self { rngs, pos, rows, transient, steps } = self;
        let mut shown = [Vec3A::ZERO; K];
        let mut fs = [0u8; K];
        for _ in 0..transient {
            step.step(Lanes { rngs, pos, rows }, &mut shown, &mut fs);
        }
        let mut out_x = vec![0f32; K * STEPS_PER_BATCH];
        let mut out_y = vec![0f32; K * STEPS_PER_BATCH];
        let mut out_z = vec![0f32; K * STEPS_PER_BATCH];
        let mut out_fn = vec![0u8; K * STEPS_PER_BATCH];
        let mut done = 0;
        while done < steps {
            let batch = STEPS_PER_BATCH.min(steps - done);
            for s in 0..batch {
                step.step(Lanes { rngs, pos, rows }, &mut shown, &mut fs);
                let row = s * K..s * K + K;
                for (k, p) in shown.iter().enumerate() {
                    (out_x[row.start + k], out_y[row.start + k], out_z[row.start + k]) = (p.x, p.y, p.z);
                }
                out_fn[row].copy_from_slice(&fs);
            }
            let n = batch * K;
            sink.consume(PointBatch { x: &out_x[..n], y: &out_y[..n], z: &out_z[..n], functions: &out_fn[..n] });
            done += batch;
        }
    }
}

/// Runs the chaos game of `plan` in parallel: one sink per worker thread made by `make_sink`
/// ([`run_per_thread`]), the sinks merged with `merge` (which must be order-independent for
/// determinism). `progress` is called once per finished chunk.
pub fn run_parallel<S: PointSink + Send>(
    ifs: &CompiledIfs,
    seed: u32,
    frame: u32,
    plan: &ChunkPlan,
    make_sink: impl Fn() -> S + Sync,
    merge: impl Fn(S, S) -> S + Sync + Send,
    progress: impl Fn() + Sync,
) -> S {
    run_per_thread(ifs, seed, frame, plan, 0..plan.chunks(), &make_sink, progress)
        .into_iter()
        .reduce(merge)
        .unwrap_or_else(make_sink)
}

/// Runs chunks `chunks` of `plan` in parallel on the current rayon pool, each worker thread into
/// its own sink, made by `make_sink` when the thread takes its first chunk: at most one sink per
/// thread lives at a time (a fold would make one per split of the work), so memory is bounded by
/// the thread count. Returns the sinks, in thread order. `progress` is called once per finished
/// chunk.
pub fn run_per_thread<S: PointSink + Send>(
    ifs: &CompiledIfs,
    seed: u32,
    frame: u32,
    plan: &ChunkPlan,
    chunks: std::ops::Range<u32>,
    make_sink: impl Fn() -> S + Sync,
    progress: impl Fn() + Sync,
) -> Vec<S> {
    let threads = rayon::current_num_threads().max(1);
    let slots: Vec<std::sync::Mutex<Option<S>>> = (0..threads).map(|_| std::sync::Mutex::new(None)).collect();
    // One chunk per job (about a millisecond of work): rayon otherwise runs a stretch of
    // chunks as one piece that no idle thread can take, and at the end one thread went on
    // alone for tens of milliseconds.
    chunks.into_par_iter().with_max_len(1).for_each(|c| {
        // Inside the pool's workers the index is below the thread count; a thread's slot is
        // only ever taken by that thread, so the lock never waits.
        let slot = rayon::current_thread_index().unwrap_or(0) % threads;
        let mut guard = slots[slot].lock().unwrap_or_else(|e| e.into_inner());
        let sink = guard.get_or_insert_with(&make_sink);
        run_chunk(ifs, seed, frame, c, plan.steps(c), sink);
        drop(guard);
        progress();
    });
    slots.into_iter().filter_map(|s| s.into_inner().unwrap_or_else(|e| e.into_inner())).collect()
}

/// A short deterministic sample of the attractor (16,384 points), for framing and bounds.
pub fn attractor_sample(ifs: &CompiledIfs, seed: u32) -> Vec<Vec3> {
    let mut sink = CollectSink::default();
    for c in 0..4 {
        run_chunk(ifs, seed ^ 0x5eed_b0d5, 0, c, 64, &mut sink);
    }
    sink.points
}

/// Axis-aligned bounds of the attractor from a short deterministic run, or the domain's box if
/// the run gives nothing finite.
pub fn attractor_bounds(ifs: &CompiledIfs, seed: u32) -> (DVec3, DVec3) {
    let mut sink = CollectSink::default();
    for c in 0..4 {
        run_chunk(ifs, seed ^ 0x5eed_b0d5, 0, c, 256, &mut sink);
    }
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in sink.points.iter().filter(|p| p.is_finite()) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (ifs.domain_lo.as_dvec3(), ifs.domain_hi.as_dvec3());
    }
    // A short run can miss thin extremities: pad by 2% of the extent.
    let pad = 0.02 * (hi - lo);
    ((lo - pad).as_dvec3(), (hi + pad).as_dvec3())
}

/// Runs the orbits with the lane kernel, specialized for its multi-cell axes.
fn run_lanes(lanes: &LaneKernel, orbits: Orbits, sink: &mut impl PointSink) {
    match lanes.multi {
        [false, false, false] => run_lanes_for::<false, false, false>(lanes, orbits, sink),
        [false, false, true] => run_lanes_for::<false, false, true>(lanes, orbits, sink),
        [false, true, false] => run_lanes_for::<false, true, false>(lanes, orbits, sink),
        [false, true, true] => run_lanes_for::<false, true, true>(lanes, orbits, sink),
        [true, false, false] => run_lanes_for::<true, false, false>(lanes, orbits, sink),
        [true, false, true] => run_lanes_for::<true, false, true>(lanes, orbits, sink),
        [true, true, false] => run_lanes_for::<true, true, false>(lanes, orbits, sink),
        [true, true, true] => run_lanes_for::<true, true, true>(lanes, orbits, sink),
    }
}

fn run_lanes_for<const MX: bool, const MY: bool, const MZ: bool>(
    lanes: &LaneKernel,
    orbits: Orbits,
    sink: &mut impl PointSink,
) {
    orbits.run(sink, |rng, p, _| {
        let fi = lanes.select(rng.next_u32());
        (lanes.map::<MX, MY, MZ>(fi, p), fi)
    })
}

/// The orbits of one chunk kept between runs (the live view's persistent points on the CPU):
/// lane k's generator and position, as [`continue_chunk`] leaves them. Lane k of chunk c is
/// chain c · [`ORBITS_PER_CHUNK`] + k, seeded as [`run_chunk`] seeds it.
#[derive(Clone, Debug, PartialEq)]
pub struct ChunkChains {
    pub rngs: [Pcg32; ORBITS_PER_CHUNK],
    pub pos: [Vec3A; ORBITS_PER_CHUNK],
    // Palette colour (`chaos_game/color_coord.rs`):
    /// Lane k's colour coordinate (unused in function colour).
    pub colors: [f32; ORBITS_PER_CHUNK],
    /// Lane k's xaos row: its previous function + 1, 0 at the start; always 0 without xaos
    /// ([`super::SelectionTable::row_of`]).
    pub rows: [u16; ORBITS_PER_CHUNK],
}

impl ChunkChains {
    /// Chunk `chunk`'s orbits as [`run_chunk`] starts them: lane k draws from the stream
    /// (seed, frame, chunk · 64 + k) and sits at its start point in the domain, its transient
    /// still to run.
    pub fn start(ifs: &CompiledIfs, seed: u32, frame: u32, chunk: u32) -> Self {
        let first_chain = chunk.wrapping_mul(ORBITS_PER_CHUNK as u32);
        let mut rngs: [Pcg32; ORBITS_PER_CHUNK] =
            std::array::from_fn(|k| Pcg32::for_stream(seed, frame, first_chain.wrapping_add(k as u32)));
        let pos = std::array::from_fn(|k| ifs.start_point(&mut rngs[k]).into());
        Self { rngs, pos, colors: [C_START; ORBITS_PER_CHUNK], rows: [0; ORBITS_PER_CHUNK] }
    }

    /// Restarts lane `lane` of chunk `chunk` as [`Self::start`] starts it for `frame` and runs
    /// its transient at once (not splatted, on the general path: the same points as every
    /// other path), so that it continues on the attractor with the other lanes.
    pub fn restart_lane(&mut self, ifs: &CompiledIfs, seed: u32, frame: u32, chunk: u32, lane: usize) {
        let chain = chunk.wrapping_mul(ORBITS_PER_CHUNK as u32).wrapping_add(lane as u32);
        let mut rng = Pcg32::for_stream(seed, frame, chain);
        let mut p = ifs.start_point(&mut rng);
        let sel = &ifs.selection;
        let mut c = C_START;
        let mut row = 0;
        for _ in 0..ifs.transient {
            let fi = sel.select(sel.row_of(p, row), rng.next_u32());
            sel.step_row(&mut row, fi);
            p = ifs.map_with_rng(fi, p, &mut rng).0;
            if let Some(coords) = &ifs.color_coords {
                c = ifs.step_color_of(c, fi, coords);
            }
        }
        self.rngs[lane] = rng;
        self.pos[lane] = p.into();
        self.colors[lane] = c;
        self.rows[lane] = row;
    }
}

/// Continues the orbits of `chains` (from [`ChunkChains::start`] or an earlier call): `skip`
/// steps not splatted, then `steps` steps into `sink`, on the fastest path; `chains` is left
/// where the orbits end. From `ChunkChains::start(ifs, seed, frame, c)` with `skip` =
/// `ifs.transient` this makes exactly the points of `run_chunk(ifs, seed, frame, c, steps, _)`,
/// and two calls of s₁ and s₂ steps make those of one call of s₁ + s₂.
pub fn continue_chunk(ifs: &CompiledIfs, chains: &mut ChunkChains, skip: u32, steps: usize, sink: &mut impl PointSink) {
    run_chains(ifs, Path::Fastest, chains, skip, steps, sink);
}
