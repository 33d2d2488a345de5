//! flam3's camera as the flame chaos game (`render.rs`) uses it: from a point of the plane to
//! its bucket of the supersampled histogram.

use super::Flame;
use super::render_base::whole_u32;
use super::render_layout::Layout;

/// flam3's camera: pixels per unit scale·2^zoom, rotation about the center, +y down; maps a
/// point of the plane to its bucket.
pub(super) struct Camera {
    pub bounds: [f64; 4],
    /// Buckets per unit and the first bucket's offset, each axis.
    pub x_scale: f64,
    pub x_offset: f64,
    pub y_scale: f64,
    pub y_offset: f64,
    pub rotation: Option<[[f64; 2]; 2]>,
    pub center: [f64; 2],
    pub hist_width: usize,
    pub hist_height: usize,
}

impl Camera {
    pub fn new(flame: &Flame, layout: &Layout) -> Self {
        let ppu = flame.scale * 2f64.powf(flame.zoom);
        let gutter_units = layout.gutter as f64 / (layout.oversample as f64 * ppu);
        let corner =
            [flame.center[0] - layout.width as f64 / ppu / 2.0, flame.center[1] - layout.height as f64 / ppu / 2.0];
        let bounds = [
            corner[0] - gutter_units,
            corner[1] - gutter_units,
            corner[0] + layout.width as f64 / ppu + gutter_units,
            corner[1] + layout.height as f64 / ppu + gutter_units,
        ];
        let x_scale = layout.hist_width as f64 / (bounds[2] - bounds[0]);
        let y_scale = layout.hist_height as f64 / (bounds[3] - bounds[1]);
        let rotation = (flame.rotate != 0.0).then(|| {
            let (s, c) = flame.rotate.to_radians().sin_cos();
            [[c, -s], [s, c]]
        });
        Self {
            bounds,
            x_scale,
            x_offset: x_scale * bounds[0],
            y_scale,
            y_offset: y_scale * bounds[1],
            rotation,
            center: flame.center,
            hist_width: layout.hist_width,
            hist_height: layout.hist_height,
        }
    }

    /// The bucket of `p` and whether `p` is in view; out of view the bucket is some bucket
    /// of the histogram (the chaos game adds nothing there), so that no branch is needed.
    #[cfg_attr(not(test), expect(dead_code, reason = "the chaos game rotates and buckets in loops of their own"))]
    #[inline(always)]
    pub fn bucket(&self, p: [f64; 2]) -> (usize, bool) {
        let p = match &self.rotation {
            Some(r) => self.rotate(r, p),
            None => p,
        };
        let (b, inside) = self.bucket_of_rotated(p);
        (b as usize, inside)
    }

    /// `p` rotated by `rotation` (the camera's) about the center.
    #[inline(always)]
    pub fn rotate(&self, r: &[[f64; 2]; 2], p: [f64; 2]) -> [f64; 2] {
        let d = [p[0] - self.center[0], p[1] - self.center[1]];
        [d[0] * r[0][0] + d[1] * r[0][1] + self.center[0], d[0] * r[1][0] + d[1] * r[1][1] + self.center[1]]
    }

    /// [`Self::bucket`] of a point already rotated.
    #[inline(always)]
    pub fn bucket_of_rotated(&self, [x, y]: [f64; 2]) -> (u32, bool) {
        let b = &self.bounds;
        let inside = (x >= b[0]) & (y >= b[1]) & (x <= b[2]) & (y <= b[3]);
        // In view the scaled coordinates are ≥ 0 (truncated toward 0 as flam3 does); out of
        // view (NaN included, which converts to 0) the clamps keep the bucket in the histogram.
        // On the far edge (x = bounds[2]) flam3 steps into the next row; this stays in the last.
        // Clamped before the truncation (NaN: `max` gives 0), which gives what truncating and
        // then clamping gives, and converted by `whole_u32`, so that a loop of them is a vector
        // loop. The buckets number below 2^32 (`render_layout.rs`).
        let i = whole_u32((self.x_scale * x - self.x_offset).max(0.0).min(self.hist_width as f64 - 1.0));
        let j = whole_u32((self.y_scale * y - self.y_offset).max(0.0).min(self.hist_height as f64 - 1.0));
        (i + j * self.hist_width as u32, inside)
    }
}
