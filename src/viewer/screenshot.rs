//! The view's screenshots: the picture on screen written as a PNG that carries the scene, the
//! time and the live settings, as every picture nlifs writes does.

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
        "points_per_frame": live.point_count,
        "steps_per_frame": live.steps_per_frame,
        "seed": live.seed,
        "shading": live.shading,
        "occlusion": live.occlusion,
        "shadows": live.shadows,
    });
    let provenance = crate::output::Provenance::for_command(&state.scene, state.t_secs, "view", settings);
    crate::output::png::save_rgb8(path, image, Some(&provenance))
}
