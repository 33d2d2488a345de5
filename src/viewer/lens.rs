//! Depth of field in the viewer, the state side: the lens (`aperture`, `focus_distance`) lives
//! in the scene's `[render]` (saved with it, one undo step per change, keys may animate it) and
//! the live view's settings follow the scene at the playhead. Focus by click reads the depth of
//! the nearest splatted point under the cursor from the closest-mode keys
//! ([`focus_depth_at`]); `ui/lens.rs` holds the panel and the gesture.

use crate::edit::Edit;
use crate::splat::{DEPTH_BITS, EMPTY, SplatView};

use super::state::ViewerState;

/// How far (pixels) around the cursor focus picking looks for a splatted point, so that a
/// click between the points of a sparse cloud still finds one.
pub const FOCUS_PICK_RADIUS_PX: i32 = 4;

impl ViewerState {
    /// Sets the scene's lens (one undo step). True when the scene changed; a bad value is an
    /// error message and changes nothing.
    pub(super) fn set_lens(&mut self, aperture: f32, focus_distance: Option<f32>) -> bool {
        if let Err(e) = crate::splat::lens::check(aperture, focus_distance) {
            self.error = Some(format!("depth of field: {e}"));
            return false;
        }
        let r = &self.scene.render;
        if (r.aperture, r.focus_distance) == (aperture, focus_distance) {
            // A preview (a slider drag) may have moved the live view: back to the scene's.
            return self.take_scene_lens();
        }
        let mut after = self.scene.clone();
        after.render.aperture = aperture;
        after.render.focus_distance = focus_distance;
        self.apply_edit(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) })
    }

    /// The live view's lens from the scene at the playhead (after an edit, an undo, a new scene
    /// or a move in time). True when the live settings changed.
    pub fn take_scene_lens(&mut self) -> bool {
        let r = self.scene.render_at(self.t_secs);
        let before = (self.live.draw.aperture, self.live.draw.focus_distance);
        (self.live.draw.aperture, self.live.draw.focus_distance) = (r.aperture, r.focus_distance);
        before != (self.live.draw.aperture, self.live.draw.focus_distance)
    }
}

/// The view distance of the nearest splatted point within [`FOCUS_PICK_RADIUS_PX`] of pixel
/// `cursor_px` (view pixels) in the closest-mode keys `keys` of `view` (one per pixel, row by
/// row): the key's 24-bit depth fraction between the view's near and far distances. None where
/// no point was splatted there.
pub fn focus_depth_at(view: &SplatView, keys: &[u32], cursor_px: [f32; 2]) -> Option<f32> {
    let (w, h) = (view.width as i32, view.height as i32);
    if keys.len() < (w * h) as usize || !(cursor_px[0].is_finite() && cursor_px[1].is_finite()) {
        return None;
    }
    let (cx, cy) = (cursor_px[0].floor() as i32, cursor_px[1].floor() as i32);
    let r = FOCUS_PICK_RADIUS_PX;
    let mut best = EMPTY;
    for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
        for x in (cx - r).max(0)..=(cx + r).min(w - 1) {
            if (x - cx).pow(2) + (y - cy).pow(2) <= r * r {
                best = best.min(keys[(y * w + x) as usize]);
            }
        }
    }
    (best != EMPTY).then(|| {
        let t = (best >> 8) as f32 / ((1u32 << DEPTH_BITS) - 1) as f32;
        view.near + t * (view.far - view.near)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::OrbitCamera;
    use crate::scene::spec::SplatMode;
    use glam::DVec3;

    /// The depth read back from a key is the splatted point's view distance within the key's
    /// quantization ((far − near) / 2^24, here < 1e-6 of the range, plus f32 rounding).
    #[test]
    fn focus_depth_is_the_nearest_key_under_the_cursor() {
        let bounds = (DVec3::ZERO, DVec3::ONE);
        let camera = OrbitCamera::framing(bounds, 3);
        let view = SplatView::new(&camera, 40, 30, bounds, SplatMode::Closest, 0.0, [0.0; 3]);
        let mut fb = crate::splat::Framebuffer::new(view, vec![[1.0; 3]]);
        // The target, and a point on the view axis nearer the eye.
        let near_p = camera.target + 0.2 * (camera.eye() - camera.target);
        let pts = [camera.target, near_p];
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) =
            (pts.iter().map(|p| p.x).collect(), pts.iter().map(|p| p.y).collect(), pts.iter().map(|p| p.z).collect());
        use crate::chaos_game::PointSink;
        fb.consume(crate::chaos_game::PointBatch { x: &x, y: &y, z: &z, functions: &[0, 0] });
        let tol = 1e-5 * (view.far - view.near);
        let centre = [20.0, 15.0];
        // Both project onto the centre pixel: the nearer wins.
        let d = focus_depth_at(&view, &fb.closest, centre).unwrap();
        assert!((d - 0.8 * camera.distance).abs() <= tol, "{d} vs {}", 0.8 * camera.distance);
        // Far from any point: nothing.
        assert_eq!(focus_depth_at(&view, &fb.closest, [2.0, 2.0]), None);
    }
}
