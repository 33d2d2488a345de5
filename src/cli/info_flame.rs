//! `nlifs info FILE.flame`: the flames of a flam3 file (index, name, size, xforms, final xform,
//! variations used, palette form) and the reader's warnings, as a table or JSON. A file that
//! cannot be read is bad input (exit code 2).

use std::path::Path;

use nlifs::flame::Flame;
use nlifs::flame::xml::{FlameFile, read_file};
use nlifs::io::printable;

use super::BadInput;

/// The variations a flame uses (its xforms and final xform), in the table's order.
fn variations_used(f: &Flame) -> Vec<&'static str> {
    let mut used: Vec<_> =
        f.xforms.iter().chain(&f.final_xform).flat_map(|x| x.variations.iter().map(|t| t.variation)).collect();
    used.sort_by_key(|v| v.0);
    used.dedup();
    used.into_iter().map(|v| v.name()).collect()
}

fn json(path: &Path, file: &FlameFile) -> serde_json::Value {
    let flames: Vec<serde_json::Value> = file
        .flames
        .iter()
        .zip(&file.sources)
        .enumerate()
        .map(|(index, (f, src))| {
            serde_json::json!({
                "index": index,
                "name": f.name,
                "line": src.line,
                "size": f.size,
                "xforms": f.xforms.len(),
                "final_xform": f.final_xform.is_some(),
                "variations": variations_used(f),
                "palette": src.palette.describe(),
            })
        })
        .collect();
    serde_json::json!({ "file": path.display().to_string(), "flames": flames, "warnings": file.warnings })
}

pub fn info(path: &Path, as_json: bool) -> anyhow::Result<()> {
    let file = read_file(path).map_err(|e| BadInput(e.to_string()))?;
    if as_json {
        println!("{}", serde_json::to_string_pretty(&json(path, &file))?);
        return Ok(());
    }
    let shown = path.display().to_string();
    let n = file.flames.len();
    println!("{}: {n} flame{}", printable(&shown, false), if n == 1 { "" } else { "s" });
    // The name column as wide as the longest name, up to NAME_WIDTH_MAX characters.
    const NAME_WIDTH_MAX: usize = 40;
    let names: Vec<String> =
        file.flames.iter().map(|f| shortened(&printable(&f.name, false), NAME_WIDTH_MAX)).collect();
    let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0).max("name".len());
    println!(
        "{:>5} {:<width$} {:>11} {:>6} {:>5}  {:<24} variations",
        "index", "name", "size", "xforms", "final", "palette"
    );
    for (index, ((f, src), name)) in file.flames.iter().zip(&file.sources).zip(&names).enumerate() {
        println!(
            "{index:>5} {name:<width$} {:>11} {:>6} {:>5}  {:<24} {}",
            format!("{}×{}", f.size[0], f.size[1]),
            f.xforms.len(),
            if f.final_xform.is_some() { "yes" } else { "no" },
            src.palette.describe(),
            variations_used(f).join(" ")
        );
    }
    for w in &file.warnings {
        println!("warning: {}", printable(w, false));
    }
    Ok(())
}

/// `text` cut to at most `max` characters, the cut marked with an ellipsis.
fn shortened(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let mut cut: String = text.chars().take(max - 1).collect();
    cut.push('…');
    cut
}
