//! Reading GPU results back to the host, and the offscreen targets they are drawn into: a
//! buffer copied through a mappable staging buffer, and a draw into an RGBA8 texture read back
//! as an 8-bit RGB image (headless renders, the viewer's screenshots, tests and benchmarks).
//! Everything here waits for the GPU; none of it belongs on a per-frame path.

use super::{GpuContext, GpuError};

/// Copies `buffer` (which must have COPY_SRC usage) to the host.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    read_buffer_prefix(ctx, buffer, buffer.size())
}

/// Copies the first `bytes` bytes of `buffer` (COPY_SRC usage; `bytes` a multiple of 4 and at
/// most its size) to the host.
pub fn read_buffer_prefix(ctx: &GpuContext, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, GpuError> {
    let bytes = bytes.min(buffer.size());
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
    ctx.queue.submit([encoder.finish()]);
    map_and_read(ctx, &staging)
}

/// Waits for the submitted work, maps `staging` and copies its bytes out.
fn map_and_read(ctx: &GpuContext, staging: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    rx.recv().map_err(|e| GpuError::Readback(e.to_string()))?.map_err(|e| GpuError::Readback(e.to_string()))?;
    let bytes = staging.get_mapped_range(..).map_err(|e| GpuError::Readback(e.to_string()))?.to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Records `draw` onto an offscreen RGBA8 texture of `width`×`height` (its arguments: the
/// encoder, the texture's view and format), then copies the texture to the host as an RGB image.
pub fn draw_offscreen(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    draw: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView, wgpu::TextureFormat),
) -> Result<image::RgbImage, GpuError> {
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let texture = offscreen_texture(ctx, "snapshot", width, height, format, wgpu::TextureUsages::COPY_SRC);
    let view = texture.create_view(&Default::default());
    let bytes_per_row = (4 * width).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("snapshot_readback"),
        size: bytes_per_row as u64 * height as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    draw(&mut encoder, &view, format);
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes_per_row),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    ctx.queue.submit([encoder.finish()]);
    let bytes = map_and_read(ctx, &staging)?;
    let mut image = image::RgbImage::new(width, height);
    for (y, row) in bytes.chunks(bytes_per_row as usize).take(height as usize).enumerate() {
        for x in 0..width as usize {
            let p = &row[4 * x..4 * x + 3];
            image.put_pixel(x as u32, y as u32, image::Rgb([p[0], p[1], p[2]]));
        }
    }
    Ok(image)
}

/// A 2D render target of `width`×`height` for offscreen drawing (snapshots, benchmarks), with
/// `extra` usages beside RENDER_ATTACHMENT.
pub fn offscreen_texture(
    ctx: &GpuContext,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    extra: wgpu::TextureUsages,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | extra,
        view_formats: &[],
    })
}
