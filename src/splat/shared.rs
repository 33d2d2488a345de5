//! One framebuffer shared by every thread of a render, so that a render's memory is its
//! framebuffer's and does not grow with the thread count (per-thread framebuffers, merged at the
//! end, take one copy per thread: 8.7 GB for 8192² in density mode with 8 threads).
//!
//! The framebuffer is cut into bands of consecutive pixels, each with a lock. A thread does not
//! write pixels one by one: its [`BandWriter`] keeps a small buffer of pending updates per band
//! (pixel and key, or pixel and colour) and, when one fills, takes that band's lock and applies
//! them all. The updates are the splat's own (a `min` of keys, saturating sums, both
//! order-independent: a saturating sum of non-negative terms is min(total, u32::MAX) in any
//! order), so the framebuffer holds the same integers as the per-thread framebuffers merged, byte
//! for byte. Applying a buffer touches one band (a few MiB at most), so it runs from the caches;
//! the pending buffers take a few MiB per thread.
//!
//! The pixels are viewed as atomics while threads write them, with relaxed loads and stores
//! (plain moves on x86): the band's lock orders the writers, and the atomics keep that safe Rust.
//! The unsafe cast of the framebuffer's `u32`s to atomics is this module's one allowance.
#![expect(unsafe_code, reason = "viewing the framebuffer's u32s as AtomicU32s (same size, alignment and validity)")]

use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

use super::{EMPTY, Framebuffer, Pixels, SplatMode, SplatView, splat_into};
use crate::chaos_game::{PointBatch, PointSink};

/// Pending updates a [`BandWriter`] buffers per band before applying them.
const PENDING_PER_BAND: usize = 256;
/// Largest band, in bytes of the framebuffer (small enough to stay in the caches while a
/// buffer is applied).
const MAX_BAND_BYTES: u64 = 2 << 20;
/// Smallest band, in pixels.
const MIN_BAND_PIXELS: u64 = 1024;

const _: () = assert!(std::mem::size_of::<AtomicU32>() == std::mem::size_of::<u32>());
const _: () = assert!(std::mem::align_of::<AtomicU32>() == std::mem::align_of::<u32>());

/// Bytes of one [`BandWriter`]'s buffers for a render of `view` by `threads` threads.
pub fn writer_bytes(view: &SplatView, threads: usize) -> u64 {
    let (bands, _) = bands_of(view, threads);
    let words = if view.mode == SplatMode::Closest { 2 } else { 4 };
    bands as u64 * (PENDING_PER_BAND as u64 * words * 4 + 4)
}

/// The band count and log2 of the pixels per band for a render of `view` by `threads` threads:
/// many more bands than threads (little waiting for locks), each at most [`MAX_BAND_BYTES`].
fn bands_of(view: &SplatView, threads: usize) -> (usize, u32) {
    let pixels = view.width as u64 * view.height as u64;
    let bytes_per_pixel = if view.mode == SplatMode::Closest { 4 } else { 16 };
    let wanted = (pixels / (16 * threads.max(1) as u64)).clamp(MIN_BAND_PIXELS, MAX_BAND_BYTES / bytes_per_pixel);
    let band_shift = 63 - wanted.leading_zeros();
    (pixels.div_ceil(1 << band_shift).max(1) as usize, band_shift)
}

/// A framebuffer that threads splat into at the same time through [`BandWriter`]s (see the
/// module comment). [`Self::into_framebuffer`] gives the framebuffer back.
pub struct SharedFramebuffer {
    framebuffer: Framebuffer,
}

impl SharedFramebuffer {
    /// An empty shared framebuffer of `view`.
    pub fn new(view: SplatView, colors: Vec<[f32; 3]>) -> Self {
        let mut framebuffer = Framebuffer::new(view, colors);
        framebuffer.touch_pages();
        Self { framebuffer }
    }

    /// Runs `work` with a [`SharedTarget`] of this framebuffer for `threads` writers; when it
    /// returns (every writer flushed), the framebuffer holds all their updates.
    pub fn splat_with<R>(&mut self, threads: usize, work: impl FnOnce(&SharedTarget<'_>) -> R) -> R {
        let fb = &mut self.framebuffer;
        let words: &mut [u32] = match fb.view.mode {
            SplatMode::Closest => &mut fb.closest,
            SplatMode::Average | SplatMode::Density => bytemuck::cast_slice_mut(&mut fb.accum),
        };
        // SAFETY: AtomicU32 has the size, alignment (asserted above) and bit validity of u32,
        // and `words` is borrowed exclusively for the target's lifetime, so nothing reads or
        // writes these u32s except through the atomics meanwhile.
        let atomics: &[AtomicU32] = unsafe { &*(words as *mut [u32] as *const [AtomicU32]) };
        let shadow: &mut [u32] = &mut fb.shadow;
        // SAFETY: as above, for the shadow map's u32s (a separate exclusive borrow).
        let shadow: &[AtomicU32] = unsafe { &*(shadow as *mut [u32] as *const [AtomicU32]) };
        let mut target = SharedTarget::new(fb.view, &fb.colors, atomics, threads);
        target.shadow = shadow;
        work(&target)
    }

    /// The framebuffer with every flushed update.
    pub fn into_framebuffer(self) -> Framebuffer {
        self.framebuffer
    }
}

/// The pixels of a [`SharedFramebuffer`] while threads write them: atomics in locked bands.
pub struct SharedTarget<'a> {
    view: SplatView,
    colors: &'a [[f32; 3]],
    /// Closest mode: one key per pixel; otherwise r, g, b, count per pixel.
    words: &'a [AtomicU32],
    bands: Vec<Mutex<()>>,
    /// Pixels per band: 2^band_shift.
    band_shift: u32,
    /// The shadow map's keys (empty without shadows), lowered with `fetch_min`: no bands, as a
    /// converged map is mostly read (a key is only written where it lowers the texel's).
    shadow: &'a [AtomicU32],
}

impl<'a> SharedTarget<'a> {
    fn new(view: SplatView, colors: &'a [[f32; 3]], words: &'a [AtomicU32], threads: usize) -> Self {
        let (count, band_shift) = bands_of(&view, threads);
        Self { view, colors, words, bands: (0..count).map(|_| Mutex::new(())).collect(), band_shift, shadow: &[] }
    }

    /// A writer for one thread.
    pub fn writer(&self) -> BandWriter<'_, 'a> {
        let stride = self.entry_words();
        BandWriter {
            target: self,
            pending: vec![0; self.bands.len() * PENDING_PER_BAND * stride],
            fill: vec![0; self.bands.len()],
        }
    }

    /// Bands of this target (for tests and the memory estimate).
    pub fn bands(&self) -> usize {
        self.bands.len()
    }

    /// u32s per pending update: pixel and key, or pixel and r, g, b (the count adds 1).
    fn entry_words(&self) -> usize {
        if self.view.mode == SplatMode::Closest { 2 } else { 4 }
    }

    /// Applies `entries` (pending updates of band `band`) under the band's lock.
    fn apply(&self, band: usize, entries: &[u32]) {
        // A poisoned lock only means another writer panicked; the integers are still whole.
        let _guard = self.bands[band].lock().unwrap_or_else(|e| e.into_inner());
        let words = self.words;
        if self.view.mode == SplatMode::Closest {
            for e in entries.chunks_exact(2) {
                let slot = &words[e[0] as usize];
                if e[1] < slot.load(Ordering::Relaxed) {
                    slot.store(e[1], Ordering::Relaxed);
                }
            }
        } else {
            for e in entries.chunks_exact(4) {
                let base = 4 * e[0] as usize;
                for (c, &add) in [e[1], e[2], e[3], 1].iter().enumerate() {
                    let slot = &words[base + c];
                    let a = slot.load(Ordering::Relaxed);
                    slot.store(a.saturating_add(add), Ordering::Relaxed);
                }
            }
        }
    }
}

/// One thread's way into a [`SharedTarget`]: a [`PointSink`] that buffers its updates per band
/// and applies a band's when they fill it. [`Self::flush`] applies the rest; a writer dropped
/// without it flushes on drop.
pub struct BandWriter<'t, 'a> {
    target: &'t SharedTarget<'a>,
    /// Per band, PENDING_PER_BAND entries of `entry_words` u32s.
    pending: Vec<u32>,
    /// Per band, entries pending.
    fill: Vec<u32>,
}

impl BandWriter<'_, '_> {
    /// Applies every pending update.
    pub fn flush(&mut self) {
        let stride = self.target.entry_words();
        for band in 0..self.fill.len() {
            let n = self.fill[band] as usize;
            if n > 0 {
                let start = band * PENDING_PER_BAND * stride;
                self.target.apply(band, &self.pending[start..start + n * stride]);
                self.fill[band] = 0;
            }
        }
    }

    #[inline(always)]
    fn push(&mut self, pixel: usize, entry: impl FnOnce(&mut [u32])) {
        let stride = self.target.entry_words();
        let band = pixel >> self.target.band_shift;
        let n = self.fill[band] as usize;
        let start = (band * PENDING_PER_BAND + n) * stride;
        let slot = &mut self.pending[start..start + stride];
        slot[0] = pixel as u32;
        entry(slot);
        if n + 1 == PENDING_PER_BAND {
            let first = band * PENDING_PER_BAND * stride;
            self.target.apply(band, &self.pending[first..first + PENDING_PER_BAND * stride]);
            self.fill[band] = 0;
        } else {
            self.fill[band] = n as u32 + 1;
        }
    }
}

impl Pixels for BandWriter<'_, '_> {
    #[inline(always)]
    fn min_key(&mut self, pixel: usize, key: u32) {
        // The vector splat sends the empty key for points outside the image, and a key not
        // below the pixel's present one cannot lower it (keys only fall): nothing to do. Once
        // the picture converges, most points end here, with one read.
        if key != EMPTY && key < self.target.words[pixel].load(Ordering::Relaxed) {
            self.push(pixel, |e| e[1] = key);
        }
    }

    #[inline(always)]
    fn add(&mut self, pixel: usize, add: [u32; 4]) {
        debug_assert_eq!(add[3], 1);
        self.push(pixel, |e| e[1..4].copy_from_slice(&add[..3]));
    }
}

impl PointSink for BandWriter<'_, '_> {
    fn consume(&mut self, batch: PointBatch<'_>) {
        let target = self.target;
        splat_into(&target.view, target.colors, batch, self);
        if let Some(shadow_view) = &target.view.shadow {
            let map = target.shadow;
            super::shadow::splat_shadow(shadow_view, batch.x, batch.y, batch.z, |texel, key| {
                if key < map[texel].load(Ordering::Relaxed) {
                    map[texel].fetch_min(key, Ordering::Relaxed);
                }
            });
        }
    }
}

impl Drop for BandWriter<'_, '_> {
    fn drop(&mut self) {
        self.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::OrbitCamera;
    use crate::rng::Pcg32;
    use crate::splat::OwnPixels;
    use glam::DVec3;

    fn view(mode: SplatMode) -> SplatView {
        let bounds = (DVec3::ZERO, DVec3::ONE);
        SplatView::new(&OrbitCamera::framing(bounds, 3), 300, 200, bounds, mode, 0.5, [0.0; 3])
    }

    /// Updates through two writers (several bands, buffers filled and flushed many times, sums
    /// driven past u32::MAX) leave the integers that the same updates leave in a framebuffer of
    /// its own (tolerance 0).
    #[test]
    fn writers_apply_what_a_framebuffer_would() {
        for mode in SplatMode::ALL {
            let mut own = Framebuffer::new(view(mode), vec![[1.0; 3]]);
            let mut shared = SharedFramebuffer::new(view(mode), vec![[1.0; 3]]);
            let mut r = Pcg32::for_stream(9, 1, 2);
            let updates: Vec<(usize, u32, [u32; 4])> = (0..50_000)
                .map(|i| {
                    // A few hot pixels take huge sums, so that they saturate.
                    let pixel = if i % 7 == 0 { i % 3 } else { r.next_u32() as usize % 60_000 };
                    let big = if i % 7 == 0 { u32::MAX / 3 } else { r.next_u32() % 256 };
                    (pixel, r.next_u32() >> 4, [big, r.next_u32() % 256, r.next_u32(), 1])
                })
                .collect();
            shared.splat_with(2, |target| {
                assert!(target.bands() > 4, "{}", target.bands());
                let (mut a, mut b) = (target.writer(), target.writer());
                for (i, &(pixel, key, add)) in updates.iter().enumerate() {
                    let w = if i % 2 == 0 { &mut a } else { &mut b };
                    if mode == SplatMode::Closest { w.min_key(pixel, key) } else { w.add(pixel, add) }
                }
                a.flush();
                // `b` flushes when dropped.
            });
            let mut pixels = OwnPixels { closest: &mut own.closest, accum: &mut own.accum };
            for &(pixel, key, add) in &updates {
                if mode == SplatMode::Closest { pixels.min_key(pixel, key) } else { pixels.add(pixel, add) }
            }
            let shared = shared.into_framebuffer();
            assert!(shared.closest == own.closest && shared.accum == own.accum, "{mode:?}");
            if mode != SplatMode::Closest {
                assert_eq!(shared.accum[0][0], u32::MAX, "the hot pixel saturates");
            }
        }
    }
}
