//! The live view's CPU point source: the chaos game of [`crate::chaos_game::run_chunk`] splatted
//! on the CPU into persistent [`Framebuffer`]s (one per rayon worker) and merged; the live view
//! uploads the merged accumulation into the GPU accumulation buffer, which the unchanged resolve
//! pass then draws. Nothing here touches the GPU. On a software adapter
//! (lavapipe) the GPU chaos game costs the same CPU cores several times more than the CPU
//! kernel, so the viewer's `auto` backend takes this route there (docs/performance.md).
//!
//! Every frame runs fresh orbits: chunk c of frame f draws from the streams (seed, f, chain) as
//! [`crate::chaos_game::run_parallel`] does, starts in the domain and discards the IFS's
//! transient, so frames add new points to the accumulation (progressive) instead of advancing
//! persistent ones. The upload has the GPU layout: closest mode one u32 key per pixel (the
//! buffer's first width × height words, as `shaders/chaos_game.wgsl` and `resolve.wgsl` use
//! it), average and density four u32 per pixel (r, g, b sums and the count), which is
//! `Framebuffer::closest` and `Framebuffer::accum` as they are.

use std::sync::Arc;

use rayon::prelude::*;

use crate::chaos_game::plan::{MAX_POINTS, POINTS_PER_CHUNK};
use crate::chaos_game::{ChunkPlan, CompiledIfs, run_chunk};
use crate::scene::spec::SplatMode;
use crate::splat::{EMPTY, Framebuffer, SplatView};

/// The CPU route's state: the IFS, the per-worker framebuffers (accumulating since the last
/// clear) and the merged copy that is uploaded. Nothing is allocated per frame except when the
/// view's size or mode changes.
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
}

impl CpuChaosGame {
    pub fn set_ifs(&mut self, ifs: &CompiledIfs) {
        self.ifs = Some(Arc::new(ifs.clone()));
    }

    /// Empties the accumulation for `view` (reallocating only when its size or mode changed).
    pub fn clear(&mut self, view: &SplatView) {
        let colors = self.ifs.as_ref().map_or_else(Vec::new, |ifs| ifs.colors.clone());
        let n = rayon::current_num_threads().max(1);
        let fits = |fb: &Framebuffer| {
            fb.view.width == view.width && fb.view.height == view.height && fb.view.mode == view.mode
        };
        if self.workers.len() != n || !self.workers.iter().all(fits) {
            self.workers = (0..n).map(|_| Framebuffer::new(*view, colors.clone())).collect();
        } else {
            for fb in &mut self.workers {
                fb.view = *view;
                fb.colors.clone_from(&colors);
                fb.closest.fill(EMPTY);
                fb.accum.fill([0; 4]);
            }
        }
        let words = view.width as usize * view.height as usize * if view.mode == SplatMode::Closest { 1 } else { 4 };
        self.merged.resize(words, 0);
    }

    /// Splats frame `frame` (at least `points` points) into the worker framebuffers on all rayon
    /// threads, merges them and returns the number of points splatted. Call [`Self::clear`]
    /// first, and again whenever the view changes.
    pub fn advance(&mut self, seed: u32, frame: u32, points: u64) -> u64 {
        let Some(ifs) = self.ifs.as_deref() else { return 0 };
        if self.workers.is_empty() {
            return 0;
        }
        let workers = self.workers.len();
        // A frame past the random streams' cap (points × steps beyond ~1.8·10¹³) runs the
        // cap's worth; the view never asks that much, but must not wrap or panic.
        let Ok(plan) = ChunkPlan::even(points.min(MAX_POINTS - workers as u64 * POINTS_PER_CHUNK), workers) else {
            return 0;
        };
        if !self.pool_tried {
            // Without a pool of its own (threads refused) frames run on the global pool.
            self.pool = rayon::ThreadPoolBuilder::new()
                .num_threads(workers)
                .thread_name(|i| format!("nlifs-cpu-route-{i}"))
                .build()
                .ok();
            self.pool_tried = true;
        }
        let framebuffers = &mut self.workers;
        let merged = &mut self.merged;
        let mut run = || {
            framebuffers.par_iter_mut().enumerate().for_each(|(w, fb)| {
                for chunk in plan.iter().skip(w).step_by(workers) {
                    run_chunk(ifs, seed, frame, chunk.index, chunk.steps, fb);
                }
            });
            merge(framebuffers, merged);
        };
        match &self.pool {
            Some(pool) => pool.install(run),
            None => run(),
        }
        plan.splats()
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

impl CpuChaosGame {
    /// The merged accumulation in the GPU layout (what the live view uploads).
    pub fn merged(&self) -> &[u32] {
        &self.merged
    }
}
