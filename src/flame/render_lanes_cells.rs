//! The lane game's histogram side (`render_lanes.rs`): its 16-byte cells, and the adds that
//! wait for their cells' cache lines.

use super::super::super::render_base::Bucket;
use super::LANES;

/// A histogram cell of the lane game: palette colour sums R, G, B and A, each × 255, on a 16-byte
/// line of its own. The lane game draws only flames whose palette's alpha is 1, where A is the
/// count × 255 as well: [`Cell::bucket`] gives it back in both places.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(16))]
pub(in crate::flame::render) struct Cell([u32; 4]);

impl Cell {
    /// The cell of `b`, its A taken as its count (in linear palette mode the f64 blend of two
    /// alphas of 1 may round A one below the count).
    pub(super) fn of(b: Bucket) -> Self {
        Self([b[0], b[1], b[2], b[4]])
    }

    /// The histogram's bucket.
    pub(in crate::flame::render) fn bucket(self) -> Bucket {
        let [r, g, b, a] = self.0;
        [r, g, b, a, a]
    }

    /// Saturating sums, each channel (a vector add where the CPU has one).
    #[inline(always)]
    pub(in crate::flame::render) fn add(&mut self, inc: &Cell) {
        for k in 0..4 {
            self.0[k] = self.0[k].saturating_add(inc.0[k]);
        }
    }

    /// Asks for the cell's cache line ahead of the add.
    #[inline(always)]
    pub(super) fn prefetch(&self) {
        #[cfg(target_arch = "x86_64")]
        #[expect(unsafe_code, reason = "a prefetch is a hint: it reads nothing and cannot fault")]
        // SAFETY: the pointer is to `self`, a live reference; prefetching never dereferences it.
        unsafe {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            _mm_prefetch::<_MM_HINT_T0>((self as *const Self).cast());
        }
    }
}

/// Where a vector's increments are: an xform's step-palette increments, looked up by entry at
/// the add (no copy of them waits), or the vector's own (linear palette: each colour's blend).
#[derive(Clone, Copy)]
pub(super) enum Increments<'a> {
    Step(&'a [Cell; 256]),
    Own,
}

/// One vector's adds, waiting for their buckets' lines (prefetched): bucket and increment.
pub(super) struct Pending<'a> {
    pub(super) bucket: [u32; LANES],
    pub(super) increments: Increments<'a>,
    /// Each lane's step-palette entry ([`Increments::Step`]).
    pub(super) entry: [u8; LANES],
    /// Each lane's increment ([`Increments::Own`]).
    pub(super) own: [Cell; LANES],
    sink: u32,
}

impl Pending<'_> {
    /// Nothing to add: 0 to the sinks from `sink`.
    fn new(sink: u32) -> Self {
        Self {
            bucket: std::array::from_fn(|l| sink + l as u32),
            increments: Increments::Own,
            entry: [0; LANES],
            own: [Cell::default(); LANES],
            sink,
        }
    }

    /// Adds them; nothing is left to add (the sinks' cells, whatever the increments).
    #[inline(always)]
    fn apply(&mut self, histogram: &mut [Cell]) {
        match self.increments {
            Increments::Step(table) => {
                for (&b, &e) in self.bucket.iter().zip(&self.entry) {
                    histogram[b as usize].add(&table[usize::from(e)]);
                }
            }
            Increments::Own => {
                for (&b, inc) in self.bucket.iter().zip(&self.own) {
                    histogram[b as usize].add(inc);
                }
            }
        }
        self.bucket = std::array::from_fn(|l| self.sink + l as u32);
    }
}

/// Vectors whose adds wait this many vectors for their buckets' lines.
const IN_FLIGHT_VECTORS: usize = 2;

/// The vectors whose adds wait, oldest first from `next`.
pub(super) struct InFlight<'a> {
    vectors: [Pending<'a>; IN_FLIGHT_VECTORS],
    next: usize,
}

impl<'a> InFlight<'a> {
    pub(super) fn new(sink: u32) -> Self {
        Self { vectors: std::array::from_fn(|_| Pending::new(sink)), next: 0 }
    }

    /// The oldest vector's adds done, and its place for the next vector's.
    #[inline(always)]
    pub(super) fn take(&mut self, histogram: &mut [Cell]) -> &mut Pending<'a> {
        let k = self.next % IN_FLIGHT_VECTORS;
        self.next = (k + 1) % IN_FLIGHT_VECTORS;
        self.vectors[k].apply(histogram);
        &mut self.vectors[k]
    }

    /// Every waiting add done.
    pub(super) fn finish(&mut self, histogram: &mut [Cell]) {
        for v in &mut self.vectors {
            v.apply(histogram);
        }
    }
}
