//! `nlifs bench render`: the CPU render's accumulation on all threads of the pool, per-thread
//! framebuffers against one shared framebuffer (`nlifs::shot::Accumulation`), in every splat
//! mode, interleaved and the best of some repeats each, so that their ratio is meaningful on a
//! shared machine. Both ways must give the same framebuffer; the bench checks that too.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use nlifs::scene::spec::{RenderSettings, SplatMode};
use nlifs::shot::{Accumulation, Framing, Shot};

use super::{BadInput, load};

#[derive(Args)]
pub struct BenchRenderArgs {
    #[arg(default_value = "scenes/plant2.toml")]
    scene: PathBuf,
    #[arg(long, default_value_t = 20_000_000)]
    points: u64,
    #[arg(long, default_value_t = 1920)]
    width: u32,
    #[arg(long, default_value_t = 1080)]
    height: u32,
    #[arg(long, default_value_t = 3)]
    repeats: usize,
}

pub fn run(args: BenchRenderArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    let threads = rayon::current_num_threads();
    println!(
        "{}: {} points into {}x{} on {threads} threads, best of {} (M points/s)",
        scene.name, args.points, args.width, args.height, args.repeats
    );
    println!("{:<8} {:>11} {:>11} {:>7}", "mode", "per-thread", "shared", "ratio");
    for mode in SplatMode::ALL {
        let settings = RenderSettings {
            width: args.width,
            height: args.height,
            points: args.points,
            mode,
            seed: 1,
            ..scene.render.clone()
        };
        let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Scene, None).map_err(|e| BadInput(e.to_string()))?;
        let mut best = [f64::INFINITY; 2];
        let mut images = [None, None];
        for _ in 0..args.repeats.max(1) {
            for (i, way) in [Accumulation::PerThread, Accumulation::Shared].into_iter().enumerate() {
                let start = Instant::now();
                let fb = shot.splat_chunks(0..shot.plan.chunks(), way, || {});
                best[i] = best[i].min(start.elapsed().as_secs_f64());
                images[i] = Some((fb.closest, fb.accum));
            }
        }
        anyhow::ensure!(images[0] == images[1], "{}: the shared framebuffer differs from the merged ones", mode.name());
        let rate = |secs: f64| args.points as f64 / secs / 1e6;
        println!("{:<8} {:>11.1} {:>11.1} {:>7.2}", mode.name(), rate(best[0]), rate(best[1]), best[0] / best[1]);
    }
    Ok(())
}
