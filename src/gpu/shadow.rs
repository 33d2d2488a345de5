//! The GPU chaos game's shadow map (`shadow_map` in `shaders/chaos_game.wgsl`, splatted by
//! `splat_shadow` behind the pipeline constant `SHADOWED`; CPU twin `src/splat/shadow.rs`): its
//! buffer, sized to the view's map (`GpuChaosGame::fit_shadow`), and its readback into the CPU
//! framebuffer's layout.

use crate::splat::SplatView;

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

/// The shadow map `buffer` (a chaos game's) as the CPU framebuffer's keys for `view` (empty
/// where the view has none).
pub fn read_shadow_map(ctx: &GpuContext, buffer: &wgpu::Buffer, view: &SplatView) -> Result<Vec<u32>, GpuError> {
    let Some(shadow) = view.shadow else { return Ok(Vec::new()) };
    let bytes = super::readback::read_buffer_prefix(ctx, buffer, 4 * shadow.texels() as u64)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
