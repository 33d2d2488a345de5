//! Where the chaos game's points go: batches of points as structure of arrays ([`PointBatch`])
//! handed to a [`PointSink`] (a framebuffer's splat, a collector, a benchmark's counter).

use glam::Vec3;

/// A batch of mapped points as structure of arrays (what vector code reads and writes best):
/// point i is (x[i], y[i], z[i]), mapped by compiled function `functions[i]`. All four slices
/// have the same length.
#[derive(Clone, Copy, Debug)]
pub struct PointBatch<'a> {
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
    pub functions: &'a [u8],
}

impl PointBatch<'_> {
    pub fn len(&self) -> usize {
        self.functions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.functions.is_empty()
    }

    #[inline(always)]
    pub fn point(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.len()).map(|i| self.point(i))
    }
}

/// Receives mapped points in batches.
pub trait PointSink {
    fn consume(&mut self, batch: PointBatch<'_>);
}

/// Collects points (used by export and tests).
#[derive(Default)]
pub struct CollectSink {
    pub points: Vec<Vec3>,
    pub functions: Vec<u8>,
}

impl PointSink for CollectSink {
    fn consume(&mut self, batch: PointBatch<'_>) {
        self.points.extend(batch.points());
        self.functions.extend_from_slice(batch.functions);
    }
}
