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
    // The wait has called the map callback on the desktop; in the browser buffers map later,
    // on the page's event loop, and blocking here would hang the page: an error instead.
    rx.try_recv()
        .map_err(|_| {
            GpuError::Readback("the buffer was not mapped after the wait (a browser maps buffers later)".into())
        })?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let bytes = staging.get_mapped_range(..).map_err(|e| GpuError::Readback(e.to_string()))?.to_vec();
    staging.unmap();
    Ok(bytes)
}

/// [`read_buffer`] that also works in the browser, where a buffer maps on the page's event loop
/// and cannot be waited for: the map is awaited. On the desktop the device wait inside maps it,
/// so the future is ready when polled.
pub async fn read_buffer_async(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([encoder.finish()]);
    map_async(&ctx.device, &staging).await?;
    let bytes = staging.get_mapped_range(..).map_err(|e| GpuError::Readback(e.to_string()))?.to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Maps `staging` for reading and waits for it without blocking the browser's thread.
async fn map_async(device: &wgpu::Device, staging: &wgpu::Buffer) -> Result<(), GpuError> {
    use std::sync::{Arc, Mutex};
    type Slot = Arc<Mutex<(Option<Result<(), wgpu::BufferAsyncError>>, Option<std::task::Waker>)>>;
    let slot: Slot = Arc::default();
    let filled = slot.clone();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let mut s = filled.lock().unwrap_or_else(|e| e.into_inner());
        s.0 = Some(r);
        if let Some(waker) = s.1.take() {
            waker.wake();
        }
    });
    // The desktop maps here; the browser ignores the wait and maps on its own.
    device
        .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    std::future::poll_fn(|cx| {
        let mut s = slot.lock().unwrap_or_else(|e| e.into_inner());
        match s.0.take() {
            Some(r) => std::task::Poll::Ready(r.map_err(|e| GpuError::Readback(e.to_string()))),
            None => {
                s.1 = Some(cx.waker().clone());
                std::task::Poll::Pending
            }
        }
    })
    .await
}

/// Records `draw` onto an offscreen RGBA8 texture of `width`×`height` (its arguments: the
/// encoder, the texture's view and format), then copies the texture to the host as an RGB image.
pub fn draw_offscreen(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    draw: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView, wgpu::TextureFormat),
) -> Result<image::RgbImage, GpuError> {
    draw_offscreen_as(ctx, width, height, wgpu::TextureFormat::Rgba8Unorm, draw)
}

/// [`draw_offscreen`] onto a texture of `format`, an RGBA8 format (`Rgba8UnormSrgb`: as a
/// window's sRGB surface; the image holds the bytes the format stores).
pub fn draw_offscreen_as(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    draw: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView, wgpu::TextureFormat),
) -> Result<image::RgbImage, GpuError> {
    let copy = copy_of_drawing(ctx, width, height, format, draw);
    let bytes = map_and_read(ctx, &copy.staging)?;
    Ok(copy.image_of(&bytes))
}

/// An offscreen drawing submitted with its copy to a mappable buffer ([`draw_offscreen_start`]),
/// to be read back as an image when the buffer maps.
pub struct OffscreenCopy {
    device: wgpu::Device,
    staging: wgpu::Buffer,
    width: u32,
    height: u32,
    bytes_per_row: u32,
}

/// [`draw_offscreen`] up to the submission: the image comes from [`OffscreenCopy::image`],
/// which the browser can await.
pub fn draw_offscreen_start(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    draw: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView, wgpu::TextureFormat),
) -> OffscreenCopy {
    copy_of_drawing(ctx, width, height, wgpu::TextureFormat::Rgba8Unorm, draw)
}

fn copy_of_drawing(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    draw: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView, wgpu::TextureFormat),
) -> OffscreenCopy {
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
    OffscreenCopy { device: ctx.device.clone(), staging, width, height, bytes_per_row }
}

impl OffscreenCopy {
    /// The drawing as an RGB image, once the copy has mapped (awaited in the browser; ready at
    /// once on the desktop, where the device wait maps it).
    pub async fn image(self) -> Result<image::RgbImage, GpuError> {
        map_async(&self.device, &self.staging).await?;
        let bytes = self.staging.get_mapped_range(..).map_err(|e| GpuError::Readback(e.to_string()))?.to_vec();
        self.staging.unmap();
        Ok(self.image_of(&bytes))
    }

    /// The RGB image in the copy's rows (padded to the copy alignment, RGBA).
    fn image_of(&self, bytes: &[u8]) -> image::RgbImage {
        let mut image = image::RgbImage::new(self.width, self.height);
        for (y, row) in bytes.chunks(self.bytes_per_row as usize).take(self.height as usize).enumerate() {
            for x in 0..self.width as usize {
                let p = &row[4 * x..4 * x + 3];
                image.put_pixel(x as u32, y as u32, image::Rgb([p[0], p[1], p[2]]));
            }
        }
        image
    }
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
