//! `nlifs record`: an animated scene rendered frame by frame to DIR/frame_NNNNN.png, resumable
//! and splittable over a job array, optionally encoded into a video with the system ffmpeg.
//! The chaos game runs on the CPU or the GPU (`--backend`), or the frames are ray-traced as
//! `nlifs snapshot` traces a still (`--renderer raytrace`, with the snapshot's options).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use nlifs::chaos_game::ChunkPlan;
use nlifs::output::Format;
use nlifs::raytrace::Initial;
use nlifs::record::{self, RecordSettings, Recorder, Renderer, TraceOptions};

use super::args::{hex_color, positive_pixels};
use super::image_args::ImageArgs;
use super::render::gpu_error;
use super::snapshot::ColorArg;
use super::{BadInput, load};

#[derive(Args)]
pub struct RecordArgs {
    scene: PathBuf,
    /// Output directory for frame_NNNNN.png.
    #[arg(short, long)]
    output: PathBuf,
    /// Frames A..B to render (end exclusive; default: the whole animation).
    #[arg(long, value_parser = record::parse_frame_range)]
    frames: Option<std::ops::Range<u32>>,
    #[arg(long, default_value_t = 24.0)]
    fps: f64,
    /// Frame width in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Frame height in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Points per frame (default: the scene's render.points at the frame's time).
    #[arg(long, value_parser = super::args::point_count)]
    points_per_frame: Option<u64>,
    /// Where the chaos game runs: cpu (the same bytes on every machine), gpu (the same bytes
    /// on every run on one adapter), or auto: the GPU where the adapter is a hardware one.
    #[arg(long, value_enum, default_value_t = RecordBackend::Auto)]
    backend: RecordBackend,
    /// What draws the frames: chaos (the chaos game's points) or raytrace (W^n(A) ray-traced
    /// as `nlifs snapshot` does, with its options below).
    #[arg(long, value_enum, default_value_t = RendererArg::Chaos)]
    renderer: RendererArg,
    /// Keep frames that are already complete (decode fully); redo anything else.
    #[arg(long)]
    resume: bool,
    /// Also encode the frames into this video with the system ffmpeg.
    #[arg(long)]
    video: Option<PathBuf>,
    /// flam3's adaptive density estimation (density mode, 8-bit PNG frames): each pixel's points
    /// spread over a disc of radius MAX_RADIUS / count^CURVE pixels, at least MIN_RADIUS
    /// (defaults 0 and 0.4); 0: off. Default: the scene's `estimator_*` fields.
    #[arg(long, value_name = "MAX_RADIUS[,MIN[,CURVE]]",
          value_parser = nlifs::resolve::density_estimation::parse_flag)]
    density_estimation: Option<nlifs::resolve::density_estimation::DensityFlag>,
    /// Average this many temporal samples within each frame's shutter (1: no blur).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    motion_blur: u32,
    /// Open shutter as a fraction of the frame interval (for --motion-blur).
    #[arg(long, default_value_t = 0.5)]
    shutter: f64,
    /// Print the animation's frame count at --fps and exit (for splitting over a job array).
    #[arg(long)]
    print_frame_count: bool,
    #[command(flatten)]
    image: ImageArgs,
    #[command(flatten)]
    trace: TraceArgs,
    /// flam3's tone controls (average and density modes) over the scene's and its keys'.
    #[command(flatten)]
    tone: super::tone_args::ToneArgs,
    /// The key light's shadows and direction over the scene's and its keys'.
    #[command(flatten)]
    light: super::light_args::LightArgs,
    /// Depth of field over the scene's and its keys'.
    #[command(flatten)]
    lens: super::lens_args::LensArgs,
    /// Colour by function or by a palette (`--color`, `--palette`).
    #[command(flatten)]
    color: super::color_args::ColorArgs,
}

/// `nlifs snapshot`'s options, for `--renderer raytrace` (its defaults where left out).
#[derive(Args)]
struct TraceArgs {
    /// Ray tracing: samples per pixel (stratified; default 4).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    spp: Option<u32>,
    /// Ray tracing: n of W^n(A) (with --adaptive: the most refinement; default 6).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=16))]
    depth: Option<u32>,
    /// Ray tracing: initial object A: sphere (default), grid or a .glb/.gltf file.
    #[arg(long)]
    initial: Option<String>,
    /// Ray tracing: stop refining where a node projects smaller than a pixel.
    #[arg(long)]
    adaptive: bool,
    /// Ray tracing, with --adaptive: the projected size in pixels to stop at (default 1).
    #[arg(long, value_parser = positive_pixels)]
    stop_pixels: Option<f32>,
    /// Ray tracing: colour by function (default) or depth (`--color` and `--palette` colour
    /// the chaos game's points).
    #[arg(long, value_enum, value_name = "MODE")]
    raytrace_color: Option<ColorArg>,
    /// Ray tracing: no shadow rays.
    #[arg(long)]
    no_shadows: bool,
    /// Ray tracing: no ground plane.
    #[arg(long)]
    no_ground: bool,
    /// Ray tracing: background as sRGB hex (#rrggbb); default: the scene's.
    #[arg(long, value_parser = hex_color)]
    background: Option<[f32; 3]>,
}

impl TraceArgs {
    /// The flags given, by name (each applies to the ray tracer only).
    fn given(&self) -> Vec<&'static str> {
        [
            (self.spp.is_some(), "--spp"),
            (self.depth.is_some(), "--depth"),
            (self.initial.is_some(), "--initial"),
            (self.adaptive, "--adaptive"),
            (self.stop_pixels.is_some(), "--stop-pixels"),
            (self.raytrace_color.is_some(), "--raytrace-color"),
            (self.no_shadows, "--no-shadows"),
            (self.no_ground, "--no-ground"),
            (self.background.is_some(), "--background"),
        ]
        .into_iter()
        .filter_map(|(given, name)| given.then_some(name))
        .collect()
    }

    fn options(&self) -> anyhow::Result<TraceOptions> {
        let d = TraceOptions::default();
        let initial = match &self.initial {
            None => d.initial,
            Some(text) => match Initial::parse(text) {
                Initial::Gltf(path)
                    if !path
                        .extension()
                        .and_then(|e| e.to_str())
                        .is_some_and(|e| e.eq_ignore_ascii_case("glb") || e.eq_ignore_ascii_case("gltf")) =>
                {
                    return Err(BadInput(format!(
                        "--initial {}: expected sphere, grid or a .glb/.gltf file",
                        path.display()
                    ))
                    .into());
                }
                initial => initial,
            },
        };
        Ok(TraceOptions {
            spp: self.spp.unwrap_or(d.spp),
            depth: self.depth.unwrap_or(d.depth),
            adaptive: self.adaptive,
            stop_pixels: self.stop_pixels.unwrap_or(d.stop_pixels),
            initial,
            color_mode: self.raytrace_color.map_or(d.color_mode, Into::into),
            shadows: !self.no_shadows,
            ground: !self.no_ground,
            background: self.background.or(d.background),
        })
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum RecordBackend {
    Cpu,
    Gpu,
    Auto,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(super) enum RendererArg {
    Chaos,
    Raytrace,
}

pub fn record(args: RecordArgs) -> anyhow::Result<()> {
    let mut scene = load(&args.scene)?;
    args.tone.apply_to_scene(&mut scene);
    args.light.apply_to_scene(&mut scene);
    args.lens.apply_to_scene(&mut scene);
    args.color.apply(&mut scene.render)?;
    if let Some(de) = args.density_estimation {
        scene.render.density_estimation = de.0;
    }
    let options = args.image.for_frames()?;
    if nlifs::resolve::density_estimation::applies(scene.render.density_estimation.as_ref(), scene.render.mode)
        .is_some()
        && !options.is_plain_png()
    {
        return Err(BadInput(record::RecordError::EstimationLayers.to_string()).into());
    }
    let renderer = match args.renderer {
        RendererArg::Chaos => {
            if let Some(flag) = args.trace.given().first() {
                return Err(BadInput(format!("{flag} applies to --renderer raytrace, not to the chaos game")).into());
            }
            Renderer::Chaos
        }
        RendererArg::Raytrace => {
            if args.points_per_frame.is_some() {
                return Err(BadInput("--points-per-frame applies to the chaos game, not to --renderer raytrace (its detail is --depth and --spp)".into()).into());
            }
            if args.backend == RecordBackend::Gpu {
                return Err(BadInput("--renderer raytrace traces on the CPU; leave out --backend gpu".into()).into());
            }
            if !options.is_plain_png() {
                return Err(BadInput(record::RecordError::RaytraceLayers.to_string()).into());
            }
            if let Some(flag) = args.color.given() {
                return Err(BadInput(format!(
                    "{flag} colours the chaos game's points; the ray tracer colours by --raytrace-color function|depth"
                ))
                .into());
            }
            Renderer::Raytrace(args.trace.options()?)
        }
    };
    if args.video.is_some() && options.format == Format::Exr {
        return Err(BadInput("--video encodes PNG frames; leave out --video with --format exr".into()).into());
    }
    if !(args.fps > 0.0 && args.fps.is_finite()) {
        return Err(BadInput(format!("--fps must be a positive number, found {}", args.fps)).into());
    }
    if !(0.0..=1.0).contains(&args.shutter) {
        return Err(BadInput(format!("--shutter must lie in 0..1, found {}", args.shutter)).into());
    }
    if args.video.is_some() && !record::ffmpeg_available() {
        return Err(BadInput("--video needs ffmpeg, which was not found on PATH; install ffmpeg or leave out --video (frames can be encoded later)".into()).into());
    }
    let mut settings = RecordSettings::for_scene(&scene);
    settings.fps = args.fps;
    settings.width = args.width.unwrap_or(settings.width);
    settings.height = args.height.unwrap_or(settings.height);
    if let Some(points) = args.points_per_frame {
        ChunkPlan::new(points).map_err(|e| BadInput(format!("--points-per-frame: {e}")))?;
    }
    settings.points_per_frame = args.points_per_frame;
    settings.motion_blur_samples = args.motion_blur;
    settings.shutter = args.shutter;
    settings.renderer = renderer;
    let mut rec = Recorder::new(&scene, settings).map_err(|e| BadInput(e.to_string()))?;
    for warning in nlifs::scene::warnings::before_record(&scene) {
        eprintln!("warning: {warning}");
    }
    let count = rec.frame_count();
    if args.print_frame_count {
        println!("{count}");
        return Ok(());
    }
    let frames = args.frames.clone().unwrap_or(0..count);
    if frames.end > count {
        return Err(BadInput(format!(
            "--frames {}..{} goes past the animation's {count} frames (0..{count} at {} fps)",
            frames.start, frames.end, args.fps
        ))
        .into());
    }
    if frames.len() > record::MAX_FRAMES_PER_RUN as usize {
        return Err(
            BadInput(record::RecordError::TooManyFrames { start: frames.start, end: frames.end }.to_string()).into()
        );
    }
    if rec.settings().renderer == Renderer::Chaos {
        rec = choose_backend(rec, args.backend)?;
    } else {
        eprintln!("record: ray-traced on the CPU");
    }
    // The frames' folder and the video can be written: checked before any frame is made (and
    // after the GPU, whose absence is an error too: no folder is made for nothing).
    let first_frame = record::frame_path_as(&args.output, frames.start, options.format);
    super::probe_outputs(
        &[Some(first_frame.as_path()), args.video.as_deref()].into_iter().flatten().collect::<Vec<_>>(),
    )?;
    let todo = record::frames_to_render_as(&rec, &args.output, frames.clone(), args.resume, options.format).len();
    if args.resume && todo < frames.len() {
        eprintln!("resume: {} of {} frames already complete", frames.len() - todo, frames.len());
    }
    let bar = ProgressBar::new(todo as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "record [{bar:30}] {pos}/{len} frames, {per_sec}, {elapsed_precise} elapsed, {eta} left",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let report = record::record_as(&rec, &args.output, frames.clone(), args.resume, &options, &mut |done, _| {
        bar.set_position(done as u64)
    })
    .with_context(|| format!("recording {}", args.scene.display()))?;
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    eprintln!(
        "wrote {} frames to {} ({}×{}, {:.2} s, {:.2} frames/s){}",
        report.rendered.len(),
        args.output.display(),
        rec.settings().width,
        rec.settings().height,
        secs,
        report.rendered.len() as f64 / secs.max(1e-9),
        if report.skipped.is_empty() { String::new() } else { format!(", kept {} complete", report.skipped.len()) }
    );
    if !report.empty.is_empty() {
        eprintln!(
            "warning: {} of {} frames are empty, no point of the attractor landed in them (first: frame {}); \
             the camera looks away from it, or the IFS diverges (`nlifs info` shows its contractivity)",
            report.empty.len(),
            report.rendered.len(),
            report.empty[0]
        );
    }
    if let Some(video) = &args.video {
        record::encode_video(&args.output, frames, args.fps, video)?;
        eprintln!("wrote {}", video.display());
    }
    Ok(())
}

/// `rec` with its chaos game where `backend` says, and a line saying where that is: `auto`
/// takes the GPU only where the adapter is a hardware one (a software rasterizer is slower
/// than the CPU chaos game).
fn choose_backend(rec: Recorder<'_>, backend: RecordBackend) -> anyhow::Result<Recorder<'_>> {
    let ctx = match backend {
        RecordBackend::Cpu => None,
        RecordBackend::Gpu => Some(nlifs::gpu::GpuContext::headless().map_err(gpu_error)?),
        RecordBackend::Auto => match nlifs::gpu::GpuContext::headless() {
            Ok(ctx) if nlifs::gpu::batch::is_software(&ctx) => {
                eprintln!("record: chaos game on the CPU ({} is a software rasterizer)", ctx.describe());
                return Ok(rec);
            }
            Ok(ctx) => Some(ctx),
            Err(_) => {
                eprintln!("record: chaos game on the CPU (no GPU adapter)");
                return Ok(rec);
            }
        },
    };
    let Some(ctx) = ctx else {
        eprintln!("record: chaos game on the CPU");
        return Ok(rec);
    };
    let rec = rec.on_gpu(ctx).map_err(|e| match e {
        record::RecordError::Gpu(e) => gpu_error(e),
        e => e.into(),
    })?;
    eprintln!("record: chaos game on the GPU, {}", rec.gpu_adapter().unwrap_or_default());
    Ok(rec)
}
