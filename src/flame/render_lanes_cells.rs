//! The lane game's histogram side (`render_lanes.rs`): its 16-byte cells, and the adds that
//! wait for their cells' cache lines.

use super::super::super::render_base::{Bucket, HistogramCell};
use super::Lanes;

/// A histogram cell of the lane game: palette colour sums R, G, B and A, each × 255, on a 16-byte
/// line of its own. The lane game draws only flames whose palette's alpha is 1, where A is the
/// count × 255 as well: [`Cell::bucket`] gives it back in both places.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Zeroable)]
#[repr(C, align(16))]
pub(in crate::flame::render) struct Cell([u32; 4]);

impl Cell {
    /// The cell of `b`, its A taken as its count (in linear palette mode the f64 blend of two
    /// alphas of 1 may round A one below the count).
    pub(super) fn of(b: Bucket) -> Self {
        Self([b[0], b[1], b[2], b[4]])
    }

    /// Saturating sums, each channel: the merge of workers' histograms and of cells set aside
    /// ([`Overflow`]); the sum of numbers ≥ 0 saturated once, whatever the grouping.
    pub(in crate::flame::render) fn add_saturating(&mut self, inc: &Cell) {
        for k in 0..4 {
            self.0[k] = self.0[k].saturating_add(inc.0[k]);
        }
    }

    /// Wrapping sums, each channel (one vector add): the chaos game's, which [`Overflow`] keeps
    /// from wrapping.
    #[inline(always)]
    fn add(&mut self, inc: &Cell) {
        for k in 0..4 {
            self.0[k] = self.0[k].wrapping_add(inc.0[k]);
        }
    }

    /// Its largest channel.
    fn largest(self) -> u32 {
        self.0.into_iter().max().unwrap_or(0)
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

impl HistogramCell for Cell {
    /// The histogram's bucket.
    #[inline(always)]
    fn bucket(self) -> Bucket {
        let [r, g, b, a] = self.0;
        [r, g, b, a, a]
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
    pub(super) bucket: Lanes<u32>,
    pub(super) increments: Increments<'a>,
    /// Each lane's step-palette entry ([`Increments::Step`]).
    pub(super) entry: Lanes<u8>,
    /// Each lane's increment ([`Increments::Own`]).
    pub(super) own: Lanes<Cell>,
}

impl Pending<'_> {
    /// Nothing to add: 0 to the sinks from `sink`.
    fn new(sink: u32) -> Self {
        Self {
            bucket: Lanes(std::array::from_fn(|l| sink + l as u32)),
            increments: Increments::Own,
            entry: Lanes::splat(0),
            own: Lanes::splat(Cell::default()),
        }
    }

    /// Adds them, once: [`InFlight::take`]'s caller writes the next vector's in their place.
    #[inline(always)]
    fn apply(&self, histogram: &mut [Cell]) {
        // Each bucket is a cell of the histogram by construction; clamped again here, with four
        // vector instructions, the adds need no bounds check each (a compare and a branch).
        let last = u32::try_from(histogram.len().saturating_sub(1)).unwrap_or(u32::MAX);
        let bucket = self.bucket.0.map(|b| b.min(last));
        let cells = histogram.as_mut_ptr();
        #[expect(unsafe_code, reason = "adds to cells whose indices were clamped to the histogram")]
        match self.increments {
            Increments::Step(table) => {
                for (&b, &e) in bucket.iter().zip(self.entry.iter()) {
                    // SAFETY: b ≤ `last` < histogram.len() (clamped above; the histogram has
                    // its lanes' sink cells, so it is not empty); `cells` comes from the
                    // `&mut` histogram, which nothing else reads or writes during the adds.
                    unsafe { (*cells.add(b as usize)).add(&table[usize::from(e)]) };
                }
            }
            Increments::Own => {
                for (&b, inc) in bucket.iter().zip(self.own.iter()) {
                    // SAFETY: as above.
                    unsafe { (*cells.add(b as usize)).add(inc) };
                }
            }
        }
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

    /// The oldest vector's adds done, and its place for the next vector's, which the caller
    /// writes whole (bucket, increments and entries or own increments).
    #[inline(always)]
    pub(super) fn take(&mut self, histogram: &mut [Cell]) -> &mut Pending<'a> {
        let k = self.next % IN_FLIGHT_VECTORS;
        self.next = (k + 1) % IN_FLIGHT_VECTORS;
        self.vectors[k].apply(histogram);
        &mut self.vectors[k]
    }

    /// Every waiting add done.
    pub(super) fn finish(self, histogram: &mut [Cell]) {
        for v in &self.vectors {
            v.apply(histogram);
        }
    }
}

/// Keeps a worker's wrapping cells ([`Cell::add`]) from wrapping: every [`Self::window`] samples
/// at most, the cells that the next window's adds could carry past `u32::MAX` are moved aside
/// (set to 0, their sums kept in u64), and given back saturated at the end. The sums are those of
/// saturating adds, in fewer instructions (a wrapping add is one vector add, a saturating one
/// three).
#[derive(Clone)]
pub(super) struct Overflow {
    /// Samples between checks.
    window: u64,
    /// A cell with a channel above this is moved aside at a check.
    limit: u32,
    /// Samples since the last check.
    since: u64,
    aside: Vec<(usize, [u64; 4])>,
}

impl Overflow {
    /// For increments of at most `largest` a channel; `None` where a block of `block` samples
    /// could carry a cell from 0 past 2^31.
    pub(super) fn new(largest: u32, block: u64) -> Option<Self> {
        let window = (1u64 << 31) / u64::from(largest.max(1));
        (window >= block).then(|| Self {
            window,
            limit: u32::MAX - (window * u64::from(largest.max(1))) as u32,
            since: 0,
            aside: Vec::new(),
        })
    }

    /// Before a block of `samples`: a check where the window would close within it.
    #[inline(always)]
    pub(super) fn before_block(&mut self, samples: u64, histogram: &mut [Cell]) {
        if self.since + samples > self.window {
            self.set_aside(histogram);
            self.since = 0;
        }
        self.since += samples;
    }

    #[inline(never)]
    fn set_aside(&mut self, histogram: &mut [Cell]) {
        for (i, cell) in histogram.iter_mut().enumerate() {
            if cell.largest() > self.limit {
                self.aside.push((i, cell.0.map(u64::from)));
                *cell = Cell::default();
            }
        }
    }

    /// The cells set aside given back, each channel's sum saturated.
    pub(super) fn finish(self, histogram: &mut [Cell]) {
        for (i, sums) in self.aside {
            let back = Cell(sums.map(|v| u32::try_from(v).unwrap_or(u32::MAX)));
            histogram[i].add_saturating(&back);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wrapping adds with checks between blocks sum as saturating adds do, where cells pass
    /// `u32::MAX` and where they do not.
    #[test]
    fn overflow_keeps_saturating_sums() {
        let (largest, block) = (1 << 20, 1000);
        let mut overflow = Overflow::new(largest, block).expect("a window of two blocks");
        let mut wrapping = vec![Cell::default(); 3];
        let mut saturating = wrapping.clone();
        let increments = [Cell([largest, 1, 0, largest]), Cell([7, largest / 3, 0, 1]), Cell([0, 0, 5, 2])];
        let mut rng = crate::rng::Pcg32::for_stream(1, 2, 3);
        for _ in 0..15 {
            overflow.before_block(block, &mut wrapping);
            for _ in 0..block {
                let i = (rng.next_u32() % 3) as usize;
                wrapping[i].add(&increments[i]);
                saturating[i].add_saturating(&increments[i]);
            }
        }
        overflow.finish(&mut wrapping);
        assert_eq!(wrapping, saturating);
        assert_eq!(saturating[0].0[0], u32::MAX, "the test passes u32::MAX");
        assert!(saturating[1].0[1] < u32::MAX);
        assert!(Overflow::new(1 << 11, 1 << 21).is_none(), "a block could pass 2^31");
    }
}
