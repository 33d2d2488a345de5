//! Headless rendering of a scene at a time on the CPU: compile the IFS, estimate the
//! attractor's bounds, frame the camera, run the chaos game into per-thread framebuffers and
//! resolve. A pure function of (scene, time, settings).

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::chaos_game::{self, ChunkPlan, CompiledIfs, PlanError};
use crate::resolve::{ResolveStyle, resolve_image};
use crate::scene::Scene;
use crate::scene::spec::RenderSettings;
use crate::splat::{Framebuffer, SplatView};

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("the scene has no enabled function")]
    NoFunctions,
    #[error(transparent)]
    Points(#[from] PlanError),
}

/// What a render produced besides the image.
pub struct Rendered {
    pub image: image::RgbImage,
    pub camera: OrbitCamera,
    pub bounds: (DVec3, DVec3),
    pub framebuffer: Framebuffer,
}

/// Renders `scene` at `t_secs` with `settings`; `camera` overrides the scene's camera.
/// `progress(done, total)` is called as chunks finish (from worker threads).
pub fn render_cpu(
    scene: &Scene,
    t_secs: f64,
    settings: &RenderSettings,
    camera: Option<OrbitCamera>,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Rendered, RenderError> {
    let ifs = scene.at(t_secs);
    let compiled = CompiledIfs::new(&ifs).ok_or(RenderError::NoFunctions)?;
    let plan = ChunkPlan::new(settings.points)?;
    let bounds = chaos_game::attractor_bounds(&compiled, settings.seed);
    let camera = camera.unwrap_or_else(|| {
        let sample = chaos_game::attractor_sample(&compiled, settings.seed);
        frame_camera(scene, t_secs, bounds, &sample, settings.width as f32 / settings.height as f32)
    });
    let view = SplatView::new(
        &camera,
        settings.width,
        settings.height,
        bounds,
        settings.mode,
        settings.depth_cue,
        settings.background,
    );
    let done = std::sync::atomic::AtomicU64::new(0);
    let framebuffer = chaos_game::run_parallel(
        &compiled,
        settings.seed,
        0,
        &plan,
        || Framebuffer::new(view, compiled.colors.clone()),
        Framebuffer::merge,
        || {
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, plan.chunks() as u64);
        },
    );
    let image = resolve_image(&framebuffer, &camera, &ResolveStyle::default());
    Ok(Rendered { image, camera, bounds, framebuffer })
}

/// The scene's camera; where the scene leaves both target and distance open, fitted to a sample
/// of the attractor's points (tighter than fitting its bounding box).
pub fn frame_camera(
    scene: &Scene,
    t_secs: f64,
    bounds: (DVec3, DVec3),
    sample: &[glam::Vec3],
    aspect: f32,
) -> OrbitCamera {
    let mut camera = scene.camera_for_at(t_secs, bounds);
    let spec = scene.camera_at(t_secs);
    if spec.target.is_none() && spec.distance.is_none() {
        camera.fit_points(sample, aspect);
    }
    camera
}
