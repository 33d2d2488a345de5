//! Headless GPU rendering (`render --backend gpu`): a prepared [`Shot`]'s chaos game on the GPU
//! in timed batches ([`super::batch`]), its accumulation read back and drawn by the CPU resolve
//! with the shot's style, so every output format of a CPU render is open to it. Density
//! estimation (density mode) runs on the GPU too (`shaders/density_estimation.wgsl`), on the
//! accumulation uploaded again after the read-back, and its estimate is resolved on the CPU.

use crate::resolve::{density_estimation, resolve_image};
use crate::shot::Shot;
use crate::splat::Framebuffer;

use super::batch::{BatchSizing, BatchStats, GpuSplatter};
use super::density_estimation::GpuDensityEstimation;
use super::{GpuContext, GpuError};

pub struct GpuRendered {
    pub image: image::RgbImage,
    /// The accumulation the image was resolved from (for the layered outputs).
    pub framebuffer: Framebuffer,
    /// Points splatted (`settings.points` rounded up to whole steps of every GPU point), batches.
    pub stats: BatchStats,
}

/// Renders `shot` on the GPU: the twin of `render::render_cpu` (same bounds, camera, splat and
/// resolve; the points come from GPU streams, so the image agrees in distribution, not bit for
/// bit). Fails with [`GpuError::FramebufferTooLarge`] where the accumulation exceeds what the
/// device can bind.
pub fn render_gpu(ctx: &GpuContext, shot: &Shot) -> Result<GpuRendered, GpuError> {
    let (framebuffer, stats) = GpuSplatter::new(BatchSizing::Timed).splat(ctx, shot)?;
    let view = &framebuffer.view;
    let image = match density_estimation::applies(shot.settings.density_estimation.as_ref(), view.mode) {
        Some(de) => {
            let mut gpu = GpuDensityEstimation::new(&ctx.device);
            let e = gpu.estimate(ctx, &framebuffer.accum, view.width, view.height, &de)?;
            density_estimation::image_of(&e, &framebuffer, &shot.camera, &shot.style)
        }
        None => resolve_image(&framebuffer, &shot.camera, &shot.style),
    };
    Ok(GpuRendered { image, framebuffer, stats })
}
