//! The lane game's arrays (`render_lanes.rs`): [`LANES`] values on cache lines of their own, and
//! the quantities of a step's points.

use super::LANES;
use crate::flame::variations_lanes::{DRAWS, Point32};

/// [`LANES`] values on cache lines of their own: the phases of a step store their vectors and
/// the next phase loads them, and a vector access that spans two lines costs more (aligned to 16
/// bytes only, all of a step's arrays spanned lines, or none did, as the stack happened to fall).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(super) struct Lanes<T = f32>(pub(super) [T; LANES]);

impl<T: Copy> Lanes<T> {
    #[inline(always)]
    pub(super) fn splat(v: T) -> Self {
        Self([v; LANES])
    }
}

impl<T> std::ops::Deref for Lanes<T> {
    type Target = [T; LANES];
    #[inline(always)]
    fn deref(&self) -> &[T; LANES] {
        &self.0
    }
}

impl<T> std::ops::DerefMut for Lanes<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T; LANES] {
        &mut self.0
    }
}

#[expect(unsafe_code, reason = "f32 lanes as plain bytes, for the queues' flat view")]
// SAFETY: `Lanes<f32>` is `repr(C)` around [f32; LANES], 4 × 64 bytes: a multiple of its
// alignment, so it has no padding, and every bit pattern is an f32.
unsafe impl bytemuck::Zeroable for Lanes<f32> {}
#[expect(unsafe_code, reason = "f32 lanes as plain bytes, for the queues' flat view")]
// SAFETY: as above; it is `Copy` and `'static`.
unsafe impl bytemuck::Pod for Lanes<f32> {}

impl<'a, T> IntoIterator for &'a Lanes<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    #[inline(always)]
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

/// The terms' random numbers, a [`Lanes`] each.
#[repr(C, align(64))]
pub(super) struct Draws(pub(super) [[f32; LANES]; DRAWS]);

/// [`Point32`]'s quantities of the lanes, one array each (so that loops over them are vector
/// loops).
pub(super) struct PointLanes {
    pub(super) x: Lanes,
    pub(super) y: Lanes,
    pub(super) r2: Lanes,
    pub(super) r: Lanes,
    pub(super) a: Lanes,
    pub(super) sa: Lanes,
    pub(super) ca: Lanes,
    pub(super) ayx: Lanes,
}

impl Default for PointLanes {
    fn default() -> Self {
        let zero = Lanes::splat(0.0);
        Self { x: zero, y: zero, r2: zero, r: zero, a: zero, sa: zero, ca: zero, ayx: zero }
    }
}

impl PointLanes {
    #[inline(always)]
    pub(super) fn lane(&self, l: usize) -> Point32 {
        Point32 {
            x: self.x[l],
            y: self.y[l],
            r2: self.r2[l],
            r: self.r[l],
            a: self.a[l],
            sa: self.sa[l],
            ca: self.ca[l],
            ayx: self.ayx[l],
        }
    }
}
