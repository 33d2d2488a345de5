//! `nlifs render`: a still with the chaos game, on the CPU (deterministic bytes) or the GPU.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};

use nlifs::chaos_game;
use nlifs::io::save_png;
use nlifs::render::render_cpu;
use nlifs::scene::spec::SplatMode;

use super::args::check_png;
use super::{BadInput, load, progress_bar};

#[derive(Args)]
pub struct RenderArgs {
    scene: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Image width in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Points to draw after the transient (default: the scene's).
    #[arg(long, value_parser = super::args::point_count)]
    points: Option<u64>,
    /// Random seed (default: the scene's).
    #[arg(long)]
    seed: Option<u32>,
    /// Scene time in seconds.
    #[arg(long, default_value_t = 0.0, value_parser = super::args::time_secs)]
    time: f64,
    /// Splat mode (default: the scene's).
    #[arg(long, value_enum)]
    mode: Option<ModeArg>,
    /// Where the chaos game runs: gpu, cpu, or auto (gpu when an adapter exists).
    #[arg(long, value_enum, default_value_t = RenderBackend::Cpu)]
    backend: RenderBackend,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeArg {
    Closest,
    Average,
    Density,
}

impl From<ModeArg> for SplatMode {
    fn from(m: ModeArg) -> Self {
        match m {
            ModeArg::Closest => SplatMode::Closest,
            ModeArg::Average => SplatMode::Average,
            ModeArg::Density => SplatMode::Density,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum RenderBackend {
    Gpu,
    Cpu,
    Auto,
}

pub fn render(args: RenderArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    let mut settings = scene.render_at(args.time);
    if let Some(w) = args.width {
        settings.width = w;
    }
    if let Some(h) = args.height {
        settings.height = h;
    }
    if let Some(n) = args.points {
        settings.points = n;
    }
    if let Some(s) = args.seed {
        settings.seed = s;
    }
    if let Some(m) = args.mode {
        settings.mode = m.into();
    }
    check_png(&args.output)?;
    let (chunks, _, _) = chaos_game::chunking(settings.points);
    let bar = progress_bar(chunks as u64, "render");
    let start = std::time::Instant::now();
    // GPU: explicit `gpu` fails without an adapter; `auto` falls back to the CPU.
    let gpu = match args.backend {
        RenderBackend::Cpu => None,
        RenderBackend::Gpu => Some(nlifs::gpu::GpuContext::headless()?),
        RenderBackend::Auto => nlifs::gpu::GpuContext::headless().ok(),
    };
    let image = match &gpu {
        Some(ctx) => {
            bar.finish_and_clear();
            eprintln!("rendering on {}", ctx.describe());
            nlifs::gpu::render::render_gpu(ctx, &scene, args.time, &settings, None)
                .map_err(|e| match e {
                    nlifs::gpu::GpuError::NoFunctions => anyhow::Error::new(BadInput(e.to_string())),
                    e => e.into(),
                })?
                .image
        }
        None => {
            render_cpu(&scene, args.time, &settings, None, &|d, _| bar.set_position(d))
                .map_err(|e| BadInput(e.to_string()))?
                .image
        }
    };
    bar.finish_and_clear();
    save_png(&args.output, &image).with_context(|| format!("cannot write {}", args.output.display()))?;
    eprintln!(
        "wrote {} ({}×{}, {} points, {:.2} s)",
        args.output.display(),
        settings.width,
        settings.height,
        settings.points,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
