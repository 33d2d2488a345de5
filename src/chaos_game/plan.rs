//! How a chaos game of n points splits into chunks: the one [`ChunkPlan`] that every CPU run
//! (render, record, export, bench) follows, so the chunks, their steps and their random streams
//! are the same wherever the points are made.
//!
//! Chunk `c` runs [`ORBITS_PER_CHUNK`] orbits, and orbit `k` of it is chain
//! `c · ORBITS_PER_CHUNK + k`, which names its random stream (seed, frame, chain). Chains are
//! u32 (as the GPU's), so a plan has at most 2^32 / [`ORBITS_PER_CHUNK`] chunks; a point count
//! that needs more is refused with [`PlanError::TooManyPoints`] rather than reusing streams.
//! All arithmetic is u64, so no count wraps on the way to that check.

use super::{ORBITS_PER_CHUNK, STEPS_PER_ORBIT};

/// Points one full chunk makes.
pub const POINTS_PER_CHUNK: u64 = (ORBITS_PER_CHUNK * STEPS_PER_ORBIT) as u64;
/// Most chunks a plan has: their chains 0..MAX_CHUNKS · ORBITS_PER_CHUNK fill the u32 range.
pub const MAX_CHUNKS: u64 = (u32::MAX as u64 + 1) / ORBITS_PER_CHUNK as u64;
/// Most points a plan makes (2^44 with 64 orbits of 4096 steps).
pub const MAX_POINTS: u64 = MAX_CHUNKS * POINTS_PER_CHUNK;

#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PlanError {
    #[error(
        "{points} points are more than the chaos game's {max} distinct random streams can draw (at most {max_points} points)",
        max = MAX_CHUNKS * ORBITS_PER_CHUNK as u64,
        max_points = MAX_POINTS
    )]
    TooManyPoints { points: u64 },
}

/// The chunks of a run: chunk `c` in `0..chunks()` runs [`Self::steps`]`(c)` steps per orbit.
/// All chunks but the last run the same steps; the last may run fewer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkPlan {
    /// Points asked for (the plan makes at least this many, see [`Self::splats`]).
    points: u64,
    chunks: u32,
    steps: usize,
    last_steps: usize,
}

/// One chunk of a plan: its index (which names its streams) and its steps per orbit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chunk {
    pub index: u32,
    pub steps: usize,
}

impl ChunkPlan {
    /// The plan for `points` points: full chunks of [`STEPS_PER_ORBIT`] steps and a last chunk
    /// with the rest, so the run makes `points` rounded up to a multiple of [`ORBITS_PER_CHUNK`]
    /// (at least one step per orbit, so 0 points make one step of one chunk).
    pub fn new(points: u64) -> Result<Self, PlanError> {
        let chunks = points.div_ceil(POINTS_PER_CHUNK).max(1);
        if chunks > MAX_CHUNKS {
            return Err(PlanError::TooManyPoints { points });
        }
        let last_points = points - (chunks - 1) * POINTS_PER_CHUNK;
        let last_steps = last_points.div_ceil(ORBITS_PER_CHUNK as u64).max(1);
        Ok(Self { points, chunks: chunks as u32, steps: STEPS_PER_ORBIT, last_steps: last_steps as usize })
    }

    /// A plan of equal chunks for `workers` workers taking every `workers`-th chunk: the chunk
    /// count is a multiple of `workers` (each runs the same number), every chunk runs the same
    /// steps, at most [`STEPS_PER_ORBIT`], and the run makes at least `points` points. (The live
    /// view's CPU route keeps persistent chains instead: `live::cpu_source::frame_layout`.)
    pub fn even(points: u64, workers: usize) -> Result<Self, PlanError> {
        let workers = workers.max(1) as u64;
        let chunks = points.div_ceil(POINTS_PER_CHUNK).max(1).next_multiple_of(workers);
        if chunks > MAX_CHUNKS {
            return Err(PlanError::TooManyPoints { points });
        }
        let steps = points.div_ceil(chunks * ORBITS_PER_CHUNK as u64).max(1) as usize;
        Ok(Self { points, chunks: chunks as u32, steps, last_steps: steps })
    }

    /// Points asked for.
    pub fn points(&self) -> u64 {
        self.points
    }

    pub fn chunks(&self) -> u32 {
        self.chunks
    }

    /// Steps per orbit of chunk `chunk` (after the transient).
    pub fn steps(&self, chunk: u32) -> usize {
        if chunk + 1 == self.chunks { self.last_steps } else { self.steps }
    }

    /// The chunks in index order.
    pub fn iter(&self) -> impl Iterator<Item = Chunk> + use<> {
        let plan = *self;
        (0..self.chunks).map(move |index| Chunk { index, steps: plan.steps(index) })
    }

    /// Points the run makes: every orbit of every chunk, all its steps (≥ [`Self::points`]).
    pub fn splats(&self) -> u64 {
        let orbits = ORBITS_PER_CHUNK as u64;
        (self.chunks as u64 - 1) * orbits * self.steps as u64 + orbits * self.last_steps as u64
    }

    /// Points chunks `chunks` make (those past the plan's end make none).
    pub fn splats_of(&self, chunks: std::ops::Range<u32>) -> u64 {
        let full = chunks.start..chunks.end.min(self.chunks.saturating_sub(1)).max(chunks.start);
        let last = u64::from(chunks.contains(&(self.chunks - 1)));
        let orbits = ORBITS_PER_CHUNK as u64;
        orbits * (u64::from(full.end - full.start) * self.steps as u64 + last * self.last_steps as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunking every render used before the plan, for the counts where it did not wrap.
    fn old_chunking(points: u64) -> (u32, usize, usize) {
        let per_chunk = (ORBITS_PER_CHUNK * STEPS_PER_ORBIT) as u64;
        let chunks = points.div_ceil(per_chunk).max(1);
        let last_points = points - (chunks - 1) * per_chunk;
        let last_steps = (last_points as usize).div_ceil(ORBITS_PER_CHUNK).max(1);
        (chunks as u32, STEPS_PER_ORBIT, last_steps)
    }

    fn counts() -> Vec<u64> {
        let k = ORBITS_PER_CHUNK as u64;
        let mut out = vec![0, 1, 2, k - 1, k, k + 1, 1000, 300_000, 2_000_000, 1 << 30];
        for c in [1, 2, 3, 7, MAX_CHUNKS - 1, MAX_CHUNKS] {
            out.extend([c * POINTS_PER_CHUNK - 1, c * POINTS_PER_CHUNK, c * POINTS_PER_CHUNK + 1]);
        }
        out.retain(|&n| n <= MAX_POINTS);
        out
    }

    #[test]
    fn same_chunks_as_before() {
        for n in counts() {
            let plan = ChunkPlan::new(n).unwrap();
            let (chunks, steps, last) = old_chunking(n);
            assert_eq!(plan.chunks(), chunks, "{n}");
            for c in [0, chunks / 2, chunks.saturating_sub(2), chunks - 1] {
                assert_eq!(plan.steps(c), if c + 1 == chunks { last } else { steps }, "{n} chunk {c}");
            }
            let splats = plan.splats();
            assert!(splats >= n && splats < n.max(1) + ORBITS_PER_CHUNK as u64, "{n}: {splats}");
        }
    }

    #[test]
    fn iter_lists_every_chunk_with_its_steps() {
        let plan = ChunkPlan::new(3 * POINTS_PER_CHUNK + 100).unwrap();
        let chunks: Vec<Chunk> = plan.iter().collect();
        assert_eq!(chunks.len(), 4);
        assert!(chunks.iter().enumerate().all(|(i, c)| c.index == i as u32));
        assert_eq!(
            chunks.iter().map(|c| c.steps).collect::<Vec<_>>(),
            [STEPS_PER_ORBIT; 3].iter().copied().chain([2]).collect::<Vec<_>>()
        );
        assert_eq!(plan.splats(), chunks.iter().map(|c| c.steps as u64 * ORBITS_PER_CHUNK as u64).sum::<u64>());
    }

    /// The last chain of the largest plan is u32::MAX; one more chunk would wrap to chain 0.
    #[test]
    fn refuses_counts_whose_streams_would_wrap() {
        let plan = ChunkPlan::new(MAX_POINTS).unwrap();
        let last_chain = (plan.chunks() as u64 - 1) * ORBITS_PER_CHUNK as u64 + ORBITS_PER_CHUNK as u64 - 1;
        assert_eq!(last_chain, u32::MAX as u64);
        for n in [MAX_POINTS + 1, u64::MAX / 2, u64::MAX] {
            assert_eq!(ChunkPlan::new(n), Err(PlanError::TooManyPoints { points: n }));
        }
        assert!(ChunkPlan::even(MAX_POINTS, 3).is_err(), "rounding up to the workers must not wrap");
        assert!(ChunkPlan::new(u64::MAX).unwrap_err().to_string().contains("random streams"));
    }

    /// Equal plans split over workers.
    #[test]
    fn even_plans_split_over_workers() {
        for n in counts() {
            for workers in [0, 1, 2, 3, 8, 64] {
                let Ok(plan) = ChunkPlan::even(n, workers) else {
                    assert!(n > MAX_POINTS - 64 * POINTS_PER_CHUNK, "{n} {workers}");
                    continue;
                };
                let w = workers.max(1) as u64;
                let chunks = n.div_ceil(POINTS_PER_CHUNK).max(1).next_multiple_of(w);
                let steps = n.div_ceil(chunks * ORBITS_PER_CHUNK as u64).max(1);
                assert_eq!(plan.chunks() as u64, chunks, "{n} {workers}");
                assert!(plan.iter().all(|c| c.steps as u64 == steps), "{n} {workers}");
                assert!(steps <= STEPS_PER_ORBIT as u64);
                assert!(plan.splats() >= n && plan.splats() < n.max(1) + chunks * ORBITS_PER_CHUNK as u64);
            }
        }
    }
}
