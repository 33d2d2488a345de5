//! The colour coordinate (`[render] color = "palette"`, flam3's rule): each compiled function
//! i has a coordinate c_i in [0, 1] and an orbit's c becomes (c + c_i) / 2 at every step; the
//! point is emitted with the palette entry `palette::index_of(c)` in place of its function
//! index, so that the splats, the resolve and the exports need no change (the colour table is
//! the palette's 256 entries).
//!
//! c is a function of the orbit's sequence of functions only, so it is carried here, on the
//! batches every kernel emits (row s of a batch is step s of the chunk's 64 orbits, lane k at
//! s · 64 + k, on every path), and not inside each kernel: the scalar, lane, AVX2 and AVX-512
//! kernels stay as they are, function colour keeps its speed, and the coordinate is the same on
//! every path because the function indices are. To let c forget its start the orbits' discarded
//! steps run as emitted rows that this sink updates c with and drops: [`ColorCoordSink::new`]
//! with `skip` rows. c starts at [`C_START`]; after the transient (≥ 24 steps) its start
//! weighs less than 2^-24.
//!
//! A flame function (`chaos_game/flame.rs`) has its own colour speed s and the step is flam3's
//! c' = s·c_i + (1 − s)·c ([`step_color_speed`]). With a final xform the point is drawn with
//! s_f·c_f + (1 − s_f)·c, the final xform's step, while the orbit keeps c; a point that the
//! final xform left as it was (its opacity) comes with [`FINAL_LEFT_OUT`] in its function index
//! and is drawn with c.
//!
//! The GPU twin is the palette branch of `shaders/chaos_game.wgsl` (the same update in f32,
//! the same quantization; the colour speeds from the flame table's headers).

use super::sink::{PointBatch, PointSink};
use super::{ORBITS_PER_CHUNK, STEPS_PER_BATCH};
use crate::palette;

/// The bit of an emitted point's function index that says the final xform left the point as it
/// was (its opacity's draw; set by `chaos_game/flame.rs`), so that this sink draws the orbit's
/// colour coordinate and not the final's step. Set only where the colour is the palette's
/// (otherwise the index is the function's colour, which the final xform does not change); an
/// IFS of more than [`FINAL_LEFT_OUT`] functions draws its final xform always (the bit would be
/// a function's).
pub(super) const FINAL_LEFT_OUT: u8 = 0x80;

/// Whether the function indices of an IFS of `functions` compiled functions leave the bit
/// [`FINAL_LEFT_OUT`] free (at most 128 functions).
pub(super) fn final_flag_fits(functions: usize) -> bool {
    functions <= FINAL_LEFT_OUT as usize
}

/// Colour speed ½ for every function (the step (c + c_i) / 2, bit for bit).
const HALF_SPEEDS: [f32; 256] = [0.5; 256];

/// The colour coordinate of an orbit at its start point.
pub const C_START: f32 = 0.5;

/// One step of the colour coordinate: (c + c_i) / 2 in f32 (the shader's expression).
#[inline(always)]
pub fn step_color(c: f32, c_i: f32) -> f32 {
    (c + c_i) * 0.5
}

/// One step of the colour coordinate with colour speed `s` (a flame function's; flam3's
/// c' = s·c_i + (1 − s)·c).
#[inline(always)]
pub fn step_color_speed(c: f32, c_i: f32, s: f32) -> f32 {
    s * c_i + (1.0 - s) * c
}

/// Wraps a sink: turns the function indices of a chunk's batches into quantized colour
/// coordinates, dropping the first `skip` rows (see the module comment).
pub(super) struct ColorCoordSink<'a, S: PointSink> {
    /// c_i by function index, padded to every u8 (no bounds checks in the loop).
    coords: Box<[f32; 256]>,
    /// The colour speed by function index (flame functions'), when a function has one.
    speeds: Option<Box<[f32; 256]>>,
    /// The final xform's colour coordinate and speed: the drawn coordinate is its step of c.
    final_color: Option<(f32, f32)>,
    /// What of a function index is the function's: all but [`FINAL_LEFT_OUT`] where the IFS
    /// has few enough functions for the flag, else all.
    function_bits: u8,
    c: &'a mut [f32; ORBITS_PER_CHUNK],
    skip: usize,
    inner: &'a mut S,
    /// The drawn coordinate of each point of a batch, then its palette entry.
    drawn: Vec<f32>,
    indices: Vec<u8>,
    /// flam3's linear palette mode (`palette::index_linear`), else the step.
    linear: bool,
}

impl<'a, S: PointSink> ColorCoordSink<'a, S> {
    pub(super) fn new(
        coords: &[f32],
        speeds: Option<&[f32]>,
        final_color: Option<(f32, f32)>,
        c: &'a mut [f32; ORBITS_PER_CHUNK],
        skip: usize,
        inner: &'a mut S,
    ) -> Self {
        let function_bits = if final_flag_fits(coords.len()) { !FINAL_LEFT_OUT } else { u8::MAX };
        let coords = Box::new(std::array::from_fn(|i| coords.get(i).copied().unwrap_or(0.0)));
        let speeds = speeds.map(|s| Box::new(std::array::from_fn(|i| s.get(i).copied().unwrap_or(0.5))));
        let drawn = vec![0.0; ORBITS_PER_CHUNK * STEPS_PER_BATCH];
        let indices = vec![0; ORBITS_PER_CHUNK * STEPS_PER_BATCH];
        Self { coords, speeds, final_color, function_bits, c, skip, inner, drawn, indices, linear: false }
    }

    /// This sink drawing flam3's linear palette interpolation (`linear`), dithered by each
    /// point's position ([`palette::dither_of`]).
    pub(super) fn interpolated(self, linear: bool) -> Self {
        Self { linear, ..self }
    }
}

impl<S: PointSink> PointSink for ColorCoordSink<'_, S> {
    fn consume(&mut self, batch: PointBatch<'_>) {
        const K: usize = ORBITS_PER_CHUNK;
        let rows = batch.len() / K;
        debug_assert_eq!(rows * K, batch.len(), "batches are whole rows of the chunk's orbits");
        let dropped = self.skip.min(rows);
        self.skip -= dropped;
        if self.indices.len() < batch.len() {
            self.indices.resize(batch.len(), 0);
            self.drawn.resize(batch.len(), 0.0);
        }
        // On copies, so that the compiler sees that c, the table and the output do not alias.
        let (mut c, coords) = (*self.c, &*self.coords);
        let drawn = &mut self.drawn[..batch.len()];
        match (self.speeds.as_deref(), self.final_color) {
            (speeds, Some((c_f, s_f))) => {
                let speeds = speeds.unwrap_or(&HALF_SPEEDS);
                let bits = self.function_bits;
                for (fs, out) in batch.functions.chunks_exact(K).zip(drawn.chunks_exact_mut(K)) {
                    for ((c, &f), out) in c.iter_mut().zip(fs).zip(out) {
                        let i = (f & bits) as usize;
                        *c = step_color_speed(*c, coords[i], speeds[i]);
                        *out = if f & !bits == 0 { step_color_speed(*c, c_f, s_f) } else { *c };
                    }
                }
            }
            (None, None) => {
                for (fs, out) in batch.functions.chunks_exact(K).zip(drawn.chunks_exact_mut(K)) {
                    for ((c, &f), out) in c.iter_mut().zip(fs).zip(out) {
                        *c = step_color(*c, coords[f as usize]);
                        *out = *c;
                    }
                }
            }
            (Some(speeds), None) => {
                for (fs, out) in batch.functions.chunks_exact(K).zip(drawn.chunks_exact_mut(K)) {
                    for ((c, &f), out) in c.iter_mut().zip(fs).zip(out) {
                        *c = step_color_speed(*c, coords[f as usize], speeds[f as usize]);
                        *out = *c;
                    }
                }
            }
        }
        let indices = &mut self.indices[..batch.len()];
        if self.linear {
            for (((out, &c), &x), &y) in indices.iter_mut().zip(&*drawn).zip(batch.x).zip(batch.y) {
                *out = palette::index_linear(c, palette::dither_of(x, y, c));
            }
        } else {
            for (out, &c) in indices.iter_mut().zip(&*drawn) {
                *out = palette::index_of(c);
            }
        }
        *self.c = c;
        let kept = dropped * K..batch.len();
        if !kept.is_empty() {
            self.inner.consume(PointBatch {
                x: &batch.x[kept.clone()],
                y: &batch.y[kept.clone()],
                z: &batch.z[kept.clone()],
                functions: &self.indices[kept],
            });
        }
    }
}
