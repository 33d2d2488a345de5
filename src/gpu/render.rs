//! Headless GPU rendering: a scene at a time into an offscreen texture through the same
//! [`Progressive`] render the viewer's live view draws with, read back as an image (`render --backend gpu`).

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::chaos_game::{self, CompiledIfs};
use crate::scene::Scene;
use crate::scene::spec::RenderSettings;

use super::progressive::{Progressive, ProgressiveSettings};
use super::{GpuContext, GpuError};

/// Most persistent points a headless render uses; more points mean more frames.
pub const MAX_HEADLESS_POINTS: u32 = 1 << 20;
/// Most steps per frame in a headless render (one submission each).
pub const MAX_HEADLESS_STEPS: u32 = 64;

pub struct GpuRendered {
    pub image: image::RgbImage,
    pub camera: OrbitCamera,
    pub bounds: (DVec3, DVec3),
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

/// The live-view settings for a headless render of `settings`.
pub fn headless_settings(settings: &RenderSettings) -> ProgressiveSettings {
    ProgressiveSettings {
        point_count: settings.points.clamp(1, MAX_HEADLESS_POINTS as u64) as u32,
        steps_per_frame: 1,
        seed: settings.seed,
        mode: settings.mode,
        depth_cue: settings.depth_cue,
        background: settings.background,
        shading: 0.0,
        point_radius_px: 0,
        max_splats: u64::MAX,
        settle_steps: 0,
    }
}

/// Renders `scene` at `t_secs` on the GPU: the twin of `render::render_cpu` (same bounds,
/// camera and splat; the points come from GPU streams, so the image agrees in distribution,
/// not bit for bit).
pub fn render_gpu(
    ctx: &GpuContext,
    scene: &Scene,
    t_secs: f64,
    settings: &RenderSettings,
    camera: Option<OrbitCamera>,
) -> Result<GpuRendered, GpuError> {
    let ifs = scene.at(t_secs);
    let compiled = CompiledIfs::new(&ifs).ok_or(GpuError::NoFunctions)?;
    let bounds = chaos_game::attractor_bounds(&compiled, settings.seed);
    let camera = camera.unwrap_or_else(|| {
        let sample = chaos_game::attractor_sample(&compiled, settings.seed);
        crate::render::frame_camera(scene, t_secs, bounds, &sample, settings.width as f32 / settings.height as f32)
    });
    let mut live = Progressive::new(ctx, headless_settings(settings), settings.width, settings.height)?;
    live.set_ifs(ctx, &compiled, bounds, true);
    live.set_camera(&camera);
    let splats = accumulate(ctx, &mut live, settings.points);
    let image = live.snapshot(ctx)?;
    Ok(GpuRendered { image, camera, bounds, splats })
}
