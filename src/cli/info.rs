//! `nlifs info`: the contractivity, Lipschitz bounds, containment and probabilities of a
//! scene's functions, and for animated scenes the timeline check, as a table or JSON. Text
//! from the file (names, the description, the path) is printed with its control characters
//! escaped ([`printable`]); JSON escapes them itself. flam3 flame files are `info_flame.rs`'s.

use std::path::PathBuf;

use clap::Args;

use nlifs::io::printable;
use nlifs::model::IfsReport;
use nlifs::scene::warnings::{TIMELINE_SAMPLES_PER_INTERVAL, ifs_warnings};

use super::{load, progress_bar};

#[derive(Args)]
pub struct InfoArgs {
    /// A scene file, a PNG nlifs wrote, or a flam3 flame file (.flame, .flam3).
    scene: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Scene time in seconds (0 to 1e9).
    #[arg(long, default_value_t = 0.0, value_parser = super::args::time_secs)]
    time: f64,
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or("—".into(), |x| format!("{x:.4}"))
}

pub fn info(args: InfoArgs) -> anyhow::Result<()> {
    if nlifs::flame::xml::is_flame_path(&args.scene) {
        return super::info_flame::info(&args.scene, args.json);
    }
    // A PNG that nlifs wrote carries its scene (output::png): its info is that scene's.
    let scene = if nlifs::output::png::is_png(&args.scene) {
        let (scene, t_secs) = nlifs::output::png::load_scene_or_png(&args.scene).map_err(super::image_args::bad)?;
        let path = args.scene.display().to_string();
        println!("scene inside {} (the image was made at t = {t_secs} s)", printable(&path, false));
        scene
    } else {
        load(&args.scene)?
    };
    let ifs = scene.at(args.time);
    let mut report: IfsReport = ifs.report();
    // The model samples a builder onto a grid; the report names the kind the scene file gives.
    for (f, spec) in report.functions.iter_mut().zip(&scene.functions) {
        f.kind = spec.def.kind();
    }
    // Sampled along the whole timeline, for animated scenes.
    let bar = progress_bar(0, "timeline check");
    let timeline = nlifs::scene::timeline_check::check_timeline_with_progress(
        &scene,
        TIMELINE_SAMPLES_PER_INTERVAL,
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    );
    bar.finish_and_clear();
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        if let (Some(check), Some(obj)) = (&timeline, value.as_object_mut()) {
            obj.insert("timeline".into(), serde_json::to_value(check)?);
        }
        println!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    let d = scene.domain.dims();
    println!(
        "{} ({}D, grid {}×{}×{}, probabilities: {})",
        printable(&scene.name, false),
        report.dimension,
        d[0],
        d[1],
        d[2],
        report.probability_mode
    );
    if !scene.description.is_empty() {
        println!("{}", printable(&scene.description, true));
    }
    // With xaos the long-run share of each function's points, beside the probability of the
    // first draw.
    let share_header = if report.xaos { format!(" {:>11}", "xaos share") } else { String::new() };
    println!(
        "{:<12} {:<8} {:>10} {:>15} {:>10} {:>11}{share_header}",
        "function", "kind", "grid_ratio", "lipschitz_bound", "contained", "probability"
    );
    for f in &report.functions {
        let contained = match f.contained {
            None => "n/a".to_string(),
            Some(true) => "yes".to_string(),
            Some(false) => format!("NO ({})", f.outside.len()),
        };
        let share = if report.xaos { format!(" {:>11.4}", f.share) } else { String::new() };
        println!(
            "{:<12} {:<8} {:>10} {:>15} {:>10} {:>11.4}{share}",
            printable(&f.name, false),
            f.kind,
            fmt_opt(f.grid_ratio),
            fmt_opt(f.lipschitz_bound),
            contained,
            f.probability
        );
        for (k, p) in &f.outside {
            println!("    point {k} at ({:.4}, {:.4}, {:.4}) lies outside the grid", p[0], p[1], p[2]);
        }
    }
    // The same sentences `render`, `record` and `snapshot` print.
    for w in ifs_warnings(&report) {
        println!("warning: {}", printable(&w, false));
    }
    println!(
        "IFS: max grid_ratio {}, max lipschitz_bound {}, all contained: {}",
        fmt_opt(report.max_grid_ratio),
        fmt_opt(report.max_lipschitz_bound),
        report.all_contained.map_or("n/a", |c| if c { "yes" } else { "NO" })
    );
    if let Some(check) = timeline {
        print!(
            "timeline: {}, {:.3} s, {} keys; checked at {} times (keys and {} between each): ",
            check.loop_mode, check.duration_secs, check.keys, check.samples, check.samples_per_interval
        );
        if check.problems.is_empty() {
            println!("contractive and contained throughout");
        } else {
            println!("{} problems", check.problems.len());
            for p in &check.problems {
                println!("    {}", printable(&p.to_string(), false));
            }
        }
    }
    Ok(())
}
