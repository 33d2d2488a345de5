//! The architecture, checked: the module graph of `src/` has no cycles and no lower layer
//! importing a higher one, every module has its place in the layer table, no source file is
//! longer than 700 lines without saying why, the binary includes no file from the library's
//! folders, and comments cite only repository files that exist.
//!
//! How the graph is read: every `.rs` file under `src/` is a module (its path gives its name;
//! `src/main.rs`, `src/cli/` and `src/bin/` are the binary, named `main…`). Comments and string
//! literals are blanked out, then the code is scanned for `use` trees and for paths in code that
//! start with `crate`, `super` or `self` (and `nlifs` in the binary); each path is resolved to
//! the longest module it names. `super` inside an inline module (`mod tests { use super::*; }`)
//! is that file's own module, so it is no edge. A module and its own submodules form one unit
//! (a `mod.rs` holds what its children share), so cycles are looked for between siblings: an
//! edge `a::x::p → a::y` counts as `a::x → a::y`, an edge `viewer::state → gpu::live` as
//! `viewer → gpu`, and an edge between a module and its ancestor is not a cycle edge.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

// ---------------------------------------------------------------------------------------------
// The layers.

/// Lower layers may not import higher ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Layer {
    Base,
    Model,
    Scene,
    Algorithms,
    Outputs,
    Live,
    Viewer,
    Cli,
}

/// Every module's layer: the entry with the longest matching module prefix. A new top-level
/// module fails `every_module_has_a_layer` until it is placed here, deliberately.
const LAYERS: &[(&str, Layer)] = &[
    // Leaf helpers that every layer may use.
    ("color", Layer::Base),
    ("rng", Layer::Base),
    ("cpu_time", Layer::Base),
    ("io", Layer::Base),
    ("simd", Layer::Base),
    ("camera", Layer::Base),
    ("palette", Layer::Base),
    // What differs between the desktop and the browser: clock, downloads, canvas, waiting.
    ("platform", Layer::Base),
    // The IFS: maps, grids, builders; flam3's flames (their data, variations and reader).
    ("model", Layer::Model),
    ("flame", Layer::Model),
    // Editable scene data and its format: the scene, its timeline, edits of it.
    ("scene", Layer::Scene),
    ("timeline", Layer::Scene),
    ("edit", Layer::Scene),
    // The CPU algorithms that turn an IFS into points and pixels.
    ("chaos_game", Layer::Algorithms),
    ("splat", Layer::Algorithms),
    ("resolve", Layer::Algorithms),
    // Whole renders and outputs, on the CPU and the GPU.
    ("shot", Layer::Outputs),
    ("render", Layer::Outputs),
    ("record", Layer::Outputs),
    ("raytrace", Layer::Outputs),
    ("gpu", Layer::Outputs),
    ("bench", Layer::Outputs),
    ("export", Layer::Outputs),
    ("output", Layer::Outputs),
    // The interactive view that the viewer drives.
    ("live", Layer::Live),
    ("viewer", Layer::Viewer),
    // The binary: src/main.rs, src/cli/.
    ("main", Layer::Cli),
    // The browser page's entry point (wasm32 only), the binary's counterpart there.
    ("web", Layer::Cli),
];

fn layer_of(module: &str) -> Option<Layer> {
    LAYERS
        .iter()
        .filter(|(prefix, _)| module == *prefix || module.starts_with(&format!("{prefix}::")))
        .max_by_key(|(prefix, _)| prefix.len())
        .map(|&(_, layer)| layer)
}

// ---------------------------------------------------------------------------------------------
// Reading the sources.

/// A source file: its path relative to the repository root and its text.
struct Source {
    path: String,
    text: String,
}

/// The `.rs` files under `src/`, sorted by path.
fn read_sources() -> Vec<Source> {
    let root = common::repo_path("");
    let mut paths = Vec::new();
    collect_files(&root.join("src"), "rs", &mut paths);
    paths
        .into_iter()
        .map(|p| Source {
            path: p.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/"),
            text: std::fs::read_to_string(&p).unwrap(),
        })
        .collect()
}

fn collect_files(dir: &Path, extension: &str, out: &mut Vec<std::path::PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect_files(&path, extension, out);
        } else if path.extension().is_some_and(|e| e == extension) {
            out.push(path);
        }
    }
}

/// The text with comments, string literals and char literals replaced by spaces (newlines
/// kept, so line numbers stay), leaving only code. Lifetimes and labels stay.
fn strip_comments_and_strings(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out: Vec<char> = Vec::with_capacity(c.len());
    let blank = |ch: char| if ch == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.extend(['/', '*'].map(blank));
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.extend([' ', ' ']);
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(c[i]));
                    i += 1;
                }
            }
        } else if let Some(hashes) = raw_string_hashes(&c, i) {
            // A raw string: r"…", r#"…"#, br"…".
            let mut j = i + if c[i] == 'b' { 2 } else { 1 } + hashes + 1;
            while j < c.len() && !(c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#'))) {
                j += 1;
            }
            let end = (j + 1 + hashes).min(c.len());
            out.extend(c[i..end].iter().map(|&ch| blank(ch)));
            i = end;
        } else if c[i] == '"' {
            let mut j = i + 1;
            while j < c.len() && c[j] != '"' {
                j += if c[j] == '\\' { 2 } else { 1 };
            }
            let end = (j + 1).min(c.len());
            out.extend(c[i..end].iter().map(|&ch| blank(ch)));
            i = end;
        } else if c[i] == '\'' && (c.get(i + 1) == Some(&'\\') || c.get(i + 2) == Some(&'\'')) {
            // A char literal ('x', '\n', '\'', '\u{..}'); otherwise a lifetime or label.
            let mut j = i + 1;
            if c[j] == '\\' {
                j += 2;
            } else {
                j += 1;
            }
            while j < c.len() && c[j] != '\'' {
                j += 1;
            }
            let end = (j + 1).min(c.len());
            out.extend(c[i..end].iter().map(|&ch| blank(ch)));
            i = end;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out.into_iter().collect()
}

/// The number of `#` of a raw string literal starting at `c[i]` (`r"`, `r#"`, `br"`), if one does.
fn raw_string_hashes(c: &[char], i: usize) -> Option<usize> {
    if i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_') {
        return None;
    }
    let mut j = match (c[i], c.get(i + 1)) {
        ('r', _) => i + 1,
        ('b', Some('r')) => i + 2,
        _ => return None,
    };
    let first_hash = j;
    while c.get(j) == Some(&'#') {
        j += 1;
    }
    (c.get(j) == Some(&'"')).then_some(j - first_hash)
}

#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    PathSep,
    Punct(char),
}

/// Identifiers, `::` and single punctuation characters of stripped code, with 1-based lines.
fn tokens(code: &str) -> Vec<(Token, usize)> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch.is_alphanumeric() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push((Token::Ident(c[start..i].iter().collect()), line));
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push((Token::PathSep, line));
            i += 2;
        } else {
            out.push((Token::Punct(ch), line));
            i += 1;
        }
    }
    out
}

/// A path as written in a file, with the inline modules (`mod tests { … }`) it sits in.
#[derive(Debug, PartialEq)]
struct WrittenPath {
    line: usize,
    inline_modules: Vec<String>,
    segments: Vec<String>,
}

/// The paths of a file's code that can name a module of this crate: every path of a `use` tree,
/// and paths in code starting with `crate`, `super`, `self` or one of `extern_roots`.
fn written_paths(code: &str, extern_roots: &[&str]) -> Vec<WrittenPath> {
    let toks = tokens(code);
    let mut out = Vec::new();
    let mut depth = 0usize;
    // (name, brace depth inside it)
    let mut inline: Vec<(String, usize)> = Vec::new();
    let starts = |s: &str| matches!(s, "crate" | "super" | "self") || extern_roots.contains(&s);
    let mut i = 0;
    while i < toks.len() {
        let inline_names = || inline.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
        match &toks[i].0 {
            Token::Punct('{') => depth += 1,
            Token::Punct('}') => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            Token::Ident(kw) if kw == "mod" => {
                if let (Some((Token::Ident(name), _)), Some((Token::Punct('{'), _))) =
                    (toks.get(i + 1), toks.get(i + 2))
                {
                    depth += 1;
                    inline.push((name.clone(), depth));
                    i += 3;
                    continue;
                }
            }
            Token::Ident(kw) if kw == "use" => {
                let line = toks[i].1;
                let mut end = i + 1;
                while end < toks.len() && toks[end].0 != Token::Punct(';') {
                    end += 1;
                }
                let mut trees = Vec::new();
                let mut at = i + 1;
                use_tree(&toks[..end], &mut at, Vec::new(), &mut trees);
                for segments in trees {
                    if segments.first().is_some_and(|s| starts(s)) {
                        out.push(WrittenPath { line, inline_modules: inline_names(), segments });
                    }
                }
                i = end + 1;
                continue;
            }
            Token::Ident(first) if starts(first) => {
                let after_sep = i > 0 && toks[i - 1].0 == Token::PathSep;
                let macro_crate = i > 0 && toks[i - 1].0 == Token::Punct('$');
                if !after_sep && !macro_crate {
                    let mut segments = vec![first.clone()];
                    let mut j = i + 1;
                    while let (Some((Token::PathSep, _)), Some((Token::Ident(s), _))) = (toks.get(j), toks.get(j + 1)) {
                        segments.push(s.clone());
                        j += 2;
                    }
                    if segments.len() > 1 {
                        out.push(WrittenPath { line: toks[i].1, inline_modules: inline_names(), segments });
                    }
                    i = j;
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// Expands the use tree at `toks[*at..]` (up to the end of `toks`) into full paths.
fn use_tree(toks: &[(Token, usize)], at: &mut usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = prefix;
    if toks.get(*at).map(|t| &t.0) == Some(&Token::PathSep) {
        *at += 1;
    }
    while let Some((tok, _)) = toks.get(*at) {
        match tok {
            Token::Ident(s) if s == "self" && !path.is_empty() => *at += 1,
            Token::Ident(s) => {
                path.push(s.clone());
                *at += 1;
                if let Some((Token::Ident(kw), _)) = toks.get(*at)
                    && kw == "as"
                {
                    *at += 2;
                }
            }
            Token::PathSep => *at += 1,
            Token::Punct('*') => *at += 1,
            Token::Punct('{') => {
                *at += 1;
                loop {
                    match toks.get(*at).map(|t| &t.0) {
                        None => return,
                        Some(Token::Punct('}')) => {
                            *at += 1;
                            return;
                        }
                        Some(Token::Punct(',')) => *at += 1,
                        Some(_) => use_tree(toks, at, path.clone(), out),
                    }
                }
            }
            Token::Punct(_) => break,
        }
    }
    out.push(path);
}

/// A module of the program: the file it lives in and its name (`viewer::state`, `main::cli`).
#[derive(Debug)]
struct ModuleFile {
    path: String,
    name: Vec<String>,
    binary: bool,
}

fn is_binary_file(path: &str) -> bool {
    path == "src/main.rs" || path.starts_with("src/cli/") || path.starts_with("src/bin/")
}

/// A file's module name from its path: `src/a/b.rs` and `src/a/b/mod.rs` are `a::b`,
/// `src/lib.rs` is the crate root (no segments); in the binary, `src/main.rs` is `main`,
/// `src/cli/x.rs` is `main::cli::x` and `src/bin/nlifs/x.rs` is `main::x`.
fn module_name(path: &str) -> Vec<String> {
    let rel = path.strip_prefix("src/").unwrap_or(path).trim_end_matches(".rs");
    let rel = rel.strip_suffix("/mod").unwrap_or(rel);
    if rel == "lib" {
        return Vec::new();
    }
    if rel == "main" {
        return vec!["main".into()];
    }
    if let Some(bin) = rel.strip_prefix("bin/") {
        let rest: Vec<String> = bin.split('/').skip(1).filter(|s| *s != "main").map(String::from).collect();
        return std::iter::once("main".to_string()).chain(rest).collect();
    }
    let segments = rel.split('/').map(String::from);
    if is_binary_file(path) {
        std::iter::once("main".to_string()).chain(segments).collect()
    } else {
        segments.collect()
    }
}

/// `#[path = "…"] mod name;` declarations: (declaring file, included file, module name).
fn path_includes(sources: &[Source]) -> Vec<(String, String, String)> {
    let mut out = Vec::new();
    for s in sources {
        let mut pending: Option<String> = None;
        for line in s.text.lines() {
            let t = line.trim();
            if let Some(rest) = t.strip_prefix("#[path = \"") {
                pending = rest.split('"').next().map(String::from);
            } else if let Some(target) = pending.take() {
                let name = t.trim_start_matches("pub ").strip_prefix("mod ").map(|r| r.trim_end_matches(';').trim());
                if let Some(name) = name {
                    let dir = Path::new(&s.path).parent().unwrap();
                    let file = dir.join(&target).to_string_lossy().replace('\\', "/");
                    out.push((s.path.clone(), file, name.to_string()));
                }
            }
        }
    }
    out
}

fn module_files(sources: &[Source]) -> Vec<ModuleFile> {
    let includes = path_includes(sources);
    sources
        .iter()
        .map(|s| {
            if let Some((from, _, name)) = includes.iter().find(|(_, file, _)| *file == s.path) {
                let mut parent = module_name(from);
                parent.push(name.clone());
                ModuleFile { path: s.path.clone(), name: parent, binary: is_binary_file(from) }
            } else {
                ModuleFile { path: s.path.clone(), name: module_name(&s.path), binary: is_binary_file(&s.path) }
            }
        })
        .collect()
}

/// One `from → to` dependency between modules, where it is written.
#[derive(Clone, Debug, PartialEq)]
struct Edge {
    from: String,
    to: String,
    file: String,
    line: usize,
    written: String,
}

/// Every module-to-module edge of the sources (self edges left out).
fn edges(sources: &[Source]) -> (Vec<ModuleFile>, Vec<Edge>) {
    let modules = module_files(sources);
    let lib: BTreeSet<&[String]> = modules.iter().filter(|m| !m.binary).map(|m| m.name.as_slice()).collect();
    let bin: BTreeSet<&[String]> = modules.iter().filter(|m| m.binary).map(|m| m.name.as_slice()).collect();
    let mut out = Vec::new();
    for (source, module) in sources.iter().zip(&modules) {
        let code = strip_comments_and_strings(&source.text);
        let roots: &[&str] = if module.binary { &["nlifs"] } else { &[] };
        for written in written_paths(&code, roots) {
            let here: Vec<String> = module.name.iter().chain(&written.inline_modules).cloned().collect();
            let mut segs = written.segments.iter().peekable();
            let (mut full, known) = match segs.peek().map(|s| s.as_str()) {
                Some("crate") if module.binary => (vec!["main".to_string()], &bin),
                Some("crate") | Some("nlifs") => (Vec::new(), &lib),
                _ => (here.clone(), if module.binary { &bin } else { &lib }),
            };
            if matches!(segs.peek().map(|s| s.as_str()), Some("crate" | "nlifs" | "self")) {
                segs.next();
            }
            while segs.peek().is_some_and(|s| *s == "super") {
                segs.next();
                full.pop();
            }
            full.extend(segs.cloned());
            let Some(target) = (1..=full.len()).rev().map(|n| &full[..n]).find(|p| known.contains(p)) else {
                continue;
            };
            if target != module.name.as_slice() {
                out.push(Edge {
                    from: module.name.join("::"),
                    to: target.join("::"),
                    file: source.path.clone(),
                    line: written.line,
                    written: written.segments.join("::"),
                });
            }
        }
    }
    (modules, out)
}

// ---------------------------------------------------------------------------------------------
// Cycles.

/// The edge between the siblings under the modules' deepest common ancestor
/// (`a::x::p → a::y` is `a::x → a::y`), or `None` when one module contains the other.
fn sibling_edge(from: &str, to: &str) -> Option<(String, String)> {
    let (a, b): (Vec<&str>, Vec<&str>) = (from.split("::").collect(), to.split("::").collect());
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    (common < a.len() && common < b.len()).then(|| (a[..=common].join("::"), b[..=common].join("::")))
}

/// Strongly connected components with more than one node (Tarjan), each sorted, in order.
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        s.on_stack.insert(v);
        for w in s.graph.get(v).into_iter().flatten() {
            if !s.index.contains_key(w.as_str()) {
                visit(s, w);
                let lw = s.low[w.as_str()];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w.as_str()) {
                let iw = s.index[w.as_str()];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on_stack.remove(w);
                component.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.out.push(component);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out.sort();
    s.out
}

/// A readable list of the cycles among siblings, each with the edges that make it and where
/// they are written; empty when there is none.
fn cycle_report(edges: &[Edge]) -> String {
    let mut lifted: BTreeMap<(String, String), Vec<&Edge>> = BTreeMap::new();
    for e in edges {
        if let Some(pair) = sibling_edge(&e.from, &e.to) {
            lifted.entry(pair).or_default().push(e);
        }
    }
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (a, b) in lifted.keys() {
        graph.entry(a.clone()).or_default().insert(b.clone());
    }
    let mut report = String::new();
    for component in cycles(&graph) {
        report += &format!("cycle between {}:\n", component.join(", "));
        for ((a, b), written) in &lifted {
            if component.contains(a) && component.contains(b) {
                report += &format!("  {a} -> {b}: {}\n", locations(written));
            }
        }
    }
    report
}

/// `file:line path` for each place, the paths of one `use` line as one tree.
fn locations(edges: &[&Edge]) -> String {
    let mut places: BTreeMap<(&str, usize), BTreeSet<&str>> = BTreeMap::new();
    for e in edges {
        places.entry((e.file.as_str(), e.line)).or_default().insert(e.written.as_str());
    }
    let mut out = Vec::new();
    for ((file, line), written) in places {
        let written: Vec<&str> = written.into_iter().collect();
        let text = if let [one] = written[..] {
            one.to_string()
        } else {
            // Several paths on one line: written as the `use` tree they came from.
            let split: Vec<Vec<&str>> = written.iter().map(|w| w.split("::").collect()).collect();
            let mut n = split.iter().map(Vec::len).min().unwrap();
            while !split.iter().all(|s| s[..n] == split[0][..n]) {
                n -= 1;
            }
            let rest: Vec<String> =
                split.iter().map(|s| if s.len() == n { "self".to_string() } else { s[n..].join("::") }).collect();
            format!("{}::{{{}}}", split[0][..n].join("::"), rest.join(", "))
        };
        out.push(format!("{file}:{line} `{text}`"));
    }
    out.join(", ")
}

/// Edges from a lower layer to a higher one, grouped by module pair.
fn layer_report(edges: &[Edge]) -> String {
    let mut upward: BTreeMap<(String, String), Vec<&Edge>> = BTreeMap::new();
    for e in edges {
        if let (Some(from), Some(to)) = (layer_of(&e.from), layer_of(&e.to))
            && from < to
        {
            upward.entry((e.from.clone(), e.to.clone())).or_default().push(e);
        }
    }
    let mut report = String::new();
    for ((a, b), written) in &upward {
        let (la, lb) = (layer_of(a).unwrap(), layer_of(b).unwrap());
        report += &format!("  {a} ({la:?}) imports {b} ({lb:?}): {}\n", locations(written));
    }
    report
}

// ---------------------------------------------------------------------------------------------
// The checks on the repository.

#[test]
fn no_module_cycles() {
    let (_, edges) = edges(&read_sources());
    assert!(edges.len() > 50, "only {} edges read: the parser is broken", edges.len());
    let report = cycle_report(&edges);
    assert!(report.is_empty(), "module cycles (break each by moving what both sides need below them):\n{report}");
}

#[test]
fn no_lower_layer_imports_a_higher_one() {
    let (_, edges) = edges(&read_sources());
    let report = layer_report(&edges);
    assert!(
        report.is_empty(),
        "lower layers importing higher ones (order: {:?}; table in tests/architecture.rs):\n{report}",
        [
            Layer::Base,
            Layer::Model,
            Layer::Scene,
            Layer::Algorithms,
            Layer::Outputs,
            Layer::Live,
            Layer::Viewer,
            Layer::Cli
        ]
    );
}

#[test]
fn every_module_has_a_layer() {
    let (modules, _) = edges(&read_sources());
    let missing: Vec<String> = modules
        .iter()
        .filter(|m| !m.name.is_empty() && layer_of(&m.name.join("::")).is_none())
        .map(|m| format!("  {} ({})", m.name.join("::"), m.path))
        .collect();
    assert!(missing.is_empty(), "modules missing from LAYERS in tests/architecture.rs:\n{}", missing.join("\n"));
}

/// The binary is built from its own folders; a `#[path]` into the library's folders compiles a
/// library file twice, as two different modules.
#[test]
fn the_binary_includes_no_library_file() {
    let sources = read_sources();
    let bad: Vec<String> = path_includes(&sources)
        .into_iter()
        .filter(|(from, file, _)| is_binary_file(from) && !is_binary_file(file))
        .map(|(from, file, name)| format!("  {from}: `#[path = ...] mod {name};` includes {file}"))
        .collect();
    assert!(bad.is_empty(), "the binary includes files of the library's folders:\n{}", bad.join("\n"));
}

/// Past this, a file wants splitting along a seam, or a first comment saying why not.
const MAX_LINES: usize = 700;
const LONG_FILE_REASON: &str = "longer than 700 lines because";

/// Whether the comment lines that open `text` say "longer than 700 lines because" (the words
/// may wrap across lines).
fn explains_its_length(text: &str) -> bool {
    let opening: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| l.starts_with("//") || l.is_empty())
        .map(|l| l.trim_start_matches('/').trim_start_matches('!'))
        .collect();
    opening.join(" ").split_whitespace().collect::<Vec<_>>().join(" ").contains(LONG_FILE_REASON)
}

#[test]
fn no_source_file_is_longer_than_700_lines_without_a_reason() {
    let mut long = Vec::new();
    for s in read_sources() {
        let lines = s.text.lines().count();
        if lines > MAX_LINES && !explains_its_length(&s.text) {
            long.push(format!("  {}: {lines} lines", s.path));
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines whose opening comment does not say \"{LONG_FILE_REASON} …\":\n{}",
        long.join("\n")
    );
}

/// Repository paths cited in `text`: `shaders/….wgsl`, `src/….rs`, `tests/….rs`, `docs/….md`.
fn cited_paths(text: &str) -> Vec<(usize, String)> {
    const KINDS: [(&str, &str); 4] = [("shaders/", ".wgsl"), ("src/", ".rs"), ("tests/", ".rs"), ("docs/", ".md")];
    let path_char = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '/' | '.' | '-');
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (start, _) in line.char_indices() {
            if line[..start].chars().next_back().is_some_and(path_char) {
                continue;
            }
            let Some((prefix, extension)) = KINDS.iter().find(|(p, _)| line[start..].starts_with(p)) else {
                continue;
            };
            let run: String = line[start..].chars().take_while(|&c| path_char(c)).collect();
            let run = run.trim_end_matches('.');
            if run.len() > prefix.len() + extension.len() && run.ends_with(extension) {
                out.push((n + 1, run.to_string()));
            }
        }
    }
    out
}

#[test]
fn cited_repository_files_exist() {
    let root = common::repo_path("");
    let mut files = Vec::new();
    collect_files(&root.join("src"), "rs", &mut files);
    collect_files(&root.join("shaders"), "wgsl", &mut files);
    collect_files(&root.join("tests"), "rs", &mut files);
    let this_file = root.join(file!());
    let mut missing = Vec::new();
    for file in files.iter().filter(|f| **f != this_file) {
        let text = std::fs::read_to_string(file).unwrap();
        for (line, cited) in cited_paths(&text) {
            if !root.join(&cited).exists() {
                missing.push(format!("  {}:{line}: {cited}", file.strip_prefix(&root).unwrap().display()));
            }
        }
    }
    assert!(missing.is_empty(), "comments cite files that do not exist:\n{}", missing.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// The checks checked, on small synthetic sources.

fn synthetic(files: &[(&str, &str)]) -> Vec<Source> {
    files.iter().map(|(path, text)| Source { path: path.to_string(), text: text.to_string() }).collect()
}

fn edge_pairs(sources: &[Source]) -> Vec<(String, String)> {
    let (_, edges) = edges(sources);
    let pairs: BTreeSet<(String, String)> = edges.into_iter().map(|e| (e.from, e.to)).collect();
    pairs.into_iter().collect()
}

fn pairs(list: &[(&str, &str)]) -> Vec<(String, String)> {
    list.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect()
}

#[test]
fn stripping_leaves_only_code() {
    let text = "let a = \"crate::x\"; // crate::y\n/* crate::z /* nested */ crate::w */ let b = r#\"crate::v \"quoted\"\"#;\nlet c = '\"'; let d: &'a str = x; let e = '\\''; crate::real::f();";
    let code = strip_comments_and_strings(text);
    assert_eq!(code.lines().count(), text.lines().count());
    assert_eq!(code.matches("crate::").count(), 1, "{code}");
    assert!(code.contains("crate::real::f()") && code.contains("&'a str"), "{code}");
}

#[test]
fn use_trees_expand_to_full_paths() {
    let code = "use crate::{a::{self, B}, c::D as E, f::*};\nuse std::fmt;\nuse super::g::{h, i::J};";
    let got: Vec<Vec<String>> = written_paths(code, &[]).into_iter().map(|p| p.segments).collect();
    let want: Vec<Vec<String>> =
        ["crate::a", "crate::a::B", "crate::c::D", "crate::f", "super::g::h", "super::g::i::J"]
            .iter()
            .map(|s| s.split("::").map(String::from).collect())
            .collect();
    assert_eq!(got, want);
    assert!(written_paths(code, &[]).iter().all(|p| p.line == 1 || p.line == 3));
}

#[test]
fn edges_resolve_to_the_longest_module_named() {
    let sources = synthetic(&[
        ("src/lib.rs", "pub mod a;\npub mod b;\npub mod viewer;"),
        ("src/a.rs", "use crate::b::deep::Thing;\nfn f() { crate::viewer::state::g(); let s = \"crate::viewer\"; }"),
        ("src/b/mod.rs", "pub mod deep;\nuse deep::Thing;"),
        ("src/b/deep.rs", "use super::Shared;\npub struct Thing;"),
        ("src/viewer/mod.rs", "pub mod state;\npub mod grid;"),
        (
            "src/viewer/state.rs",
            "use super::grid::pick;\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::a::f;\n}\nmacro_rules! m { () => { $crate::b::x() } }",
        ),
        ("src/viewer/grid.rs", "pub fn pick() { super::state::g(); self::pick(); }"),
        ("src/main.rs", "use nlifs::viewer::state;\nmod cli;\nfn main() { crate::cli::run(); nlifs::a::f(); }"),
        ("src/cli/mod.rs", "use nlifs::b::deep::Thing;\nuse crate::x;"),
    ]);
    assert_eq!(
        edge_pairs(&sources),
        pairs(&[
            ("a", "b::deep"),
            ("a", "viewer::state"),
            ("b::deep", "b"),
            ("main", "a"),
            ("main", "main::cli"),
            ("main", "viewer::state"),
            ("main::cli", "b::deep"),
            ("main::cli", "main"),
            ("viewer::grid", "viewer::state"),
            ("viewer::state", "a"),
            ("viewer::state", "viewer::grid"),
        ])
    );
}

#[test]
fn a_path_include_makes_a_library_file_part_of_the_binary() {
    let sources = synthetic(&[
        ("src/lib.rs", "pub mod scene;"),
        ("src/scene.rs", ""),
        ("src/main.rs", "#[path = \"scene/cli.rs\"]\nmod scene_cli;"),
        ("src/scene/cli.rs", "use super::helper;\nuse nlifs::scene::Scene;"),
    ]);
    assert_eq!(edge_pairs(&sources), pairs(&[("main::scene_cli", "main"), ("main::scene_cli", "scene")]));
    assert_eq!(
        path_includes(&sources),
        vec![("src/main.rs".to_string(), "src/scene/cli.rs".to_string(), "scene_cli".to_string())]
    );
}

#[test]
fn cycles_are_found_between_siblings_only() {
    let sources = synthetic(&[
        ("src/lib.rs", ""),
        ("src/scene.rs", "use crate::timeline::Key;"),
        ("src/timeline.rs", "use crate::splat::x;"),
        ("src/splat.rs", "use crate::scene::linear_to_srgb;"),
        ("src/rng.rs", "use crate::scene::Scene;"),
        ("src/viewer/mod.rs", "use crate::viewer::state::S;"),
        ("src/viewer/state.rs", "use super::grid_edit::g;\nuse super::Options;"),
        ("src/viewer/grid_edit.rs", "use super::state::S;"),
        ("src/viewer/ui.rs", "use super::state::S;"),
    ]);
    let (_, edges) = edges(&sources);
    let report = cycle_report(&edges);
    assert_eq!(
        report,
        "cycle between scene, splat, timeline:\n  \
         scene -> timeline: src/scene.rs:1 `crate::timeline::Key`\n  \
         splat -> scene: src/splat.rs:1 `crate::scene::linear_to_srgb`\n  \
         timeline -> splat: src/timeline.rs:1 `crate::splat::x`\n\
         cycle between viewer::grid_edit, viewer::state:\n  \
         viewer::grid_edit -> viewer::state: src/viewer/grid_edit.rs:1 `super::state::S`\n  \
         viewer::state -> viewer::grid_edit: src/viewer/state.rs:1 `super::grid_edit::g`\n"
    );
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (a, b) in [("a", "b"), ("b", "c"), ("c", "a"), ("d", "a"), ("e", "f"), ("f", "e"), ("g", "g")] {
        graph.entry(a.into()).or_default().insert(b.into());
    }
    assert_eq!(cycles(&graph), vec![vec!["a", "b", "c"], vec!["e", "f"]]);
    assert_eq!(sibling_edge("a::x::p", "a::y"), Some(("a::x".into(), "a::y".into())));
    assert_eq!(sibling_edge("viewer::state", "gpu::live"), Some(("viewer".into(), "gpu".into())));
    assert_eq!(sibling_edge("viewer::state", "viewer"), None);
}

#[test]
fn layers_are_read_from_the_table() {
    assert_eq!(layer_of("rng"), Some(Layer::Base));
    assert_eq!(layer_of("scene::timeline"), Some(Layer::Scene));
    assert_eq!(layer_of("gpu::readback"), Some(Layer::Outputs));
    assert_eq!(layer_of("main::cli::render"), Some(Layer::Cli));
    assert_eq!(layer_of("renderer"), None, "a prefix matches whole segments only");
    assert_eq!(layer_of("mystery"), None);
    let sources = synthetic(&[
        ("src/lib.rs", ""),
        ("src/scene.rs", "use crate::splat::SplatMode;\nuse crate::rng::Pcg32;"),
        ("src/splat.rs", "use crate::scene::linear_to_srgb;"),
    ]);
    let (_, edges) = edges(&sources);
    assert_eq!(
        layer_report(&edges),
        "  scene (Scene) imports splat (Algorithms): src/scene.rs:1 `crate::splat::SplatMode`\n"
    );
}

#[test]
fn a_long_file_explains_itself_in_its_opening_comment() {
    assert!(explains_its_length(
        "//! The scene checker.\n//!\n//! It is longer than 700\n//! lines because ...\nuse x;"
    ));
    assert!(!explains_its_length("//! The scene checker.\nuse x;\n// longer than 700 lines because ..."));
    assert!(!explains_its_length("fn f() {}"));
}

#[test]
fn citations_are_found_in_comments_and_prose() {
    // (This file is not scanned: these citations are made up.)
    let text = "//! The twin of `shaders/resolve.wgsl` (see src/gpu/resolve.rs).\n\
                // docs/architecture.md, tests/common/mod.rs; not src/gpu/*.rs nor vello/src/cpu/x.rs\n\
                // src/chaos_game/x86.rs.\n";
    let got: Vec<(usize, String)> = cited_paths(text);
    let want = [
        (1, "shaders/resolve.wgsl"),
        (1, "src/gpu/resolve.rs"),
        (2, "docs/architecture.md"),
        (2, "tests/common/mod.rs"),
        (3, "src/chaos_game/x86.rs"),
    ];
    assert_eq!(got, want.map(|(l, p)| (l, p.to_string())));
}
