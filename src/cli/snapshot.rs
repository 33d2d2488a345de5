//! `nlifs snapshot`: a ray-traced still of the deterministic approximation W^n(A), spheres or
//! meshes, at a fixed depth or refined adaptively to the pixel.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use clap::{Args, ValueEnum};

use nlifs::camera::OrbitCamera;
use nlifs::output::Provenance;
use nlifs::output::png::save_rgb8;
use nlifs::raytrace::{self, ColorMode, RaytraceSettings};
use nlifs::scene::Scene;
use nlifs::scene::spec::RenderSettings;
use nlifs::shot::{Framing, Shot};

use super::args::{GeometryArgs, check_png, hex_color, positive_pixels};
use super::{load, progress_bar};

#[derive(Clone, Copy, ValueEnum)]
pub(super) enum ColorArg {
    /// Per-function colour (the outermost function of each leaf).
    Function,
    /// Colour by depth.
    Depth,
}

impl From<ColorArg> for ColorMode {
    fn from(c: ColorArg) -> Self {
        match c {
            ColorArg::Function => ColorMode::Function,
            ColorArg::Depth => ColorMode::Depth,
        }
    }
}

/// What the still's camera is fitted to, where the scene leaves the camera's target and distance
/// open.
#[derive(Clone, Copy, Debug, Default, PartialEq, ValueEnum)]
pub(super) enum FramingArg {
    /// The traced geometry W^n(A) (the spheres reach a little beyond the attractor).
    #[default]
    Geometry,
    /// The attractor's points, as `nlifs render` frames them: a still and a point render of
    /// the same scene and size then share the camera, pixel for pixel.
    Points,
}

#[derive(Args)]
pub struct SnapshotArgs {
    scene: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, default_value_t = 960, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: u32,
    #[arg(long, default_value_t = 720, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: u32,
    /// Samples per pixel (stratified).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    spp: u32,
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Stop refining where a node projects smaller than a pixel (--depth becomes the cap).
    #[arg(long)]
    adaptive: bool,
    /// With --adaptive: stop where a node's sphere projects smaller than this many pixels
    /// (above 0, at most 1e6).
    #[arg(long, default_value_t = 1.0, value_parser = positive_pixels)]
    stop_pixels: f32,
    #[arg(long, value_enum, default_value = "function")]
    color: ColorArg,
    /// No shadow rays.
    #[arg(long)]
    no_shadows: bool,
    /// No ground plane.
    #[arg(long)]
    no_ground: bool,
    /// Background as sRGB hex (#rrggbb); default: the scene's.
    #[arg(long, value_parser = hex_color)]
    background: Option<[f32; 3]>,
    /// What the camera is fitted to where the scene leaves its target and distance open.
    #[arg(long, value_enum, default_value = "geometry")]
    framing: FramingArg,
}

/// The camera `nlifs render` of `scene` at `t_secs` uses for an image of `width`×`height`.
fn render_camera(scene: &Scene, t_secs: f64, width: u32, height: u32) -> anyhow::Result<OrbitCamera> {
    let settings = RenderSettings { width, height, ..scene.render.clone() };
    Ok(Shot::prepare(scene, t_secs, &settings, Framing::Fit, None)?.camera)
}

pub fn snapshot(args: SnapshotArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    check_png(&args.output)?;
    let settings = RaytraceSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        depth: args.geometry.depth,
        adaptive: args.adaptive,
        stop_pixels: args.stop_pixels,
        initial: args.geometry.initial()?,
        color_mode: args.color.into(),
        shadows: !args.no_shadows,
        ground: !args.no_ground,
        seed: scene.render.seed,
        background: args.background,
    };
    super::probe_output(&args.output)?;
    for w in nlifs::scene::warnings::scene_warnings(&scene, args.geometry.time) {
        eprintln!("warning: {w}");
    }
    let bar = progress_bar(args.height as u64, "trace");
    let cancel = AtomicBool::new(false);
    let camera = match args.framing {
        FramingArg::Geometry => None,
        FramingArg::Points => Some(render_camera(&scene, args.geometry.time, args.width, args.height)?),
    };
    let traced = raytrace::render(&scene, args.geometry.time, camera, &settings, &|d, _| bar.set_position(d), &cancel)?;
    bar.finish_and_clear();
    // The scene and the tracer's settings ride in the PNG, as in every image nlifs writes.
    let made_of = serde_json::json!({
        "width": args.width,
        "height": args.height,
        "spp": args.spp,
        "depth": args.geometry.depth,
        "adaptive": args.adaptive,
        "stop_pixels": args.stop_pixels,
        "shadows": !args.no_shadows,
        "ground": !args.no_ground,
    });
    // The default framing leaves the record as it was (same bytes as before the option).
    let mut made_of = made_of;
    if args.framing == FramingArg::Points {
        made_of["framing"] = "points".into();
    }
    let provenance = Provenance::for_command(&scene, args.geometry.time, "snapshot", made_of);
    save_rgb8(&args.output, &traced.image, Some(&provenance)).map_err(super::image_args::bad)?;
    if traced.stats.leaf_hits == 0 {
        eprintln!(
            "warning: the picture shows no part of W^{}(A): no ray hit it (the camera looks away from it)",
            args.geometry.depth
        );
    }
    let rays = traced.stats.primary_rays + traced.stats.shadow_rays;
    eprintln!(
        "wrote {} ({}×{}, {} spp, {} leaves to depth {}, {} nodes; build {:.2} s, trace {:.2} s, {:.2} Mrays/s)",
        args.output.display(),
        args.width,
        args.height,
        args.spp,
        traced.leaf_count,
        traced.max_depth,
        traced.node_count,
        traced.build_secs,
        traced.trace_secs,
        rays as f64 / traced.trace_secs / 1e6
    );
    Ok(())
}
