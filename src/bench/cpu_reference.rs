//! The batched reference of `nlifs bench cpu`: the chaos game and the closest-mode splat written
//! the plain way, the row nlifs's own figures are set against in the same run.
//!
//! Sixteen chains are mapped [`ROUNDS`] rounds at a time into a buffer of 16 · 64 points (16 KiB,
//! in the L1 cache), each step scalar code: the selection of
//! [`SelectionTable::select`](crate::chaos_game::SelectionTable::select) and the scalar map with
//! the cell search by bins ([`CompiledIfs::map_fast`], no vector instructions); then the
//! buffer is projected without branches (a point outside the image goes to a spare pixel past
//! the image's) and each key is merged into its pixel with a scalar `min` store. The chains are
//! nlifs's chains (chain k of chunk c draws from the stream (seed, frame, 64c + k), from its
//! start point and through its transient) and each step's arithmetic is the one the fast kernels
//! reproduce bit for bit, so the reference's keys are nlifs's closest-mode framebuffer, byte for
//! byte (a test checks it): the two rows compare two ways of computing the same image. Points
//! carry their function (no palette colour) and there is no shadow map.

use glam::Vec3;

use crate::chaos_game::{ChunkChains, CompiledIfs, ORBITS_PER_CHUNK, PointBatch, PointSink};
use crate::splat::{DEPTH_BITS, EMPTY, SplatView};

/// Chains mapped together.
pub const CHAINS: usize = 16;
/// Steps of the chains mapped into the buffer before it is splatted.
pub const ROUNDS: usize = 64;

/// The buffer of one batch: `ROUNDS` rows of `CHAINS` points.
pub struct Buffer {
    x: [f32; CHAINS * ROUNDS],
    y: [f32; CHAINS * ROUNDS],
    z: [f32; CHAINS * ROUNDS],
    function: [u8; CHAINS * ROUNDS],
}

/// The reference's closest-mode keys: one per pixel of `view`, and a spare one past them where
/// points outside the image go.
pub struct ReferenceKeys {
    pub view: SplatView,
    /// width · height keys, then the spare.
    keys: Vec<u32>,
}

impl ReferenceKeys {
    pub fn new(view: SplatView) -> Self {
        Self { view, keys: vec![EMPTY; view.width as usize * view.height as usize + 1] }
    }

    /// The image's keys (without the spare), row-major as [`crate::splat::Framebuffer::closest`].
    pub fn image(&self) -> &[u32] {
        &self.keys[..self.keys.len() - 1]
    }

    /// Merges the points of `batch` into the keys: a projection without branches, then a
    /// scalar `min` store per point.
    fn splat(&mut self, batch: PointBatch<'_>) {
        let v = &self.view;
        let m = v.pixel_from_world;
        let (width, height) = (v.width as f32, v.height as f32);
        let inv_range = 1.0 / (v.far - v.near);
        let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
        let spare = self.keys.len() - 1;
        for (i, &function) in batch.functions.iter().enumerate() {
            // SplatView::project's arithmetic, in its order.
            let q = m * Vec3::new(batch.x[i], batch.y[i], batch.z[i]).extend(1.0);
            let inv_w = 1.0 / q.w;
            let (x, y) = (q.x * inv_w, q.y * inv_w);
            // `&`, not `&&`: one mask, no branch (NaN fails every compare).
            let inside = (q.w > 0.0) & (x >= 0.0) & (y >= 0.0) & (x < width) & (y < height);
            let t = ((q.z - v.near) * inv_range).clamp(0.0, 1.0);
            let d = t * scale;
            let d = if d > 0.0 { d } else { 0.0 };
            let key = (d as u32) << 8 | function as u32;
            // Saturating casts: any value is safe to compute; only inside points use them.
            let pixel = (y as u32 as usize) * v.width as usize + x as u32 as usize;
            let pixel = if inside { pixel } else { spare };
            let slot = &mut self.keys[pixel];
            *slot = (*slot).min(key);
        }
    }
}

/// What a batch of mapped points goes to.
pub trait BufferSink {
    fn take(&mut self, buffer: &Buffer, n: usize);
}

impl BufferSink for ReferenceKeys {
    fn take(&mut self, buffer: &Buffer, n: usize) {
        self.splat(PointBatch {
            x: &buffer.x[..n],
            y: &buffer.y[..n],
            z: &buffer.z[..n],
            functions: &buffer.function[..n],
        });
    }
}

/// The reference's splat behind nlifs's chaos game (its batches of 64 chains × 16 steps).
impl PointSink for ReferenceKeys {
    fn consume(&mut self, batch: PointBatch<'_>) {
        self.splat(batch);
    }
}

/// Map only: keeps the last point of each batch alive, so that mapping is not optimized away.
#[derive(Default)]
pub struct Discard {
    pub acc: Vec3,
}

impl BufferSink for Discard {
    fn take(&mut self, buffer: &Buffer, n: usize) {
        if let Some(i) = n.checked_sub(1) {
            self.acc += Vec3::new(buffer.x[i], buffer.y[i], buffer.z[i]);
        }
    }
}

/// Runs chunk `chunk` of a chaos game (its 64 chains, `steps` points each after the transient)
/// the reference's way into `sink`: the chains in groups of [`CHAINS`], each group's steps
/// [`ROUNDS`] at a time.
pub fn run_chunk(ifs: &CompiledIfs, seed: u32, frame: u32, chunk: u32, steps: usize, sink: &mut impl BufferSink) {
    let chains = ChunkChains::start(ifs, seed, frame, chunk);
    let sel = &ifs.selection;
    let adaptive = sel.cells != [1, 1, 1];
    let step = |rng: &mut crate::rng::Pcg32, p: Vec3| -> (Vec3, usize) {
        let cell = if adaptive { sel.cell_of(p) } else { 0 };
        let fi = sel.select(cell, rng.next_u32());
        (ifs.map_fast(fi, p), fi)
    };
    let mut buffer = Buffer {
        x: [0.0; CHAINS * ROUNDS],
        y: [0.0; CHAINS * ROUNDS],
        z: [0.0; CHAINS * ROUNDS],
        function: [0; CHAINS * ROUNDS],
    };
    for group in 0..ORBITS_PER_CHUNK / CHAINS {
        let lanes = group * CHAINS..group * CHAINS + CHAINS;
        let mut rngs: [crate::rng::Pcg32; CHAINS] = std::array::from_fn(|k| chains.rngs[lanes.start + k]);
        let mut pos: [Vec3; CHAINS] = std::array::from_fn(|k| Vec3::from(chains.pos[lanes.start + k]));
        for _ in 0..ifs.transient {
            for (rng, p) in rngs.iter_mut().zip(pos.iter_mut()) {
                *p = step(rng, *p).0;
            }
        }
        let mut done = 0;
        while done < steps {
            let rounds = ROUNDS.min(steps - done);
            for round in 0..rounds {
                for (k, (rng, p)) in rngs.iter_mut().zip(pos.iter_mut()).enumerate() {
                    let (q, fi) = step(rng, *p);
                    *p = q;
                    let i = round * CHAINS + k;
                    (buffer.x[i], buffer.y[i], buffer.z[i], buffer.function[i]) = (q.x, q.y, q.z, fi as u8);
                }
            }
            sink.take(&buffer, rounds * CHAINS);
            done += rounds;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::scene::spec::{RenderSettings, SplatMode};
    use crate::shot::{Framing, Shot};
    use crate::splat::Framebuffer;

    /// The reference's keys, behind its own chaos game or nlifs's, are nlifs's closest-mode
    /// framebuffer byte for byte (tolerance 0: the same chains, the same arithmetic), for a paper scene with 3D grid maps and a 2D one, with
    /// a step count that leaves a last batch of fewer than 64 rounds.
    #[test]
    fn reference_keys_are_the_closest_framebuffer() {
        for name in ["tapering", "plant2"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
            let scene = Scene::load(&path).expect("paper scene");
            let settings = RenderSettings { width: 320, height: 200, points: 300_000, seed: 3, ..scene.render.clone() };
            let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Scene, None).expect("shot");
            let view = SplatView { mode: SplatMode::Closest, shadow: None, ..shot.view };
            let mut fb = Framebuffer::new(view, shot.compiled.colors.clone());
            let mut keys = ReferenceKeys::new(view);
            let mut behind_nlifs = ReferenceKeys::new(view);
            let last_steps = shot.plan.steps(shot.plan.chunks() - 1);
            assert!(shot.plan.chunks() > 1 && !last_steps.is_multiple_of(ROUNDS), "{name}: {last_steps} steps");
            for c in shot.plan.iter() {
                crate::chaos_game::run_chunk(&shot.compiled, 3, 0, c.index, c.steps, &mut fb);
                run_chunk(&shot.compiled, 3, 0, c.index, c.steps, &mut keys);
                crate::chaos_game::run_chunk(&shot.compiled, 3, 0, c.index, c.steps, &mut behind_nlifs);
            }
            assert!(fb.covered_pixels() > 2000, "{name}: {}", fb.covered_pixels());
            assert!(keys.image() == fb.closest.as_slice(), "{name}");
            assert!(behind_nlifs.image() == fb.closest.as_slice(), "{name}");
        }
    }
}
