//! The live view's CPU point source: the chaos game's kernels ([`continue_chunk`]) splatted
//! on the CPU into persistent [`Framebuffer`]s (one per rayon worker) and merged; the live view
//! uploads the merged accumulation into the GPU accumulation buffer, which the unchanged resolve
//! pass then draws. Nothing here touches the GPU. On a software adapter
//! (lavapipe) the GPU chaos game costs the same CPU cores several times more than the CPU
//! kernel, so the viewer's `auto` backend takes this route there (docs/performance.md).
//!
//! The points persist across frames, as the GPU route's do: a fixed set of chains (chunks of
//! [`ORBITS_PER_CHUNK`] orbits, [`frame_layout`]), started as [`crate::chaos_game::run_chunk`]
//! starts chunk c of the frame they start in (streams (seed, frame, chain), start points in the
//! domain, the transient not splatted), then advanced about [`CHAIN_STEPS_PER_FRAME`] steps a
//! frame by [`continue_chunk`]. A scene edit or a played key keeps them where they are (the
//! IFS changes, the accumulation is cleared, the next frame skips `settle_steps` before it
//! splats), so the picture re-converges from where the points are; a new scene, a new seed or
//! a new layout (point count, thread count) starts them afresh. A chain that leaves the finite
//! floats or [`chain_bound`] is restarted at the end of the frame ([`ChunkChains::restart_lane`]:
//! a new stream of that frame, its transient run at once). The upload has the GPU layout:
//! closest mode one u32 key per pixel (the buffer's first width × height words, as
//! `shaders/chaos_game.wgsl` and `resolve.wgsl` use it), average and density four u32 per pixel
//! (r, g, b sums and the count), which is `Framebuffer::closest` and `Framebuffer::accum` as
//! they are.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::chaos_game::plan::MAX_CHUNKS;
use crate::chaos_game::{ChunkChains, CompiledIfs, ORBITS_PER_CHUNK, continue_chunk};
use crate::scene::spec::SplatMode;
use crate::splat::{EMPTY, Framebuffer, SplatView};

/// Steps a chain advances per frame, about (the frame's points are spread over whole chunks):
/// long enough that a frame's `settle_steps` after an edit are a small part of it, short
/// enough that a frame has many independent chains (2^20 points: 8,192 chains).
pub const CHAIN_STEPS_PER_FRAME: u64 = 128;
/// Most chunks of chains (2^20 chains); larger frames advance them further instead.
pub const MAX_CHAIN_CHUNKS: u64 = 1 << 14;

/// The chains of a frame of at least `points` points on `workers` workers: the number of
/// chunks (a multiple of `workers`, each worker advancing as many) and the steps each chain
/// advances. The frame splats chunks × [`ORBITS_PER_CHUNK`] × steps points.
pub fn frame_layout(points: u64, workers: usize) -> (u32, usize) {
    let workers = workers.max(1) as u64;
    let per_chunk = ORBITS_PER_CHUNK as u64 * CHAIN_STEPS_PER_FRAME;
    let cap = MAX_CHAIN_CHUNKS.max(workers).min(MAX_CHUNKS / workers * workers);
    let chunks = points.div_ceil(per_chunk).max(1).next_multiple_of(workers).min(cap);
    let steps = points.div_ceil(chunks * ORBITS_PER_CHUNK as u64).max(1);
    (chunks as u32, steps as usize)
}

/// How far from the origin a chain may go before it is restarted: a million times the
/// domain's extent (no view frames that far; a diverging orbit passes it long before the
/// floats run out).
pub fn chain_bound(ifs: &CompiledIfs) -> f32 {
    let extent = ifs.domain_lo.abs().max(ifs.domain_hi.abs()).max_element();
    1e6 * if extent.is_finite() { extent.max(1.0) } else { 1.0 }
}

/// The CPU route's state: the IFS, the persistent chains, the per-worker framebuffers
/// (accumulating since the last clear) and the merged copy that is uploaded. Nothing is
/// allocated per frame except when the view's size or mode or the chains' layout changes.
///
/// The frame runs on a pool of its own (as many threads as rayon's global pool), so that a
/// background job on the global pool (ray trace, recording) shares the cores with the viewer's
/// frames through the OS scheduler instead of queueing them behind its own tasks.
#[derive(Default)]
pub struct CpuChaosGame {
    pool: Option<rayon::ThreadPool>,
    pool_tried: bool,
    ifs: Option<Arc<CompiledIfs>>,
    workers: Vec<Framebuffer>,
    /// Closest mode: the merged keys; other modes: the merged sums (4 u32 per pixel).
    merged: Vec<u32>,
    /// Chunk c's chains at index c; empty until the first frame and after a restart.
    chains: Vec<ChunkChains>,
    /// The seed the chains were started with.
    chains_seed: u32,
    /// Steps the next frame runs without splatting (the transient after a start, the settle
    /// steps after an edit).
    skip_steps: u32,
    /// Chains restarted at the end of the last frame.
    restarted: u64,
    /// The merged shadow map (empty without one).
    merged_shadow: Vec<u32>,
}

impl CpuChaosGame {
    /// Sets the IFS. `restart`: a different scene (the chains start afresh at the next frame);
    /// otherwise an edit: the chains stay where they are and the next frame runs
    /// `settle_steps` (at most the transient) before it splats.
    pub fn set_ifs(&mut self, ifs: &CompiledIfs, restart: bool, settle_steps: u32) {
        self.ifs = Some(Arc::new(ifs.clone()));
        if restart {
            self.restart();
        } else {
            self.skip_steps = self.skip_steps.max(settle_steps.min(ifs.transient));
        }
    }

    /// Starts the chains afresh at the next frame.
    pub fn restart(&mut self) {
        self.chains.clear();
    }

    /// The chains (chunk c at index c), as the last frame left them; empty before the first.
    pub fn chains(&self) -> &[ChunkChains] {
        &self.chains
    }

    /// Chains restarted at the end of the last frame (they left the finite floats or
    /// [`chain_bound`]).
    pub fn restarted_chains(&self) -> u64 {
        self.restarted
    }

    /// Empties the accumulation for `view` (reallocating only when its size or mode changed).
    pub fn clear(&mut self, view: &SplatView) {
        let colors = self.ifs.as_ref().map_or_else(Vec::new, |ifs| ifs.colors.clone());
        let n = rayon::current_num_threads().max(1);
        let fits = |fb: &Framebuffer| {
            fb.view.width == view.width
                && fb.view.height == view.height
                && fb.view.mode == view.mode
                && fb.shadow.len() == view.shadow.map_or(0, |s| s.texels())
        };
        if self.workers.len() != n || !self.workers.iter().all(fits) {
            self.workers = (0..n).map(|_| Framebuffer::new(*view, colors.clone())).collect();
        } else {
            for fb in &mut self.workers {
                fb.view = *view;
                fb.colors.clone_from(&colors);
                fb.closest.fill(EMPTY);
                fb.accum.fill([0; 4]);
                fb.shadow.fill(EMPTY);
            }
        }
        self.merged_shadow.resize(view.shadow.map_or(0, |s| s.texels()), EMPTY);
        let words = view.width as usize * view.height as usize * if view.mode == SplatMode::Closest { 1 } else { 4 };
        self.merged.resize(words, 0);
    }

    /// Advances the chains by a frame of at least `points` points ([`frame_layout`]), splats
    /// them into the worker framebuffers on all rayon threads, merges them and returns the
    /// number of points splatted. `frame` names the random streams of chains started or
    /// restarted in this frame. Call [`Self::clear`] first, and again whenever the view changes.
    pub fn advance(&mut self, seed: u32, frame: u32, points: u64) -> u64 {
        self.advance_within(seed, frame, points, u64::MAX)
    }

    /// [`Self::advance`] with the frame cut to about `at_most` points (whole steps of every
    /// chain, at least one): the chains are laid out for `points` as always, so a smaller frame
    /// advances the same chains fewer steps and never restarts them.
    pub fn advance_within(&mut self, seed: u32, frame: u32, points: u64, at_most: u64) -> u64 {
        let Some(ifs) = self.ifs.clone() else { return 0 };
        if self.workers.is_empty() {
            return 0;
        }
        let workers = self.workers.len();
        let (chunks, steps) = frame_layout(points, workers);
        let steps = steps.min((at_most / (chunks as u64 * ORBITS_PER_CHUNK as u64)).max(1) as usize);
        if self.chains.len() != chunks as usize || self.chains_seed != seed {
            self.chains = (0..chunks).map(|c| ChunkChains::start(&ifs, seed, frame, c)).collect();
            self.chains_seed = seed;
            self.skip_steps = ifs.transient;
        }
        if !self.pool_tried {
            // Without a pool of its own (threads refused) frames run on the global pool.
            self.pool = rayon::ThreadPoolBuilder::new()
                .num_threads(workers)
                .thread_name(|i| format!("nlifs-cpu-route-{i}"))
                .build()
                .ok();
            self.pool_tried = true;
        }
        let per_worker = chunks as usize / workers;
        let skip = self.skip_steps;
        let bound = chain_bound(&ifs);
        let restarted = AtomicU64::new(0);
        let framebuffers = &mut self.workers;
        let chains = &mut self.chains;
        let merged = &mut self.merged;
        let merged_shadow = &mut self.merged_shadow;
        let ifs = &*ifs;
        let mut run = || {
            framebuffers.par_iter_mut().zip(chains.par_chunks_mut(per_worker)).enumerate().for_each(
                |(w, (fb, mine))| {
                    for (i, chain) in mine.iter_mut().enumerate() {
                        continue_chunk(ifs, chain, skip, steps, fb);
                        let chunk = (w * per_worker + i) as u32;
                        for lane in 0..ORBITS_PER_CHUNK {
                            let p = chain.pos[lane];
                            if !(p.is_finite() && p.abs().max_element() <= bound) {
                                chain.restart_lane(ifs, seed, frame, chunk, lane);
                                restarted.fetch_add(1, Ordering::Relaxed);
                            }
                        }
                    }
                },
            );
            merge(framebuffers, merged);
            merge_shadow(framebuffers, merged_shadow);
        };
        match &self.pool {
            Some(pool) => pool.install(run),
            None => run(),
        }
        self.skip_steps = 0;
        self.restarted = restarted.into_inner();
        chunks as u64 * ORBITS_PER_CHUNK as u64 * steps as u64
    }
}

/// Merges the workers' framebuffers into `merged` (min of keys, saturating sums), in parallel
/// over blocks of pixels.
fn merge(workers: &[Framebuffer], merged: &mut [u32]) {
    const BLOCK: usize = 1 << 14;
    if workers[0].view.mode == SplatMode::Closest {
        merged.par_chunks_mut(BLOCK).enumerate().for_each(|(b, out)| {
            let range = b * BLOCK..b * BLOCK + out.len();
            out.copy_from_slice(&workers[0].closest[range.clone()]);
            for fb in &workers[1..] {
                for (o, &k) in out.iter_mut().zip(&fb.closest[range.clone()]) {
                    *o = (*o).min(k);
                }
            }
        });
    } else {
        merged.par_chunks_mut(4 * BLOCK).enumerate().for_each(|(b, out)| {
            let start = b * BLOCK;
            let pixels = out.len() / 4;
            out.copy_from_slice(bytemuck::cast_slice(&workers[0].accum[start..start + pixels]));
            for fb in &workers[1..] {
                let sums: &[u32] = bytemuck::cast_slice(&fb.accum[start..start + pixels]);
                for (o, &s) in out.iter_mut().zip(sums) {
                    *o = o.saturating_add(s);
                }
            }
        });
    }
}

/// Merges the workers' shadow maps into `merged` (min of keys), in parallel over blocks.
fn merge_shadow(workers: &[Framebuffer], merged: &mut [u32]) {
    const BLOCK: usize = 1 << 14;
    merged.par_chunks_mut(BLOCK).enumerate().for_each(|(b, out)| {
        let range = b * BLOCK..b * BLOCK + out.len();
        out.copy_from_slice(&workers[0].shadow[range.clone()]);
        for fb in &workers[1..] {
            for (o, &k) in out.iter_mut().zip(&fb.shadow[range.clone()]) {
                *o = (*o).min(k);
            }
        }
    });
}

impl CpuChaosGame {
    /// The merged shadow map (what the live view uploads with the accumulation).
    pub fn merged_shadow(&self) -> &[u32] {
        &self.merged_shadow
    }

    /// The merged accumulation in the GPU layout (what the live view uploads).
    pub fn merged(&self) -> &[u32] {
        &self.merged
    }
}
