//! Headless GPU rendering: a scene at a time into an offscreen texture through the same
//! [`LiveView`] the viewer draws with, read back as an image (`render --backend gpu`).

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::chaos_game::{self, CompiledIfs};
use crate::scene::Scene;
use crate::scene::spec::RenderSettings;

use super::live::{LiveSettings, LiveView};
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

/// Copies `buffer` (which must have COPY_SRC usage) to the host.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([encoder.finish()]);
    map_and_read(ctx, &staging)
}

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

/// Resolves `live` into an offscreen RGBA8 texture of its size and reads it back.
pub fn snapshot(ctx: &GpuContext, live: &mut LiveView) -> Result<image::RgbImage, GpuError> {
    let (width, height) = live.size();
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
    live.draw(ctx, &mut encoder, &view, format, [0, 0]);
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

/// Runs the chaos game of `ifs` on `live` until `points` points were splatted (rounded up to
/// whole frames); returns the number splatted. The first frame restarts the points.
pub fn accumulate(ctx: &GpuContext, live: &mut LiveView, points: u64) -> u64 {
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
pub fn headless_settings(settings: &RenderSettings) -> LiveSettings {
    LiveSettings {
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
        chaos_backend: super::cpu_route::ChaosBackend::Gpu,
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
    let mut live = LiveView::new(ctx, headless_settings(settings), settings.width, settings.height)?;
    live.set_ifs(ctx, &compiled, bounds, true);
    live.set_camera(&camera);
    let splats = accumulate(ctx, &mut live, settings.points);
    let image = snapshot(ctx, &mut live)?;
    Ok(GpuRendered { image, camera, bounds, splats })
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
