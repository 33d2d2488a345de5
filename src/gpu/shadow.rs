//! The GPU chaos game's shadow map (`shadow_map` in `shaders/chaos_game.wgsl`, splatted by
//! `splat_shadow` behind the pipeline constant `SHADOWED`; CPU twin `src/splat/shadow.rs`): its
//! buffer (`GpuChaosGame::fit_shadow` sizes it to the view's map), its readback into the CPU
//! framebuffer's layout, and the live view's map size.

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::splat::{ShadowView, SplatView};

use super::{GpuContext, GpuError};

/// A shadow map buffer of `side_px`² texels (at least one u32, so that it can be bound when the
/// view has no map).
pub fn shadow_buffer(device: &wgpu::Device, side_px: u32) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shadow_map"),
        size: 4 * (side_px as u64 * side_px as u64).max(1),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The shadow map in `buffer` (a chaos game's) as the CPU framebuffer's keys for `view` (empty
/// where the view has none).
pub fn read_shadow_map(ctx: &GpuContext, buffer: &wgpu::Buffer, view: &SplatView) -> Result<Vec<u32>, GpuError> {
    let Some(shadow) = view.shadow else { return Ok(Vec::new()) };
    let bytes = super::readback::read_buffer_prefix(ctx, buffer, 4 * shadow.texels() as u64)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// The live view's shadow map has half the side of a still's (a quarter of the texels; at
/// 1280×720, 320²), at least [`crate::splat::shadow::MIN_SIDE_PX`]: it is splatted from every
/// frame's points and, on the CPU route, merged and uploaded every frame; at the live view's
/// size the soft edge of the coarser map still spans only a few pixels.
pub const LIVE_SHADOW_SIDE_DIVISOR: u32 = 2;

/// The live view `view` of `camera` with the shadow map of a key light towards `to_light`
/// (view space) where `casts` says one is needed (closest mode, shading and shadows on).
pub fn live_shadow(
    view: SplatView,
    casts: bool,
    to_light: glam::Vec3,
    camera: &OrbitCamera,
    bounds: (DVec3, DVec3),
) -> SplatView {
    if !casts {
        return view;
    }
    let side_px = (ShadowView::side_for_image(view.width, view.height) / LIVE_SHADOW_SIDE_DIVISOR)
        .max(crate::splat::shadow::MIN_SIDE_PX);
    view.with_shadow_side(camera, bounds, to_light, side_px)
}
