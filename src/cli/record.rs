//! `nlifs record`: an animated scene rendered frame by frame to DIR/frame_NNNNN.png, resumable
//! and splittable over a job array, optionally encoded into a video with the system ffmpeg.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use nlifs::chaos_game::ChunkPlan;
use nlifs::output::Format;
use nlifs::record::{self, RecordSettings, Recorder};

use super::image_args::ImageArgs;
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
    /// Where frames are rendered: cpu, the only recorder in this build (it has no GPU path).
    #[arg(long, value_enum, default_value_t = RecordBackend::Cpu)]
    backend: RecordBackend,
    /// Keep frames that are already complete (decode fully); redo anything else.
    #[arg(long)]
    resume: bool,
    /// Also encode the frames into this video with the system ffmpeg.
    #[arg(long)]
    video: Option<PathBuf>,
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
}

/// The recorders that exist. A GPU recorder would add a variant here.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum RecordBackend {
    Cpu,
}

pub fn record(args: RecordArgs) -> anyhow::Result<()> {
    // The only recorder there is; a GPU one would be chosen here.
    let RecordBackend::Cpu = args.backend;
    let scene = load(&args.scene)?;
    let options = args.image.for_frames()?;
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
    let rec = Recorder::new(&scene, settings).map_err(|e| BadInput(e.to_string()))?;
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
