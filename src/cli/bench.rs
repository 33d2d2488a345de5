//! `nlifs bench`: throughput figures for the documents. The ray tracer against POV-Ray on the
//! same spheres, the GPU chaos game, a 1920×1080 recording on the CPU and the GPU, the CPU
//! chaos game on one core, and how much of an attractor a budget of points covers under each
//! probability choice.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::Context;
use clap::Subcommand;

use nlifs::cpu_time::cpu_secs;
use nlifs::io::save_png;
use nlifs::raytrace::{self, RaytraceSettings};
use nlifs::scene::spec::SplatMode;

use super::export::write_pov;
use super::{BadInput, load};

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Rays per second and 1920×1080 stills of tapering (n = 6) and plant2 (n = 7), side by side
    /// with POV-Ray 3.7 rendering the same spheres.
    Raytrace {
        /// Directory with the paper scenes.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        #[arg(long, default_value_t = 1920)]
        width: u32,
        #[arg(long, default_value_t = 1080)]
        height: u32,
        /// Samples per pixel (POV-Ray: +AM1 +A0.0 +R2, 1 + 4 rays per supersampled pixel).
        #[arg(long, default_value_t = 5)]
        spp: u32,
        /// Skip POV-Ray.
        #[arg(long)]
        no_povray: bool,
        /// Where to keep the images and .pov files.
        #[arg(long, default_value = "target/bench-raytrace")]
        out: PathBuf,
        /// Also write each scene's spheres, camera, lights and shading as `NAME_nN.trace` in
        /// the output folder, the input of the Embree comparison in tools/embree/.
        #[arg(long)]
        describe: bool,
    },
    /// GPU chaos game: points/s (map + splat) and frames/s at 1280×720, and frames to converge
    /// after a scene edit.
    Gpu {
        #[arg(default_value = "scenes/plant2.toml")]
        scene: PathBuf,
        /// Persistent GPU points.
        #[arg(long, default_value_t = 1 << 20)]
        points: u32,
        /// Steps per point per frame.
        #[arg(long, default_value_t = 1)]
        steps: u32,
        /// Frames to time.
        #[arg(long, default_value_t = 60)]
        frames: u32,
    },
    /// Frames per second of `nlifs record` at 1920×1080, the chaos game on the CPU and on the
    /// GPU (any adapter, a software one included, to measure it); with `--renderer raytrace`,
    /// ray-traced W^n(A) rebuilt every frame, and the rebuild's share of a frame.
    Record {
        #[arg(default_value = "scenes/twist-anim.toml")]
        scene: PathBuf,
        /// Frames to record (after one untimed frame).
        #[arg(long, default_value_t = 4)]
        frames: u32,
        #[arg(long, default_value_t = 1920)]
        width: u32,
        #[arg(long, default_value_t = 1080)]
        height: u32,
        /// Points per frame (default: the scene's).
        #[arg(long, value_parser = super::args::point_count)]
        points_per_frame: Option<u64>,
        /// Where the frames go (one folder per backend).
        #[arg(long, default_value = "target/bench-record")]
        out: PathBuf,
        /// chaos: the chaos game on the CPU and the GPU; raytrace: `record --renderer raytrace`.
        #[arg(long, value_enum, default_value_t = super::record::RendererArg::Chaos)]
        renderer: super::record::RendererArg,
        /// Ray tracing: n of W^n(A).
        #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(0..=16))]
        depth: u32,
        /// Ray tracing: samples per pixel.
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
        spp: u32,
    },
    /// CPU chaos game on one core: map only and map + splat at 1920×1080 in each mode, and a
    /// plain batched implementation of the map and the closest splat beside them.
    Cpu {
        /// Scene to run (default: the paper's tapering).
        #[arg(default_value = "scenes/tapering.toml")]
        scene: PathBuf,
        #[arg(long, default_value_t = 50_000_000)]
        points: u64,
        /// Rounds: each row runs once per round (the rows take turns) and keeps its best.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
    },
    /// The solid look's cost in `nlifs render` (closest mode, all threads): the whole command
    /// (`nlifs render SCENE --look ...` as a child process) in the paper look, with shading
    /// only, solid without shadows and solid, in R rounds of one run per look (the order
    /// rotating), and what each look adds in % of its render: the median over the rounds of
    /// its time minus the paper look's in the same round, with the middle half of the rounds;
    /// median and best wall time, mean CPU time. Then the parts in this process (best wall of
    /// R runs, mean CPU): preparation (bounds, camera), chaos game + splat, the shadow map's
    /// splat, each look's resolve and the PNG write.
    Look {
        #[arg(default_value = "scenes/plant2.toml")]
        scene: PathBuf,
        #[arg(long, default_value_t = 1920)]
        width: u32,
        #[arg(long, default_value_t = 1080)]
        height: u32,
        #[arg(long, default_value_t = 4_000_000)]
        points: u64,
        #[arg(long, default_value_t = 3)]
        repeats: usize,
    },
    /// How much of the attractor a fixed budget of points covers under uniform, contractivity
    /// and locally adaptive probabilities.
    Coverage {
        scene: PathBuf,
        #[arg(long, default_value_t = 200_000)]
        budget: u64,
        #[arg(long, default_value_t = 40_000_000)]
        reference: u64,
        #[arg(long, default_value_t = 512)]
        size: u32,
    },
    /// CPU render accumulation on all threads: per-thread framebuffers against one shared
    /// framebuffer, points/s per splat mode, side by side.
    Render(super::bench_render::BenchRenderArgs),
    /// A flame file's flames rendered once by `nlifs render` (one thread, then all), imported as
    /// scenes and rendered on one thread (the route of `view` and `record`), and by
    /// `flam3-render` (one thread), the same samples: CPU seconds of each whole process,
    /// samples per CPU second, nlifs / flam3.
    Flame {
        file: PathBuf,
        /// Where the images go.
        #[arg(long, default_value = "target/bench-flame")]
        out: PathBuf,
    },
}

pub fn run(command: BenchCommand) -> anyhow::Result<()> {
    match command {
        BenchCommand::Raytrace { scenes, width, height, spp, no_povray, out, describe } => {
            raytrace(&scenes, width, height, spp, no_povray, describe, &out)
        }
        BenchCommand::Gpu { scene, points, steps, frames } => {
            let scene = load(&scene)?;
            let report = nlifs::gpu::bench::run(&scene, points, steps, frames)?;
            println!("{report}");
            Ok(())
        }
        BenchCommand::Cpu { scene, points, repeats } => cpu(&scene, points, repeats),
        BenchCommand::Record { scene, frames, width, height, points_per_frame, out, renderer, depth, spp } => {
            if renderer == super::record::RendererArg::Raytrace {
                if points_per_frame.is_some() {
                    return Err(BadInput(
                        "--points-per-frame applies to the chaos game, not to --renderer raytrace".into(),
                    )
                    .into());
                }
                return record_raytrace(&scene, frames, width, height, depth, spp, &out);
            }
            record(&scene, frames, width, height, points_per_frame, &out)
        }
        BenchCommand::Render(args) => super::bench_render::run(args),
        BenchCommand::Flame { file, out } => super::render_flame::bench(&file, &out),
        BenchCommand::Look { scene, width, height, points, repeats } => {
            super::bench_look::run(&scene, width, height, points, repeats)
        }
        BenchCommand::Coverage { scene, budget, reference, size } => {
            let s = load(&scene)?;
            println!("{}: share of the attractor's {size}x{size} pixels lit by {budget} points", s.name);
            let shares = nlifs::bench::coverage(&s, budget, reference, size).map_err(|e| BadInput(e.to_string()))?;
            for (name, share) in shares {
                println!("  {name:<14} {:6.2} %", 100.0 * share);
            }
            Ok(())
        }
    }
}

fn record(
    path: &Path,
    frames: u32,
    width: u32,
    height: u32,
    points_per_frame: Option<u64>,
    out: &Path,
) -> anyhow::Result<()> {
    let scene = load(path)?;
    let settings = nlifs::record::RecordSettings {
        width,
        height,
        points_per_frame,
        ..nlifs::record::RecordSettings::for_scene(&scene)
    };
    let points = points_per_frame.unwrap_or(scene.render.points);
    let (cpu_frame, gpu_frame) = (out.join("cpu/frame_00000.png"), out.join("gpu/frame_00000.png"));
    super::probe_outputs(&[&cpu_frame, &gpu_frame])?;
    println!("record {}: {width}×{height}, {points} points per frame, {frames} frames", scene.name);
    for gpu in [false, true] {
        let ctx = if gpu {
            match nlifs::gpu::GpuContext::headless() {
                Ok(ctx) => Some(ctx),
                Err(e) => {
                    println!("  gpu: skipped ({e})");
                    continue;
                }
            }
        } else {
            None
        };
        let dir = out.join(if gpu { "gpu" } else { "cpu" });
        let r =
            nlifs::bench::record(&scene, settings.clone(), frames, ctx, &dir).map_err(|e| BadInput(e.to_string()))?;
        println!(
            "  {:<40} {:6.3} frames/s ({:.2} s wall, {:.2} s process CPU for {} frames) -> {}",
            r.backend,
            r.frames as f64 / r.secs,
            r.secs,
            r.cpu_secs,
            r.frames,
            dir.display()
        );
    }
    Ok(())
}

/// `bench record --renderer raytrace`: frames per second of the recording, then the same
/// frames' rebuilds of W^n(A) timed alone, as a share of a frame.
fn record_raytrace(
    path: &Path,
    frames: u32,
    width: u32,
    height: u32,
    depth: u32,
    spp: u32,
    out: &Path,
) -> anyhow::Result<()> {
    let scene = load(path)?;
    let options = nlifs::record::TraceOptions { depth, spp, ..Default::default() };
    let settings = nlifs::record::RecordSettings {
        width,
        height,
        renderer: nlifs::record::Renderer::Raytrace(options.clone()),
        ..nlifs::record::RecordSettings::for_scene(&scene)
    };
    let dir = out.join("raytrace");
    super::probe_output(&dir.join("frame_00000.png"))?;
    println!(
        "record {} --renderer raytrace: {width}×{height}, W^{depth}(sphere), {spp} spp, {frames} frames, {} threads",
        scene.name,
        rayon::current_num_threads()
    );
    let bad = |e: nlifs::record::RecordError| BadInput(e.to_string());
    let r = nlifs::bench::record(&scene, settings.clone(), frames, None, &dir).map_err(bad)?;
    let rebuild = nlifs::bench::raytrace_rebuilds(&scene, settings, &options, r.frames).map_err(bad)?;
    let (frame_secs, rebuild_secs) = (r.secs / r.frames as f64, rebuild.secs / rebuild.frames as f64);
    println!(
        "  {:6.3} frames/s ({:.2} s wall, {:.2} s process CPU for {} frames) -> {}",
        r.frames as f64 / r.secs,
        r.secs,
        r.cpu_secs,
        r.frames,
        dir.display()
    );
    let (frame_cpu, rebuild_cpu) = (r.cpu_secs / r.frames as f64, rebuild.cpu_secs / rebuild.frames as f64);
    println!(
        "  rebuild of W^{depth}(A) ({} leaves, {} nodes) per frame: {:.1} ms wall, {:.1} % of a frame's {:.0} ms; {:.1} ms CPU, {:.1} % of a frame's {:.0} ms",
        rebuild.leaf_count,
        rebuild.node_count,
        1e3 * rebuild_secs,
        100.0 * rebuild_secs / frame_secs,
        1e3 * frame_secs,
        1e3 * rebuild_cpu,
        100.0 * rebuild_cpu / frame_cpu,
        1e3 * frame_cpu
    );
    Ok(())
}

fn cpu(path: &Path, points: u64, repeats: usize) -> anyhow::Result<()> {
    let scene = load(path)?;
    let (width, height) = (1920, 1080);
    println!(
        "CPU chaos game, one thread, {} ({points} points, {width}x{height}, best of {} rounds)",
        scene.name,
        repeats.max(1)
    );
    let r = nlifs::bench::cpu(&scene, points, width, height, repeats.max(1)).map_err(|e| BadInput(e.to_string()))?;
    println!("  {:<52} {:>10} {:>12}", "", "M points/s", "per CPU s");
    let row = |name: &str, rate: nlifs::bench::Rate| {
        println!("  {name:<52} {:>10.1} {:>12.1}", rate.wall / 1e6, rate.cpu / 1e6);
    };
    row("nlifs map only", r.map);
    for (mode, rate) in &r.splat {
        row(&format!("nlifs map + splat {}", mode.name()), *rate);
    }
    if let Some(rate) = r.closest_with_shadow {
        row("nlifs map + splat closest + the look's shadow map", rate);
    }
    row("reference (16 chains x 64 rounds, scalar min) map only", r.reference_map);
    row("reference map + splat closest", r.reference_closest);
    row("nlifs map + reference splat closest", r.reference_splat);
    let closest = r.splat.iter().find(|(m, _)| *m == SplatMode::Closest).map_or_else(Default::default, |(_, c)| *c);
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
    println!(
        "  map + splat closest, nlifs / reference: {:.2}x per CPU s ({:.2}x wall)",
        ratio(closest.cpu, r.reference_closest.cpu),
        ratio(closest.wall, r.reference_closest.wall)
    );
    println!(
        "  map + splat closest, nlifs / nlifs map + reference splat: {:.2}x per CPU s",
        ratio(closest.cpu, r.reference_splat.cpu)
    );
    for (mode, rate) in r.splat.iter().filter(|(m, _)| *m != SplatMode::Closest) {
        println!(
            "  map + splat {} / map + splat closest: {:.2}x per CPU s ({:.2}x wall)",
            mode.name(),
            ratio(rate.cpu, closest.cpu),
            ratio(rate.wall, closest.wall)
        );
    }
    let level = nlifs::simd::SimdLevel::detect();
    let sums = match nlifs::simd::SumUpdates::detect() {
        nlifs::simd::SumUpdates::Scatter => "gathered and scattered a vector at a time",
        nlifs::simd::SumUpdates::Lanes => "updated lane by lane, a vector after their prefetch",
    };
    if level.avx512() {
        println!("  vector kernels: AVX-512; the accumulating modes' sums {sums} (NLIFS_SUM_UPDATES=scatter|lanes)");
    } else {
        println!("  vector kernels: {level:?}");
    }
    Ok(())
}

fn raytrace(
    scenes: &Path,
    width: u32,
    height: u32,
    spp: u32,
    no_povray: bool,
    describe: bool,
    out: &Path,
) -> anyhow::Result<()> {
    super::probe_output(&out.join("tapering_n6_nlifs.png"))?;
    let threads = rayon::current_num_threads();
    println!(
        "machine: {} threads in rayon's pool; {width}×{height}, {spp} spp, 2 lights with shadows, ground plane",
        threads
    );
    for (name, depth) in [("tapering", 6u32), ("plant2", 7)] {
        let scene = load(&scenes.join(format!("{name}.toml")))?;
        let settings = RaytraceSettings { width, height, spp, depth, ..Default::default() };
        if describe {
            let ifs = scene.at(0.0);
            let (hierarchy, camera) = raytrace::build(&scene, &ifs, 0.0, None, &settings)?;
            let shading = raytrace::shading_for(&scene, &ifs, &camera, &settings);
            let path = out.join(format!("{name}_n{depth}.trace"));
            let mut file = std::io::BufWriter::new(
                std::fs::File::create(&path).with_context(|| format!("cannot write {}", path.display()))?,
            );
            raytrace::tracer::write_trace_description(&hierarchy, &camera, &shading, &mut file)
                .and_then(|()| std::io::Write::flush(&mut file))
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        let cancel = AtomicBool::new(false);
        let cpu_before = cpu_secs().0;
        let traced = raytrace::render(&scene, 0.0, None, &settings, &|_, _| {}, &cancel)?;
        let cpu = cpu_secs().0 - cpu_before;
        let png = out.join(format!("{name}_n{depth}_nlifs.png"));
        save_png(&png, &traced.image)?;
        let rays = (traced.stats.primary_rays + traced.stats.shadow_rays) as f64;
        println!(
            "{name} n={depth}: {} spheres, build {:.3} s, trace {:.2} s wall, {:.2} s CPU (build + trace), {:.1} M rays ({:.2} M primary), {:.2} Mrays per CPU second  -> {}",
            traced.leaf_count,
            traced.build_secs,
            traced.trace_secs,
            cpu,
            rays / 1e6,
            traced.stats.primary_rays as f64 / 1e6,
            rays / cpu.max(1e-9) / 1e6,
            png.display()
        );
        if no_povray {
            continue;
        }
        let pov = out.join(format!("{name}_n{depth}.pov"));
        write_pov(&scene, 0.0, depth, width, height, &pov)?;
        let pov_png = out.join(format!("{name}_n{depth}_povray.png"));
        let start = Instant::now();
        let children_before = cpu_secs().1;
        let status = std::process::Command::new("povray")
            .arg(format!("+I{}", pov.display()))
            .arg(format!("+O{}", pov_png.display()))
            .args([
                format!("+W{width}"),
                format!("+H{height}"),
                "+A0.0".into(),
                "+AM1".into(),
                "+R2".into(),
                format!("+WT{threads}"),
                "-D".into(),
                "-V".into(),
                "+FN".into(),
                "-GA".into(),
            ])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .context("cannot run povray")?;
        let pov_secs = start.elapsed().as_secs_f64();
        let pov_cpu = cpu_secs().1 - children_before;
        if !status.success() {
            println!("  povray failed ({status})");
            continue;
        }
        let ours = traced.build_secs + traced.trace_secs;
        println!(
            "  POV-Ray 3.7: {pov_secs:.2} s wall, {pov_cpu:.2} s CPU (parse + bounding + trace, {threads} threads) -> {}\n  nlifs: {ours:.2} s wall, {cpu:.2} s CPU: {:.1}× faster by CPU time, {:.1}× by wall time",
            pov_png.display(),
            pov_cpu / cpu.max(1e-9),
            pov_secs / ours
        );
    }
    Ok(())
}
