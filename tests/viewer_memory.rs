//! The live view's host memory stays flat frame after frame: the viewer's frame (advance and
//! draw of [`LiveView`], into an offscreen target as the window would get it) repeated a few
//! hundred times must not grow the process's resident memory. It would have caught Mesa
//! lavapipe's per-draw leak of shaders specialized on their uniforms (about 0.4 MB a draw of
//! the resolve, 80 MB over these frames; `shaders/resolve.wgsl` says why its parameters are a
//! storage buffer), and catches any per-frame leak of ours the same way.
//!
//! Linux only (resident memory from /proc); without a GPU adapter it skips loudly, unless
//! NLIFS_REQUIRE_GPU=1, in which case it fails.

mod common;

use nlifs::chaos_game::{self, CompiledIfs};
use nlifs::gpu::progressive::ProgressiveSettings;
use nlifs::live::{ChaosBackend, LiveSettings, LiveView};
use nlifs::scene::spec::SplatMode;

/// Frames drawn before the first reading (pipelines, caches and the allocator settle) and
/// between the two readings.
const WARM_UP_FRAMES: u32 = 40;
const MEASURED_FRAMES: u32 = 200;
/// The most the resident memory may grow over the measured frames: 0.05 MB a frame (the leak
/// was eight times that), room for the allocator's own growth.
const GROWTH_LIMIT_BYTES: u64 = 10 << 20;

fn resident_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("read /proc/self/status");
    let kb: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("VmRSS in /proc/self/status");
    kb * 1024
}

/// Draws `scene` frame after frame the way the viewer does and returns the growth of the
/// resident memory over the measured frames.
fn growth_over_frames(ctx: &nlifs::gpu::GpuContext, scene: &str, settings: LiveSettings) -> u64 {
    let (width, height) = (480, 320);
    let scene = common::load_scene(scene);
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let camera = scene.camera_for(bounds);
    let mut live = LiveView::new(ctx, settings, width, height).unwrap();
    live.set_ifs(ctx, &compiled, bounds, true);
    live.set_camera(&camera);
    let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("viewer_memory_target"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Bgra8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    let frame = |live: &mut LiveView| {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        live.advance(ctx, &mut encoder);
        live.draw(ctx, &mut encoder, &view, wgpu::TextureFormat::Bgra8Unorm, [0, 0]);
        ctx.queue.submit([encoder.finish()]);
        ctx.device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).unwrap();
    };
    for _ in 0..WARM_UP_FRAMES {
        frame(&mut live);
    }
    let before = resident_bytes();
    for _ in 0..MEASURED_FRAMES {
        frame(&mut live);
    }
    resident_bytes().saturating_sub(before)
}

#[test]
fn live_view_frames_keep_host_memory_flat() {
    let Some(ctx) = common::gpu() else { return };
    let base = LiveSettings {
        draw: ProgressiveSettings {
            point_count: 4096,
            steps_per_frame: 1,
            seed: 3,
            max_splats: u64::MAX,
            ..ProgressiveSettings::default()
        },
        chaos_backend: ChaosBackend::Cpu,
        render_density: None,
    };
    let cases = [
        (
            "plant1",
            "solid look, CPU route",
            LiveSettings { draw: ProgressiveSettings { shading: 1.0, occlusion: 0.6, ..base.draw }, ..base },
        ),
        ("julia", "paper look, GPU route", LiveSettings { chaos_backend: ChaosBackend::Gpu, ..base }),
        (
            "plant2",
            "density mode",
            LiveSettings { draw: ProgressiveSettings { mode: SplatMode::Density, ..base.draw }, ..base },
        ),
    ];
    for (scene, what, settings) in cases {
        let growth = growth_over_frames(&ctx, scene, settings);
        eprintln!("{scene} ({what}): resident memory grew {:.1} MB over {MEASURED_FRAMES} frames", growth as f64 / 1e6);
        assert!(
            growth <= GROWTH_LIMIT_BYTES,
            "{scene} ({what}): resident memory grew {:.1} MB over {MEASURED_FRAMES} frames (limit {:.1} MB) on {}",
            growth as f64 / 1e6,
            GROWTH_LIMIT_BYTES as f64 / 1e6,
            ctx.describe()
        );
    }
}
