//! Renders scenes in closest mode on the CPU and resolves each accumulation twice, in the paper
//! look and in the solid look (`src/resolve.rs`), writing `<stem>-paper.png` and
//! `<stem>-solid.png` to compare by eye (and with `nlifs snapshot` of the same scene).
//!
//! `cargo run --release --example solid_look -- OUT_DIR [POINTS] [WIDTH HEIGHT] SCENE...`

use nlifs::resolve::{ResolveStyle, resolve_image};
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;

fn main() -> anyhow::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(!args.is_empty(), "usage: solid_look OUT_DIR [POINTS] [WIDTH HEIGHT] SCENE...");
    let out_dir = std::path::PathBuf::from(args.remove(0));
    let mut numbers = Vec::new();
    while let Some(n) = args.first().and_then(|a| a.parse::<u64>().ok()) {
        numbers.push(n);
        args.remove(0);
    }
    std::fs::create_dir_all(&out_dir)?;
    for path in &args {
        let scene = Scene::load(std::path::Path::new(path))?;
        let mut settings = scene.render_at(0.0);
        settings.mode = SplatMode::Closest;
        if let Some(&points) = numbers.first() {
            settings.points = points;
        }
        if let [_, width, height] = numbers[..] {
            (settings.width, settings.height) = (width as u32, height as u32);
        }
        let rendered = nlifs::render::render_cpu(&scene, 0.0, &settings, None, &|_, _| {})?;
        let stem = std::path::Path::new(path).file_stem().unwrap_or_default().to_string_lossy().into_owned();
        for (name, style) in [("paper", ResolveStyle::PAPER), ("solid", ResolveStyle::SOLID)] {
            let started = std::time::Instant::now();
            let image = resolve_image(&rendered.framebuffer, &rendered.camera, &style);
            let out = out_dir.join(format!("{stem}-{name}.png"));
            image.save(&out)?;
            eprintln!("{}: resolved in {:.3} s", out.display(), started.elapsed().as_secs_f64());
        }
    }
    Ok(())
}
