//! `nlifs render`: a still with the chaos game, on the CPU (deterministic bytes) or the GPU.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use nlifs::output::Provenance;
use nlifs::output::part::PartSpec;
use nlifs::resolve::{MAX_POINT_RADIUS_PX, ResolveStyle};
use nlifs::scene::spec::{Look, SplatMode};
use nlifs::shot::{Framing, Shot};

use super::image_args::{ImageArgs, render_part, write_still};
use super::{BadInput, load, probe_output, progress_bar};

#[derive(Args)]
pub struct RenderArgs {
    scene: PathBuf,
    /// Output image (.png or .exr).
    #[arg(short, long, required_unless_present = "raw", conflicts_with = "raw")]
    output: Option<PathBuf>,
    #[command(flatten)]
    image: ImageArgs,
    /// Render part K of N of the points (chunks of the chaos game) into --raw, for `nlifs merge`.
    #[arg(long, requires = "raw", value_parser = PartSpec::parse)]
    part: Option<PartSpec>,
    /// The part file to write (with --part).
    #[arg(long, requires = "part")]
    raw: Option<PathBuf>,
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
    /// The look of closest-mode pictures: `solid` (lit from the depth of neighbouring points,
    /// with ambient occlusion) or `paper` (the paper's depth-cued flat colour). Default: the
    /// scene's `[render] look`.
    #[arg(long, value_enum)]
    look: Option<LookArg>,
    /// Lighting strength, 0 (flat colours) to 1 (fully lit), over the look's; closest mode.
    #[arg(long, value_parser = parse_unit)]
    shading: Option<f32>,
    /// Ambient occlusion strength, 0 (none) to 1, over the look's; closest mode.
    #[arg(long, value_parser = parse_unit)]
    occlusion: Option<f32>,
    /// flam3's tone controls (average and density modes) over the scene's.
    #[command(flatten)]
    tone: super::tone_args::ToneArgs,
    /// The key light's shadows and direction over the scene's.
    #[command(flatten)]
    light: super::light_args::LightArgs,
    /// Depth of field over the scene's.
    #[command(flatten)]
    lens: super::lens_args::LensArgs,
    /// Drawn point radius in pixels: each pixel shows the nearest point within it (closest mode).
    #[arg(long, value_name = "PX", default_value_t = 0,
          value_parser = clap::value_parser!(u32).range(0..=MAX_POINT_RADIUS_PX as i64))]
    point_radius: u32,
    /// flam3's adaptive density estimation (density mode, CPU, 8-bit PNG): each pixel's points
    /// spread over a disc of radius MAX_RADIUS / count^CURVE pixels, at least MIN_RADIUS
    /// (defaults 0 and 0.4), so sparse regions turn smooth and dense ones stay sharp; 0: off.
    /// Default: the scene's `estimator_radius`, `estimator_minimum`, `estimator_curve`.
    #[arg(long, value_name = "MAX_RADIUS[,MIN[,CURVE]]",
          value_parser = nlifs::resolve::density_estimation::parse_flag)]
    density_estimation: Option<nlifs::resolve::density_estimation::DensityFlag>,
    /// EXR: the layers to write besides R G B A, comma-separated: Z and id (closest mode), count
    /// (average and density modes), N (the shading normal: closest mode with shading or
    /// occlusion). Default: all the mode has. A layer the mode lacks is an error.
    #[arg(long, value_name = "LIST")]
    layers: Option<String>,
    /// Where the chaos game runs: gpu, cpu, or auto (gpu when a hardware adapter exists).
    #[arg(long, value_enum, default_value_t = RenderBackend::Cpu)]
    backend: RenderBackend,
    /// Colour by function or by a palette (`--color`, `--palette`).
    #[command(flatten)]
    color: super::color_args::ColorArgs,
    /// Flame files: samples per output pixel (default: the flame's `quality`).
    #[arg(long)]
    quality: Option<f64>,
    /// Flame files: render threads (default: all cores; the bytes are the same).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    threads: Option<u32>,
    /// Flame files: the flame to render, numbered from 0 (default: the first).
    #[arg(long, conflicts_with = "name")]
    index: Option<usize>,
    /// Flame files: the flame to render by its `name`.
    #[arg(long)]
    name: Option<String>,
}

#[derive(Clone, Copy, ValueEnum)]
enum LookArg {
    Solid,
    Paper,
}

impl From<LookArg> for Look {
    fn from(l: LookArg) -> Self {
        match l {
            LookArg::Solid => Look::Solid,
            LookArg::Paper => Look::Paper,
        }
    }
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
    if nlifs::flame::xml::is_flame_path(&args.scene) {
        if args.raw.is_some() || args.points.is_some() || args.mode.is_some() || args.backend == RenderBackend::Gpu {
            return Err(BadInput(
                "--part, --raw, --points, --mode and --backend gpu are for scenes, not flame files".into(),
            )
            .into());
        }
        let output = args.output.clone().expect("clap requires --output without --raw");
        return super::render_flame::render(super::render_flame::FlameRequest {
            file: &args.scene,
            output: &output,
            width: args.width,
            height: args.height,
            quality: args.quality,
            seed: args.seed,
            threads: args.threads.map(|n| n as usize),
            index: args.index,
            name: args.name.as_deref(),
        });
    }
    if args.quality.is_some() || args.threads.is_some() || args.index.is_some() || args.name.is_some() {
        return Err(
            BadInput("--quality, --threads, --index and --name are for flame files (.flame, .flam3)".into()).into()
        );
    }
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
    // The look is part of the settings, so that parts, merges and the PNG's own scene keep it.
    settings.look = args.look.map(Look::from).or(settings.look);
    settings.shading = args.shading.or(settings.shading);
    settings.occlusion = args.occlusion.or(settings.occlusion);
    args.tone.apply(&mut settings);
    args.light.apply(&mut settings);
    args.lens.apply(&mut settings);
    args.color.apply(&mut settings)?;
    if let Some(de) = args.density_estimation {
        settings.density_estimation = de.0;
    }
    if let (Some(spec), Some(raw)) = (args.part, &args.raw) {
        if args.point_radius != 0 {
            return Err(BadInput(
                "--point-radius is not kept in part files: give it to a whole render, not to --part".into(),
            )
            .into());
        }
        if args.backend == RenderBackend::Gpu {
            return Err(BadInput(
                "--part renders on the CPU (its chunks are the CPU chaos game's); leave out --backend gpu".into(),
            )
            .into());
        }
        return render_part(&scene, args.time, &settings, spec, raw);
    }
    let output = args.output.clone().expect("clap requires --output without --raw");
    let options = args.image.for_file(&output)?;
    let layers = super::render_cpu::LayerChoice::parse(args.layers.as_deref(), &options)?;
    let provenance = Provenance::for_render(&scene, args.time, &settings);
    let start = std::time::Instant::now();
    let shot = Shot::prepare(&scene, args.time, &settings, Framing::Fit, None).map_err(|e| BadInput(e.to_string()))?;
    let style = ResolveStyle { point_radius_px: args.point_radius, ..shot.style };
    let shot = shot.with_style(style);
    let bar = progress_bar(shot.plan.chunks() as u64, "render");
    // GPU: explicit `gpu` fails without an adapter (exit 2); `auto` takes a hardware adapter
    // only (the CPU outruns a software rasterizer), as `record --backend auto` does.
    let gpu = match args.backend {
        RenderBackend::Cpu => None,
        RenderBackend::Gpu => Some(nlifs::gpu::GpuContext::headless().map_err(gpu_error)?),
        RenderBackend::Auto => {
            nlifs::gpu::GpuContext::headless().ok().filter(|ctx| !nlifs::gpu::batch::is_software(ctx))
        }
    };
    if gpu.is_some() && args.layers.is_some() {
        // The GPU still writes every layer the mode has; choosing them is the CPU writer's.
        return Err(BadInput("--layers needs --backend cpu (the GPU route writes all the mode's layers)".into()).into());
    }
    // After the checks (the GPU's among them), before the work.
    probe_output(&output)?;
    for warning in nlifs::scene::warnings::scene_warnings(&scene, args.time) {
        bar.suspend(|| eprintln!("warning: {warning}"));
    }
    let image = match &gpu {
        Some(ctx) => {
            bar.finish_and_clear();
            eprintln!("rendering on {}", ctx.describe());
            // In batches of bounded length (no driver watchdog trips), read back for the resolve.
            let r = nlifs::gpu::render::render_gpu(ctx, &shot).map_err(gpu_error)?;
            eprintln!(
                "GPU: {} points in {} batches, longest {:.0} ms",
                r.stats.splats,
                r.stats.batches,
                1e3 * r.stats.longest_batch_secs
            );
            write_still(
                &output,
                &options,
                &r.framebuffer,
                &shot.camera,
                &shot.style,
                shot.settings.density_estimation.as_ref(),
                Some(&r.image),
                &provenance,
            )?;
            Some(r.image)
        }
        None => {
            let covered = super::render_cpu::render_still(&shot, &output, &options, &layers, &provenance, &bar)?;
            if covered == 0 {
                // The warning's own test, on an image with nothing drawn.
                if let Some(warning) =
                    nlifs::scene::warnings::coverage_warning(&image::RgbImage::new(0, 0), settings.background)
                {
                    eprintln!("warning: {warning}");
                }
            }
            None
        }
    };
    if let Some(warning) = image.and_then(|image| nlifs::scene::warnings::coverage_warning(&image, settings.background))
    {
        eprintln!("warning: {warning}");
    }
    eprintln!(
        "wrote {} ({}×{}, {} points, {:.2} s)",
        output.display(),
        settings.width,
        settings.height,
        settings.points,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// A GPU error as the CLI reports it: bad input (exit 2) where the request exceeds the machine
/// (no adapter, an image or point count past the device's limits).
pub fn gpu_error(e: nlifs::gpu::GpuError) -> anyhow::Error {
    if e.is_bad_input() { BadInput(e.to_string()).into() } else { e.into() }
}

/// `--shading`, `--occlusion`: a number in 0..=1.
fn parse_unit(s: &str) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("`{s}` is not a number"))?;
    if !(0.0..=1.0).contains(&v) {
        return Err(format!("{v} is not in 0..=1"));
    }
    Ok(v)
}
