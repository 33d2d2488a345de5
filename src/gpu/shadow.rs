//! The GPU chaos game's shadow map (`shadow_map` in `shaders/chaos_game.wgsl`, splatted by
//! `splat_shadow` behind the pipeline constant `SHADOWED`; CPU twin `src/splat/shadow.rs`): its
//! buffer, sized to the view's map, and its readback into the CPU framebuffer's layout.

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::resolve::shadow::key_light;
use crate::splat::{ShadowView, SplatView};

use super::progressive::ProgressiveSettings;

use super::chaos_game::GpuChaosGame;
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

impl GpuChaosGame {
    /// Resizes the shadow map to `shadow`'s (its contents are lost: the frame must clear).
    pub fn fit_shadow(&mut self, device: &wgpu::Device, shadow: Option<&ShadowView>) {
        let side_px = shadow.map_or(0, |s| s.side_px);
        if side_px != self.shadow_side {
            self.shadow = shadow_buffer(device, side_px);
            self.shadow_side = side_px;
            self.invalidate_bindings();
        }
    }
}

/// The shadow map of `game` as the CPU framebuffer's keys for `view` (empty where the view has
/// none).
pub fn read_shadow_map(ctx: &GpuContext, game: &GpuChaosGame, view: &SplatView) -> Result<Vec<u32>, GpuError> {
    let Some(shadow) = view.shadow else { return Ok(Vec::new()) };
    let bytes = super::readback::read_buffer_prefix(ctx, &game.shadow, 4 * shadow.texels() as u64)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// The live view's shadow map has half the side of a still's (a quarter of the texels; at
/// 1280×720, 320²), at least [`crate::splat::shadow::MIN_SIDE_PX`]: it is splatted from every
/// frame's points and, on the CPU route, merged and uploaded every frame; at the live view's
/// size the soft edge of the coarser map still spans only a few pixels.
pub const LIVE_SHADOW_SIDE_DIVISOR: u32 = 2;

/// The live view `view` of `camera` with the shadow map `settings` need (none where they cast
/// no shadows: not closest mode, shading or shadows off).
pub fn live_shadow(
    view: SplatView,
    settings: &ProgressiveSettings,
    camera: &OrbitCamera,
    bounds: (DVec3, DVec3),
) -> SplatView {
    let s = settings;
    if s.mode != crate::scene::spec::SplatMode::Closest || s.shadows <= 0.0 || s.shading <= 0.0 {
        return view;
    }
    let side_px = (ShadowView::side_for_image(view.width, view.height) / LIVE_SHADOW_SIDE_DIVISOR)
        .max(crate::splat::shadow::MIN_SIDE_PX);
    let to_light = glam::Vec3::from_array(key_light(s.light_yaw_deg, s.light_pitch_deg));
    view.with_shadow_side(camera, bounds, to_light, side_px)
}
