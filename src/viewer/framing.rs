//! Framing for the viewer: the attractor (and, for `Shift+F`, the grid box) fitted into the view
//! rectangle with a margin. A viewer helper rather than a change to `shot::frame_camera`
//! (which `nlifs render` shares): the viewer frames from a larger sample, because the 16,384
//! points of one `attractor_sample` miss thin extremities (plant 1's stem was cut off at the
//! bottom of the view), and leaves a wider margin, because its picture keeps accumulating
//! points in the tails that a sample never reaches.

use glam::{DVec3, Vec3};

use crate::camera::OrbitCamera;
use crate::chaos_game::{self, CompiledIfs};
use crate::scene::Scene;

/// Extra distance beyond `OrbitCamera::fit_points` (which leaves 5%): the sample's extent then
/// covers at most 1 / (1.05 · 1.07) ≈ 89% of the view along its tighter axis.
pub const EXTRA_MARGIN: f32 = 0.07;

/// Seeds of the samples the framing sample joins.
const SAMPLES: u32 = 4;

/// A sample of the attractor for framing: [`SAMPLES`] deterministic samples from different
/// seeds, joined (65,536 points).
pub fn framing_sample(ifs: &CompiledIfs, seed: u32) -> Vec<Vec3> {
    (0..SAMPLES)
        .flat_map(|k| chaos_game::attractor_sample(ifs, seed.wrapping_add(k.wrapping_mul(0x9e37_79b9))))
        .collect()
}

/// Fits `camera` (its angles and projection kept) around `points` in a view of `aspect`, with
/// the viewer's margin.
pub fn fit(camera: &mut OrbitCamera, points: &[Vec3], aspect: f32) {
    camera.fit_points(points, aspect);
    camera.distance *= 1.0 + EXTRA_MARGIN;
}

/// The scene's camera at `t_secs`, fitted around `sample` where the scene leaves target and
/// distance open (the same rule as `nlifs render`), with the viewer's margin. A camera the scene
/// places (an imported flame's) frames the render's image, `[render] width` × `height`: in a view
/// narrower than that image it moves back until the image's width fits, as Blender's camera view
/// shows the whole frame, instead of cutting off its sides.
pub fn scene_camera(scene: &Scene, t_secs: f64, bounds: (DVec3, DVec3), sample: &[Vec3], aspect: f32) -> OrbitCamera {
    let mut camera = crate::shot::frame_camera(scene, t_secs, bounds, sample, aspect);
    let spec = scene.camera_at(t_secs);
    if spec.target.is_none() && spec.distance.is_none() {
        if !sample.is_empty() {
            camera.distance *= 1.0 + EXTRA_MARGIN;
        }
    } else {
        let render_aspect = scene.render.width as f32 / scene.render.height.max(1) as f32;
        if aspect > 0.0 && aspect < render_aspect {
            camera.distance *= render_aspect / aspect;
        }
    }
    camera
}

/// The eight corners of a box.
pub fn box_corners((lo, hi): (DVec3, DVec3)) -> impl Iterator<Item = Vec3> {
    (0..8).map(move |k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
        .as_vec3()
    })
}
