//! `nlifs export`: the attractor's points (PLY, glTF), the deterministic approximation W^n(A)
//! as a glTF mesh, and W^n(A) of spheres as a POV-Ray scene (what `bench raytrace` compares
//! against).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::{Args, Subcommand};

use nlifs::chaos_game::{self, CollectSink};
use nlifs::export::{
    point_bounds, write_glb_colors, write_glb_points_streamed, write_glb_positions, write_ply_header,
    write_ply_vertices,
};
use nlifs::io::write_atomic;
use nlifs::raytrace::{self, Initial, RaytraceSettings};
use nlifs::scene::Scene;
use nlifs::scene::spec::RenderSettings;
use nlifs::shot::{Framing, Shot};

use super::args::GeometryArgs;
use super::{BadInput, load, progress_bar};

#[derive(Subcommand)]
pub enum ExportCommand {
    /// The attractor's points with colour, as binary PLY (.ply) or glTF 2.0 binary (.glb).
    Points {
        scene: PathBuf,
        /// Output file, .ply or .glb.
        #[arg(short, long)]
        output: PathBuf,
        #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(1..=200_000_000))]
        points: u64,
        #[arg(long)]
        seed: Option<u32>,
        /// Scene time in seconds.
        #[arg(long, default_value_t = 0.0, value_parser = super::args::time_secs)]
        time: f64,
    },
    /// The deterministic approximation W^n(A) as a glTF 2.0 binary mesh (.glb).
    Mesh(ExportMeshArgs),
    /// W^n(A) of spheres as a POV-Ray 3.7 scene (for benchmarks).
    #[command(hide = true)]
    Pov(ExportPovArgs),
}

#[derive(Args)]
pub struct ExportMeshArgs {
    scene: PathBuf,
    /// Output .glb.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    geometry: GeometryArgs,
}

#[derive(Args)]
pub struct ExportPovArgs {
    scene: PathBuf,
    /// Output .pov.
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, default_value_t = 960)]
    width: u32,
    #[arg(long, default_value_t = 720)]
    height: u32,
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(0..=16))]
    depth: u32,
    #[arg(long, default_value_t = 0.0, value_parser = super::args::time_secs)]
    time: f64,
}

pub fn run(command: ExportCommand) -> anyhow::Result<()> {
    match command {
        ExportCommand::Points { scene, output, points, seed, time } => {
            export_points(&scene, &output, points, seed, time)
        }
        ExportCommand::Mesh(args) => export_mesh(args),
        ExportCommand::Pov(args) => export_pov(args),
    }
}

fn export_points(path: &Path, output: &Path, points: u64, seed: Option<u32>, time: f64) -> anyhow::Result<()> {
    let scene = load(path)?;
    let ext = output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    let glb = match ext.as_deref() {
        Some("glb") => true,
        Some("ply") => false,
        _ => return Err(BadInput(format!("output {} must end in .ply or .glb", output.display())).into()),
    };
    let settings = RenderSettings { points, seed: seed.unwrap_or(scene.render.seed), ..scene.render_at(time) };
    let shot = Shot::prepare(&scene, time, &settings, Framing::Scene, None).map_err(|e| BadInput(e.to_string()))?;
    super::probe_output(output)?;
    let (compiled, plan, seed) = (&shot.compiled, &shot.plan, settings.seed);
    let passes = if glb { 3 } else { 1 };
    let bar = progress_bar(passes * plan.chunks() as u64, "points");
    // The points in chunk order, window by window (each window's chunks in parallel), cut at
    // `points`: what the file holds, made again for each pass instead of held.
    let for_each_batch = |f: &mut dyn FnMut(&CollectSink, usize) -> std::io::Result<()>| -> std::io::Result<()> {
        use rayon::prelude::*;
        let window = (2 * rayon::current_num_threads()).max(4) as u32;
        let mut left = points as usize;
        let mut start = 0;
        while start < plan.chunks() && left > 0 {
            let end = (start + window).min(plan.chunks());
            let sinks: Vec<CollectSink> = (start..end)
                .into_par_iter()
                .map(|c| {
                    let mut s = CollectSink::default();
                    chaos_game::run_chunk(compiled, seed, shot.stream, c, plan.steps(c), &mut s);
                    bar.inc(1);
                    s
                })
                .collect();
            for s in &sinks {
                let n = s.points.len().min(left);
                f(s, n)?;
                left -= n;
            }
            start = end;
        }
        Ok(())
    };
    let colors_of = |s: &CollectSink, n: usize| -> Vec<[f32; 3]> {
        s.functions[..n].iter().map(|&f| compiled.colors[f as usize]).collect()
    };
    let written = write_atomic(output, |w| {
        if glb {
            let mut bounds = None;
            for_each_batch(&mut |s, n| {
                bounds = s.points[..n].iter().fold(bounds, |b, p| Some(point_bounds(b, *p)));
                Ok(())
            })?;
            write_glb_points_streamed(
                w,
                points,
                bounds,
                |w| for_each_batch(&mut |s, n| write_glb_positions(w, &s.points[..n])),
                |w| for_each_batch(&mut |s, n| write_glb_colors(w, &colors_of(s, n))),
            )
        } else {
            write_ply_header(w, points)?;
            for_each_batch(&mut |s, n| write_ply_vertices(w, &s.points[..n], &colors_of(s, n)))
        }
    });
    bar.finish_and_clear();
    written.with_context(|| format!("cannot write {}", output.display()))?;
    eprintln!("wrote {} ({} points)", output.display(), points);
    Ok(())
}

fn export_mesh(args: ExportMeshArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    if !args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
        return Err(BadInput(format!("output {} must end in .glb", args.output.display())).into());
    }
    let ifs = scene.at(args.geometry.time);
    let initial = args.geometry.initial()?;
    super::probe_output(&args.output)?;
    let h = raytrace::build_fixed(&ifs, &initial, args.geometry.depth)?;
    let colors: Vec<[f32; 3]> = ifs.active().iter().map(|&i| ifs.functions[i].color).collect();
    let names: Vec<String> = ifs.active().iter().map(|&i| ifs.functions[i].name.clone()).collect();
    write_atomic(&args.output, |w| raytrace::export::write_glb_mesh(w, &h, &colors, &names))
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    eprintln!("wrote {} ({} leaves of W^{}(A))", args.output.display(), h.leaf_count, args.geometry.depth);
    Ok(())
}

fn export_pov(args: ExportPovArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    super::probe_output(&args.output)?;
    write_pov(&scene, args.time, args.depth, args.width, args.height, &args.output)?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

/// Writes the .pov of W^depth(sphere) with the camera, lights and ground the tracer uses.
pub fn write_pov(
    scene: &Scene,
    t_secs: f64,
    depth: u32,
    width: u32,
    height: u32,
    output: &Path,
) -> anyhow::Result<raytrace::hierarchy::Hierarchy> {
    let ifs = scene.at(t_secs);
    let h = raytrace::build_fixed(&ifs, &Initial::Sphere, depth)?;
    let camera = scene.camera_for((h.bounds.0.as_dvec3(), h.bounds.1.as_dvec3()));
    let settings = RaytraceSettings { width, height, depth, ..Default::default() };
    let shading = raytrace::shading_for(scene, &ifs, &camera, &settings);
    write_atomic(output, |w| raytrace::export::write_pov(w, &h, &camera, &shading))
        .with_context(|| format!("cannot write {}", output.display()))?;
    Ok(h)
}
