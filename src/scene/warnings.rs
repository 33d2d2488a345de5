//! The warnings that every command prints about what it draws, in one place so that `info`,
//! `render`, `record` and `snapshot` say the same: a function that may not be contractive or
//! that leaves the grid (so the attractor may be unbounded, blank or cut), and a picture in
//! which nothing of the attractor landed. Each is a sentence without the `warning: ` prefix,
//! which the command line adds.

use crate::color;
use crate::model::IfsReport;
use crate::scene::Scene;
use crate::scene::timeline_check::TimelineCheck;

/// The warnings of one resolved IFS: per enabled function, a Lipschitz bound ≥ 1 (the chaos
/// game may diverge) and transformed grid points outside the grid (the attractor may leave it).
pub fn ifs_warnings(report: &IfsReport) -> Vec<String> {
    let mut out = Vec::new();
    for f in &report.functions {
        if let Some(l) = f.lipschitz_bound
            && l >= 1.0
        {
            out.push(format!("{} may not be contractive (Lipschitz bound {l:.4} ≥ 1)", f.name));
        }
        if f.contained == Some(false) {
            out.push(format!(
                "{} is not contained: {} of its transformed grid points lie outside the grid",
                f.name,
                f.outside.len()
            ));
        }
    }
    out
}

/// [`ifs_warnings`] of `scene` at `t_secs`, for its enabled functions.
pub fn scene_warnings(scene: &Scene, t_secs: f64) -> Vec<String> {
    let ifs = scene.at(t_secs);
    let mut report = ifs.report();
    report.functions.retain(|f| ifs.functions.iter().any(|g| g.name == f.name && g.enabled));
    ifs_warnings(&report)
}

/// The problems a timeline check found, one sentence each.
pub fn timeline_warnings(check: &TimelineCheck) -> Vec<String> {
    check.problems.iter().map(|p| p.to_string()).collect()
}

/// How many pixels of `image` differ from the background `background` (linear RGB): the
/// pixels some point or surface landed on.
pub fn covered_pixels(image: &image::RgbImage, background: [f32; 3]) -> usize {
    let bg = background.map(color::linear_to_srgb8);
    image.pixels().filter(|p| p.0 != bg).count()
}

/// A warning when nothing landed in the picture, else None.
pub fn coverage_warning(image: &image::RgbImage, background: [f32; 3]) -> Option<String> {
    (covered_pixels(image, background) == 0).then(|| {
        "the picture is empty: no point of the attractor landed in it (the camera looks away from it, \
         or the IFS diverges; `nlifs info` shows its contractivity)"
            .to_string()
    })
}

/// What `render` prints after drawing `scene` at `t_secs` into `image` over `background`: the
/// scene's warnings, then how many pixels were drawn or that none were.
pub fn after_render(scene: &Scene, t_secs: f64, image: &image::RgbImage, background: [f32; 3]) -> Vec<String> {
    let mut out = scene_warnings(scene, t_secs);
    out.extend(coverage_warning(image, background));
    out
}

/// What `record` prints before drawing: the warnings along the whole timeline when the scene
/// is animated (the check of `nlifs info`), else those of the still scene.
pub fn before_record(scene: &Scene) -> Vec<String> {
    match crate::scene::timeline_check::check_timeline(scene, TIMELINE_SAMPLES_PER_INTERVAL) {
        Some(check) => timeline_warnings(&check),
        None => scene_warnings(scene, 0.0),
    }
}

/// Samples strictly between neighbouring keys for the timeline check (`info`, `record`).
pub const TIMELINE_SAMPLES_PER_INTERVAL: usize = 8;
