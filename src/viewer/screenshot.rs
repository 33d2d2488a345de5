//! The view's screenshots: the picture on screen written as a PNG that carries the scene, the
//! time and the live settings, as every picture nlifs writes does. The picture is read back
//! when its copy maps: at once on the desktop, a few frames later in the browser
//! (`platform::run_async`), where the PNG becomes a download.

use std::path::PathBuf;

use super::{Command, Gfx, ViewerState, recent};
use crate::gpu::GpuError;
use crate::platform::Pending;

/// A screenshot on its way: where it goes, and its picture once read back.
pub(super) type PendingShot = (PathBuf, Pending<Result<image::RgbImage, GpuError>>);

/// Starts the screenshot of the view on screen for `path` (a redraw comes when it is read).
pub(super) fn start(gfx: &mut Gfx, path: PathBuf) -> PendingShot {
    let window = gfx.window.clone();
    let image = crate::platform::run_async(gfx.live.snapshot_start(&gfx.ctx).image(), move || window.request_redraw());
    (path, image)
}

/// Saves the screenshot on its way once its picture is there, and says where it went.
pub(super) fn finish(state: &mut ViewerState, shot: &mut Option<PendingShot>) {
    let Some(image) = shot.as_ref().and_then(|(_, image)| image.take()) else { return };
    let Some((path, _)) = shot.take() else { return };
    let message = match image {
        Ok(image) => match save_screenshot(state, &path, &image) {
            // Where it went, in full (F12 names the file itself).
            Ok(()) => format!("saved the screenshot {}", recent::absolute(&path).display()),
            Err(e) => e.to_string(),
        },
        Err(e) => format!("screenshot failed: {e}"),
    };
    state.apply([Command::SetToast(Some(message.clone()))]);
    state.message = Some(message);
}

/// Writes a screenshot of the view with the scene, time and live settings inside (as every PNG
/// nlifs writes), so that `nlifs view` reopens it.
pub(super) fn save_screenshot(
    state: &super::state::ViewerState,
    path: &std::path::Path,
    image: &image::RgbImage,
) -> Result<(), crate::output::OutputError> {
    let live = &state.live;
    let settings = serde_json::json!({
        "width": image.width(),
        "height": image.height(),
        "points_per_frame": live.draw.point_count,
        "steps_per_frame": live.draw.steps_per_frame,
        "seed": live.draw.seed,
        "shading": live.draw.shading,
        "occlusion": live.draw.occlusion,
        "shadows": live.draw.shadows,
    });
    let provenance = crate::output::Provenance::for_command(&state.scene, state.t_secs, "view", settings);
    crate::output::png::save_rgb8(path, image, Some(&provenance))
}
