//! Headless GPU rendering: a prepared [`Shot`] into an offscreen texture through the same
//! [`Progressive`] render the viewer's live view draws with, read back as an image (`render --backend gpu`).

use crate::shot::Shot;

use super::progressive::{Progressive, ProgressiveSettings};
use super::{GpuContext, GpuError};

/// Most persistent points a headless render uses; more points mean more frames.
pub const MAX_HEADLESS_POINTS: u32 = 1 << 20;
/// Most steps per frame in a headless render (one submission each).
pub const MAX_HEADLESS_STEPS: u32 = 64;

pub struct GpuRendered {
    pub image: image::RgbImage,
    /// Points splatted (`settings.points` rounded up to whole frames).
    pub splats: u64,
}

/// Runs the chaos game of `ifs` on `live` until `points` points were splatted (rounded up to
/// whole frames); returns the number splatted. The first frame restarts the points.
pub fn accumulate(ctx: &GpuContext, live: &mut Progressive, points: u64) -> u64 {
    let mut splats = 0;
    while splats < points {
        let per_step = live.settings.point_count as u64;
        let steps = (points - splats).div_ceil(per_step).clamp(1, MAX_HEADLESS_STEPS as u64) as u32;
        live.settings.steps_per_frame = steps;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let done = live.advance(ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        if done == 0 {
            break;
        }
        splats += done;
    }
    splats
}

/// The live-view settings for a headless render of `shot`.
pub fn headless_settings(shot: &Shot) -> ProgressiveSettings {
    let settings = &shot.settings;
    ProgressiveSettings {
        point_count: settings.points.clamp(1, MAX_HEADLESS_POINTS as u64) as u32,
        steps_per_frame: 1,
        seed: settings.seed,
        mode: settings.mode,
        depth_cue: settings.depth_cue,
        background: settings.background,
        shading: shot.style.shading,
        occlusion: shot.style.occlusion,
        point_radius_px: shot.style.point_radius_px,
        max_splats: u64::MAX,
        settle_steps: 0,
    }
}

/// Renders `shot` on the GPU: the twin of `render::render_cpu` (same bounds, camera, splat and
/// resolve style; the points come from GPU streams, so the image agrees in distribution, not
/// bit for bit).
pub fn render_gpu(ctx: &GpuContext, shot: &Shot) -> Result<GpuRendered, GpuError> {
    let settings = &shot.settings;
    let mut live = Progressive::new(ctx, headless_settings(shot), settings.width, settings.height)?;
    live.set_ifs(ctx, &shot.compiled, shot.bounds, true);
    live.set_camera(&shot.camera);
    let splats = accumulate(ctx, &mut live, settings.points);
    let image = live.snapshot(ctx)?;
    Ok(GpuRendered { image, splats })
}
