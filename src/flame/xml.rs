//! The flam3 XML reader: `.flame` / `.flam3` files into [`Flame`]s, read as flam3 reads them
//! (its `parser.c`, defaults from `flam3.c`'s `clear_cp` and `initialize_xforms`), with every
//! deviation from a clean file said in a warning and every malformed one an error that names
//! the file, line and column.
//!
//! A file may hold any number of `<flame>` elements at any depth (flam3 searches the whole tree:
//! `<flames>`, `<Flames>`, `<test>` roots), or several top-level `<flame>`s with no root at all,
//! which XML forbids: the text is wrapped in a synthetic root after its XML declaration, and
//! positions are mapped back to the original text. Sizes are bounded (file size, image size,
//! quality, xaos table) so that a hostile file cannot make the reader or the renderer run out
//! of memory or time.
//!
//! This file holds the document, positions, the `<flame>` attributes and the palette elements;
//! `xml_xform.rs` the `<xform>`, `<finalxform>` and `<symmetry>` elements.

use std::fmt::Display;
use std::path::{Path, PathBuf};

use super::palette::{self, HexLayout, InlineForm, PaletteEntries, PaletteLibrary, PaletteSource};
use super::xml_xform::{self, ParamIndex, XformRead};
use super::{FilterShape, Flame, PaletteMode, Xform};

/// Largest flame file read, in bytes: real files are kilobytes to a few megabytes.
pub const MAX_FILE_BYTES: u64 = 256 << 20;
/// Largest image side in pixels: the limit of nlifs's `--width` / `--height` and scene files'
/// `render.width` / `render.height`.
pub const MAX_SIDE_PX: u32 = 16384;
/// Largest samples per pixel, `quality` × 4^`zoom` (flam3 multiplies the density by the zoom's
/// area): real files use 50 to a few thousand.
pub const MAX_QUALITY: f64 = 1e6;
/// Largest supersampling factor.
pub const MAX_SUPERSAMPLE: u32 = 16;
/// Largest number of xaos entries in one flame (rows × xforms), 128 MiB of f64.
pub const MAX_XAOS_ENTRIES: usize = 16 << 20;

/// The flames of one file, in file order, and what the reader had to say about them.
#[derive(Clone, Debug, Default)]
pub struct FlameFile {
    pub flames: Vec<Flame>,
    /// One sentence each, naming the file, line, flame and (where one) xform.
    pub warnings: Vec<String>,
    /// Per flame (same order): where it is and how its palette was given.
    pub sources: Vec<FlameSource>,
}

/// Where a flame was in its file and how its palette was given.
#[derive(Clone, Debug, PartialEq)]
pub struct FlameSource {
    /// 1-based line of its `<flame` tag.
    pub line: u32,
    pub palette: PaletteSource,
}

/// A flame file that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum FlameError {
    #[error("cannot read {file}: {source}")]
    Io { file: String, source: std::io::Error },
    #[error("{file} is {size_bytes} bytes, more than the {limit_bytes} bytes a flame file may have")]
    TooLarge { file: String, size_bytes: u64, limit_bytes: u64 },
    #[error("{file}:{line}:{column}: {message}")]
    At { file: String, line: u32, column: u32, message: String },
    #[error("{file}: {message}")]
    File { file: String, message: String },
}

/// Where the reader finds flam3's palette library.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    pub palette_library: PathBuf,
}

impl Default for ReadOptions {
    /// The library at [`palette::palette_library_path`].
    fn default() -> Self {
        Self { palette_library: palette::palette_library_path() }
    }
}

/// Whether `path` names a flame file: extension `.flame` or `.flam3` (any case), or else text
/// whose first non-blank character is `<` (scene files are TOML, PNGs binary).
pub fn is_flame_path(path: &Path) -> bool {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if matches!(ext.as_deref(), Some("flame" | "flam3")) {
        return true;
    }
    let mut head = [0u8; 256];
    let n = std::fs::File::open(path).and_then(|mut f| std::io::Read::read(&mut f, &mut head)).unwrap_or(0);
    let head = head[..n].strip_prefix(b"\xef\xbb\xbf".as_slice()).unwrap_or(&head[..n]);
    head.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'<')
}

/// Reads a flame file (at most [`MAX_FILE_BYTES`]; checked before reading).
pub fn read_file(path: &Path) -> Result<FlameFile, FlameError> {
    read_file_with(path, &ReadOptions::default())
}

/// [`read_file`] with the palette library's place given.
pub fn read_file_with(path: &Path, options: &ReadOptions) -> Result<FlameFile, FlameError> {
    let file = path.display().to_string();
    let io = |source| FlameError::Io { file: file.clone(), source };
    let size_bytes = std::fs::metadata(path).map_err(io)?.len();
    if size_bytes > MAX_FILE_BYTES {
        return Err(FlameError::TooLarge { file, size_bytes, limit_bytes: MAX_FILE_BYTES });
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let (text, latin1) = match String::from_utf8(bytes) {
        Ok(text) => (text, false),
        // Older editors wrote names in Latin-1 (Windows-1252): one char per byte keeps them.
        Err(e) => (e.into_bytes().iter().map(|&b| b as char).collect(), true),
    };
    let mut out = read_str_with(&text, &file, options)?;
    if latin1 {
        out.warnings.insert(0, format!("{file}: not UTF-8; read as Latin-1"));
    }
    Ok(out)
}

/// Reads flame XML text; `file_name` names it in messages.
pub fn read_str(text: &str, file_name: &str) -> Result<FlameFile, FlameError> {
    read_str_with(text, file_name, &ReadOptions::default())
}

/// [`read_str`] with the palette library's place given.
pub fn read_str_with(text: &str, file_name: &str, options: &ReadOptions) -> Result<FlameFile, FlameError> {
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(FlameError::TooLarge {
            file: file_name.into(),
            size_bytes: text.len() as u64,
            limit_bytes: MAX_FILE_BYTES,
        });
    }
    let source = Source::wrap(text);
    let opts = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(&source.wrapped, opts).map_err(|e| {
        let pos = e.pos();
        let (line, column) = source.line_col(source.offset_of(pos.row, pos.col));
        let shown = pos.to_string();
        let message = e.to_string().replace(&format!(" at {shown}"), "").replace(&shown, "here");
        FlameError::At { file: file_name.into(), line, column, message: format!("malformed XML: {message}") }
    })?;
    let mut reader = Reader {
        file: file_name,
        source: &source,
        options,
        params: ParamIndex::new(),
        library: None,
        out: FlameFile::default(),
    };
    reader.scan(doc.root())?;
    if reader.out.flames.is_empty() {
        return Err(FlameError::File { file: file_name.into(), message: "no <flame> element".into() });
    }
    Ok(reader.out)
}

/// The text as parsed (wrapped in a synthetic root) and the map back to the original's lines.
pub(super) struct Source {
    wrapped: String,
    /// Byte offset in the original where the root's open tag was inserted.
    insert_at: usize,
    original_len: usize,
    /// Byte offsets of the original's line starts.
    line_starts: Vec<usize>,
    original: String,
}

const ROOT_OPEN: &str = "<nlifs-flame-file>";
const ROOT_CLOSE: &str = "</nlifs-flame-file>";

impl Source {
    fn wrap(text: &str) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // After the XML declaration (it must come first), before anything else.
        let trimmed = text.trim_start();
        let insert_at = if trimmed.starts_with("<?xml") {
            let decl_start = text.len() - trimmed.len();
            trimmed.find("?>").map_or(0, |end| decl_start + end + 2)
        } else {
            0
        };
        let (head, tail) = text.split_at(insert_at);
        // A DOCTYPE must stay before the root: such a file (one root by its DTD) is not wrapped.
        let wrap = !tail.contains("<!DOCTYPE");
        let wrapped = if wrap { format!("{head}{ROOT_OPEN}{tail}{ROOT_CLOSE}") } else { text.to_string() };
        let line_starts = std::iter::once(0)
            .chain(text.bytes().enumerate().filter(|(_, b)| *b == b'\n').map(|(i, _)| i + 1))
            .collect();
        Self {
            wrapped,
            insert_at: if wrap { insert_at } else { usize::MAX },
            original_len: text.len(),
            line_starts,
            original: text.to_string(),
        }
    }

    /// The original's byte offset of a byte offset in the wrapped text.
    fn original_offset(&self, wrapped_offset: usize) -> usize {
        let o = if wrapped_offset >= self.insert_at.saturating_add(ROOT_OPEN.len()) {
            wrapped_offset - ROOT_OPEN.len()
        } else {
            wrapped_offset.min(self.insert_at)
        };
        o.min(self.original_len)
    }

    /// The original's byte offset of a 1-based (row, column in chars) of the wrapped text.
    fn offset_of(&self, row: u32, col: u32) -> usize {
        let mut line_start = 0;
        for _ in 1..row {
            match self.wrapped[line_start..].find('\n') {
                Some(n) => line_start += n + 1,
                None => break,
            }
        }
        let in_line = self.wrapped[line_start..]
            .char_indices()
            .nth(col.saturating_sub(1) as usize)
            .map_or(self.wrapped.len() - line_start, |(i, _)| i);
        self.original_offset(line_start + in_line)
    }

    /// 1-based line and column (in chars) of an original byte offset.
    fn line_col(&self, offset: usize) -> (u32, u32) {
        let line = self.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = self.line_starts[line - 1];
        let end = offset.min(self.original.len());
        let column = self.original.get(start..end).map_or(end - start, |s| s.chars().count()) + 1;
        (line as u32, column as u32)
    }

    /// Line and column of a node of the parsed document.
    pub(super) fn node_pos(&self, node: roxmltree::Node) -> (u32, u32) {
        self.line_col(self.original_offset(node.range().start))
    }

    /// Line and column of an attribute's value.
    pub(super) fn attr_pos(&self, attr: &roxmltree::Attribute) -> (u32, u32) {
        self.line_col(self.original_offset(attr.range_value().start))
    }
}

/// Messages about one flame: its label ("flame 'name' (#2)") and the file's positions.
pub(super) struct Ctx<'a> {
    pub file: &'a str,
    pub source: &'a Source,
    pub flame: String,
    pub warnings: &'a mut Vec<String>,
}

impl Ctx<'_> {
    pub fn error_at(&self, (line, column): (u32, u32), what: impl Display) -> FlameError {
        FlameError::At { file: self.file.into(), line, column, message: format!("{}: {what}", self.flame) }
    }

    pub fn error(&self, node: roxmltree::Node, what: impl Display) -> FlameError {
        self.error_at(self.source.node_pos(node), what)
    }

    pub fn attr_error(&self, attr: &roxmltree::Attribute, what: impl Display) -> FlameError {
        self.error_at(self.source.attr_pos(attr), format!("attribute {}: {what}", attr.name()))
    }

    pub fn warn(&mut self, node: roxmltree::Node, what: impl Display) {
        let (line, _) = self.source.node_pos(node);
        self.warnings.push(format!("{}:{line}: {}: {what}", self.file, self.flame));
    }
}

/// A number as flam3's `strtod` reads one (surrounding blanks allowed, `nan` and `inf` too).
pub(super) fn number(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok()
}

/// Whitespace-separated numbers.
pub(super) fn numbers(s: &str) -> Option<Vec<f64>> {
    s.split_whitespace().map(number).collect()
}

/// An attribute's number, or an error naming it.
pub(super) fn attr_number(ctx: &Ctx, attr: &roxmltree::Attribute) -> Result<f64, FlameError> {
    number(attr.value()).ok_or_else(|| ctx.attr_error(attr, format!("'{}' is not a number", attr.value())))
}

/// An attribute's integer (flam3's `strtol`; an integral decimal like `2.0` is taken too).
pub(super) fn attr_int(ctx: &Ctx, attr: &roxmltree::Attribute) -> Result<i64, FlameError> {
    let v = attr.value().trim();
    v.parse::<i64>()
        .ok()
        .or_else(|| number(v).filter(|x| x.fract() == 0.0 && x.abs() < 1e15).map(|x| x as i64))
        .ok_or_else(|| ctx.attr_error(attr, format!("'{v}' is not an integer")))
}

/// Exactly `n` numbers, or an error naming the attribute.
pub(super) fn attr_numbers(ctx: &Ctx, attr: &roxmltree::Attribute, n: usize) -> Result<Vec<f64>, FlameError> {
    match numbers(attr.value()) {
        Some(v) if v.len() == n => Ok(v),
        _ => Err(ctx.attr_error(attr, format!("expected {n} numbers, found '{}'", attr.value()))),
    }
}

/// flam3's defaults (`clear_cp` with defaults on) for everything but the xforms and palette.
fn default_flame() -> Flame {
    Flame {
        name: String::new(),
        size: [100, 100],
        center: [0.0, 0.0],
        scale: 50.0,
        rotate: 0.0,
        zoom: 0.0,
        quality: 1.0,
        supersample: 1,
        filter: 0.5,
        filter_shape: FilterShape::Gaussian,
        brightness: 4.0,
        gamma: 4.0,
        gamma_threshold: 0.01,
        vibrancy: 1.0,
        highlight_power: -1.0,
        background: [0.0; 3],
        estimator_radius: 9.0,
        estimator_minimum: 0.0,
        estimator_curve: 0.4,
        palette_mode: PaletteMode::Step,
        palette: vec![[0.0; 4]; palette::PALETTE_LEN],
        xforms: Vec::new(),
        final_xform: None,
    }
}

/// flam3's `filter_shape` names.
fn filter_shape(name: &str) -> Option<FilterShape> {
    use FilterShape::*;
    Some(match name {
        "gaussian" => Gaussian,
        "hermite" => Hermite,
        "box" => Box,
        "triangle" => Triangle,
        "bell" => Bell,
        "bspline" => BSpline,
        "mitchell" => Mitchell,
        "blackman" => Blackman,
        "catrom" => Catrom,
        "hanning" => Hanning,
        "hamming" => Hamming,
        "lanczos3" => Lanczos3,
        "lanczos2" => Lanczos2,
        "quadratic" => Quadratic,
        _ => return None,
    })
}

/// `<flame>` attributes flam3 reads that change nothing in a still image (animation, batching,
/// metadata that flam3 writes).
const STILL_IGNORED: &[&str] = &[
    "time",
    "interpolation",
    "interpolation_type",
    "interpolation_space",
    "palette_interpolation",
    "hsv_rgb_palette_blend",
    "temporal_filter_type",
    "temporal_filter_width",
    "temporal_filter_exp",
    "temporal_samples",
    "passes",
    "version",
    "url",
    "nick",
    "notes",
];

struct Reader<'a> {
    file: &'a str,
    source: &'a Source,
    options: &'a ReadOptions,
    params: ParamIndex,
    /// Read on first use.
    library: Option<PaletteLibrary>,
    out: FlameFile,
}

impl Reader<'_> {
    /// Every `<flame>` below `node`, in document order (flam3's `scan_for_flame_nodes`).
    fn scan(&mut self, node: roxmltree::Node) -> Result<(), FlameError> {
        for child in node.children().filter(|n| n.is_element()) {
            if child.has_tag_name("flame") {
                self.flame(child)?;
            } else {
                self.scan(child)?;
            }
        }
        Ok(())
    }

    fn library(&mut self, ctx: &Ctx, node: roxmltree::Node) -> Result<&PaletteLibrary, FlameError> {
        if self.library.is_none() {
            let path = &self.options.palette_library;
            let lib = PaletteLibrary::read(path).map_err(|why| {
                ctx.error(
                    node,
                    format!("the palette is a number from flam3's palette library, and {why} (NLIFS_FLAM3_PALETTES names another file)"),
                )
            })?;
            self.library = Some(lib);
        }
        Ok(self.library.get_or_insert_with(PaletteLibrary::default))
    }

    /// One `<flame>`.
    fn flame(&mut self, node: roxmltree::Node) -> Result<(), FlameError> {
        let index = self.out.flames.len();
        let name = node.attribute("name").unwrap_or("");
        let label = if name.is_empty() { format!("flame #{index}") } else { format!("flame #{index} '{name}'") };
        let mut warnings = std::mem::take(&mut self.out.warnings);
        let mut ctx = Ctx { file: self.file, source: self.source, flame: label, warnings: &mut warnings };
        let result = self.flame_in(node, &mut ctx);
        self.out.warnings = warnings;
        let (flame, palette) = result?;
        self.out.flames.push(flame);
        self.out.sources.push(FlameSource { line: self.source.node_pos(node).0, palette });
        Ok(())
    }

    fn flame_in(&mut self, node: roxmltree::Node, ctx: &mut Ctx) -> Result<(Flame, PaletteSource), FlameError> {
        let mut f = default_flame();
        let mut library_number: Option<i32> = None;
        let mut hue_turns = 0.0;
        let mut solo_xform: Option<i64> = None;
        let mut ignored: Vec<&str> = Vec::new();
        for attr in node.attributes() {
            // A value that is not finite: warned about, the default kept.
            let finite = |ctx: &mut Ctx, v: f64, what: &str| -> Option<f64> {
                if v.is_finite() {
                    Some(v)
                } else {
                    ctx.warn(node, format!("{what} is {v}; the default is used"));
                    None
                }
            };
            match attr.name() {
                "name" => f.name = attr.value().to_string(),
                "palette" => {
                    let n = attr_int(ctx, &attr)?;
                    // -1 is flam3's "random palette", which a still does not pick: no library palette.
                    if n != -1 {
                        library_number = Some(i32::try_from(n).map_err(|_| ctx.attr_error(&attr, "out of range"))?);
                    }
                }
                "size" => {
                    let v = attr_numbers(ctx, &attr, 2)?;
                    let side =
                        |x: f64| (x.fract() == 0.0 && x >= 1.0 && x <= f64::from(MAX_SIDE_PX)).then_some(x as u32);
                    match (side(v[0]), side(v[1])) {
                        (Some(w), Some(h)) => f.size = [w, h],
                        _ => {
                            return Err(ctx.attr_error(
                                &attr,
                                format!(
                                    "'{}' is not a width and height in pixels from 1 to {MAX_SIDE_PX}",
                                    attr.value()
                                ),
                            ));
                        }
                    }
                }
                "center" => {
                    let v = attr_numbers(ctx, &attr, 2)?;
                    for k in 0..2 {
                        if let Some(x) = finite(ctx, v[k], &format!("center[{k}]")) {
                            f.center[k] = x;
                        }
                    }
                }
                "background" => {
                    let v = attr_numbers(ctx, &attr, 3)?;
                    for k in 0..3 {
                        if let Some(x) = finite(ctx, v[k], &format!("background[{k}]")) {
                            f.background[k] = x;
                        }
                    }
                }
                "scale" | "rotate" | "zoom" | "filter" | "brightness" | "gamma" | "gamma_threshold" | "vibrancy"
                | "highlight_power" | "estimator_radius" | "estimator_minimum" | "estimator_curve" | "quality"
                | "hue" => {
                    let v = attr_number(ctx, &attr)?;
                    let Some(v) = finite(ctx, v, attr.name()) else { continue };
                    match attr.name() {
                        "scale" => f.scale = v,
                        "rotate" => f.rotate = v,
                        "zoom" => f.zoom = v,
                        "filter" => f.filter = v,
                        "brightness" => f.brightness = v,
                        "gamma" => f.gamma = v,
                        "gamma_threshold" => f.gamma_threshold = v,
                        "vibrancy" => f.vibrancy = v,
                        "highlight_power" => f.highlight_power = v,
                        "estimator_radius" => f.estimator_radius = v,
                        "estimator_minimum" => f.estimator_minimum = v,
                        "estimator_curve" => f.estimator_curve = v,
                        "quality" if v > 0.0 => f.quality = v,
                        "quality" => ctx.warn(node, format!("quality {v} is not positive; the default 1 is used")),
                        // C's fmod, as flam3: the sign stays.
                        _ => hue_turns = v % 1.0,
                    }
                }
                "supersample" | "oversample" => {
                    let v = attr_int(ctx, &attr)?;
                    if v < 1 {
                        ctx.warn(node, format!("supersample {v} is below 1; 1 is used"));
                    } else if v > i64::from(MAX_SUPERSAMPLE) {
                        return Err(ctx.attr_error(&attr, format!("{v} is more than {MAX_SUPERSAMPLE}")));
                    } else {
                        f.supersample = v as u32;
                    }
                }
                "filter_shape" => match filter_shape(attr.value()) {
                    Some(shape) => f.filter_shape = shape,
                    None => ctx.warn(node, format!("unknown filter_shape '{}'; gaussian is used", attr.value())),
                },
                "palette_mode" => match attr.value() {
                    "step" => f.palette_mode = PaletteMode::Step,
                    "linear" => f.palette_mode = PaletteMode::Linear,
                    other => ctx.warn(node, format!("unknown palette_mode '{other}'; step is used")),
                },
                "soloxform" => solo_xform = Some(attr_number(ctx, &attr)? as i64),
                name if STILL_IGNORED.contains(&name) => {}
                name => ignored.push(name),
            }
        }
        if !ignored.is_empty() {
            ctx.warn(node, format!("attributes flam3 does not read, ignored: {}", ignored.join(", ")));
        }
        let effective_quality = f.quality * 4f64.powf(f.zoom.max(0.0));
        if !(effective_quality <= MAX_QUALITY) {
            return Err(ctx.error(
                node,
                format!(
                    "quality {} at zoom {} is {effective_quality:.3e} samples per pixel, more than the {MAX_QUALITY:e} allowed",
                    f.quality, f.zoom
                ),
            ));
        }

        // Children in document order, as flam3 adds xforms.
        let mut entries = PaletteEntries::default();
        let mut forms: Vec<InlineForm> = Vec::new();
        let mut blend: Option<(i32, f64, i32, f64, f64)> = None;
        let mut std_xforms: Vec<Xform> = Vec::new();
        let mut chaos_rows: Vec<Option<(Vec<f64>, roxmltree::Node)>> = Vec::new();
        let mut final_xform: Option<Xform> = None;
        let mut palette_issues = PaletteIssues::default();
        let mut motion_warned = false;
        for child in node.children().filter(|n| n.is_element()) {
            match child.tag_name().name() {
                "color" => {
                    palette_color(ctx, child, &mut entries, &mut palette_issues)?;
                    forms.push(InlineForm::Color);
                }
                "colors" => {
                    palette_colors(ctx, child, &mut entries, &mut palette_issues)?;
                    forms.push(InlineForm::Colors);
                }
                "palette" => {
                    if let Some(b) = palette_element(ctx, child, &mut entries, &mut palette_issues)? {
                        blend = Some(b);
                    } else {
                        forms.push(InlineForm::HexPalette);
                    }
                }
                "symmetry" => {
                    let added = xml_xform::symmetry(ctx, child)?;
                    chaos_rows.extend(added.iter().map(|_| None));
                    std_xforms.extend(added);
                }
                "xform" | "finalxform" => {
                    let is_final = child.has_tag_name("finalxform");
                    if is_final && final_xform.is_some() {
                        return Err(ctx.error(child, "more than one <finalxform>"));
                    }
                    let array_len = std_xforms.len() + usize::from(final_xform.is_some());
                    let label =
                        if is_final { "final xform".to_string() } else { format!("xform {}", std_xforms.len()) };
                    let XformRead { xform, chaos } =
                        xml_xform::xform(ctx, child, &self.params, is_final, array_len, &label)?;
                    if child.children().any(|n| n.has_tag_name("motion")) && !motion_warned {
                        motion_warned = true;
                        ctx.warn(child, "<motion> elements (animation) are ignored");
                    }
                    if is_final {
                        final_xform = Some(xform);
                    } else {
                        std_xforms.push(xform);
                        chaos_rows.push(chaos.map(|row| (row, child)));
                    }
                }
                "edit" => {}
                other => ctx.warn(child, format!("element <{other}> ignored")),
            }
        }
        if std_xforms.is_empty() {
            let what = if final_xform.is_some() { "has only a final xform" } else { "has no <xform>" };
            return Err(ctx.error(node, format!("{what}, nothing to draw (a size template such as vidres.flam3?)")));
        }
        if !(std_xforms.iter().map(|x| x.weight).sum::<f64>() > 0.0) {
            return Err(ctx.error(node, "the xforms' weights sum to 0, nothing to draw"));
        }
        palette_issues.report(ctx, node);

        // Xaos rows, padded with 1 to the number of xforms (flam3 writes rows without their
        // trailing 1s); longer rows are cut.
        let n = std_xforms.len();
        let rows = chaos_rows.iter().filter(|r| r.is_some()).count();
        if rows.saturating_mul(n) > MAX_XAOS_ENTRIES {
            return Err(
                ctx.error(node, format!("{rows} xaos rows of {n} entries are more than {MAX_XAOS_ENTRIES} entries"))
            );
        }
        for (i, (x, row)) in std_xforms.iter_mut().zip(chaos_rows).enumerate() {
            let Some((mut row, at)) = row else { continue };
            if row.len() > n {
                ctx.warn(
                    at,
                    format!("xform {i}: chaos has {} entries for {n} xforms; the extra ones are ignored", row.len()),
                );
                row.truncate(n);
            }
            row.resize(n, 1.0);
            x.chaos = row;
        }
        if let Some(solo) = solo_xform.filter(|&s| s >= 0) {
            for (i, x) in std_xforms.iter_mut().enumerate() {
                if i as i64 != solo {
                    x.opacity = 0.0;
                }
            }
        }
        f.xforms = std_xforms;
        f.final_xform = final_xform;

        // The palette: a library number replaces every inline entry (flam3 applies it after
        // reading the element); then the missing entries are interpolated.
        let given = entries.given();
        let source = if let Some(number) = library_number {
            if given > 0 {
                ctx.warn(
                    node,
                    format!("palette=\"{number}\" replaces the {given} inline palette entries, as in flam3"),
                );
            }
            match self.library(ctx, node)?.get(number, hue_turns) {
                Some(p) => f.palette = p,
                None => {
                    let path = self.options.palette_library.display();
                    ctx.warn(node, format!("palette {number} is not in {path}; white is used, as flam3 does"));
                    f.palette = palette::white();
                }
            }
            PaletteSource::Library { number, hue_turns }
        } else if let Some((index0, hue0, index1, hue1, blend)) = blend {
            let lib = self.library(ctx, node)?;
            let get = |n: i32, hue: f64| lib.get(n, hue);
            let (p0, p1) = (get(index0, hue0), get(index1, hue1));
            let missing: Vec<i32> =
                [(index0, &p0), (index1, &p1)].iter().filter(|(_, p)| p.is_none()).map(|(n, _)| *n).collect();
            let path = lib.path.display().to_string();
            f.palette =
                palette::blend_hsv(&p0.unwrap_or_else(palette::white), &p1.unwrap_or_else(palette::white), blend);
            if !missing.is_empty() {
                ctx.warn(
                    node,
                    format!("palettes {missing:?} are not in {path}; white is used for them, as flam3 does"),
                );
            }
            PaletteSource::LibraryBlend { index0, index1, blend }
        } else if given > 0 {
            if given < palette::PALETTE_LEN {
                ctx.warn(
                    node,
                    format!("the palette gives {given} of 256 entries; the others are interpolated between their neighbours, as flam3 does"),
                );
            }
            f.palette = entries.filled();
            forms.dedup();
            let form = if forms.len() == 1 { forms[0] } else { InlineForm::Mixed };
            PaletteSource::Inline { form, given }
        } else {
            ctx.warn(node, "no palette: every entry is black and transparent, as in flam3");
            f.palette = entries.filled();
            PaletteSource::None
        };
        Ok((f, source))
    }
}

/// Palette troubles counted over a flame, said in one warning each kind.
#[derive(Default)]
struct PaletteIssues {
    clamped: usize,
    bad_index: Vec<i64>,
    short_data: usize,
    extra_data: usize,
}

impl PaletteIssues {
    fn report(&self, ctx: &mut Ctx, node: roxmltree::Node) {
        if self.clamped > 0 {
            ctx.warn(node, format!("{} palette channel values outside 0..255 were clamped", self.clamped));
        }
        if !self.bad_index.is_empty() {
            let shown: Vec<String> = self.bad_index.iter().take(5).map(|i| i.to_string()).collect();
            let more = if self.bad_index.len() > 5 { ", …" } else { "" };
            ctx.warn(
                node,
                format!(
                    "{} <color> entries with an index outside 0..255 or none were left out ({}{more})",
                    self.bad_index.len(),
                    shown.join(", ")
                ),
            );
        }
        if self.short_data > 0 {
            ctx.warn(node, format!("{} palette elements have fewer colours than their count", self.short_data));
        }
        if self.extra_data > 0 {
            ctx.warn(node, format!("{} palette elements have data past their count, ignored", self.extra_data));
        }
    }
}

/// `<color index rgb|rgba [a]>`: channels 0..255, premultiplied by alpha as flam3 does. As in
/// flam3, the alpha resets to 255 at each attribute, so only an `rgba` or `a` last counts.
fn palette_color(
    ctx: &Ctx,
    node: roxmltree::Node,
    entries: &mut PaletteEntries,
    issues: &mut PaletteIssues,
) -> Result<(), FlameError> {
    let mut index: Option<i64> = None;
    let mut rgb = [0.0; 3];
    let mut alpha = 255.0;
    for attr in node.attributes() {
        alpha = 255.0;
        match attr.name() {
            "index" => index = Some(attr_int(ctx, &attr)?),
            "rgb" => rgb.copy_from_slice(&attr_numbers(ctx, &attr, 3)?),
            "rgba" => {
                let v = attr_numbers(ctx, &attr, 4)?;
                rgb.copy_from_slice(&v[..3]);
                alpha = v[3];
            }
            "a" => alpha = attr_number(ctx, &attr)?,
            other => return Err(ctx.error(node, format!("<color> has an unknown attribute {other}"))),
        }
    }
    let mut channel = |v: f64| {
        let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 255.0) };
        if c != v {
            issues.clamped += 1;
        }
        c / 255.0
    };
    let a = channel(alpha);
    let color = [a * channel(rgb[0]), a * channel(rgb[1]), a * channel(rgb[2]), a];
    match index {
        Some(i) if (0..256).contains(&i) => entries.entries[i as usize] = Some(color),
        other => issues.bad_index.push(other.unwrap_or(-1)),
    }
    Ok(())
}

/// `<colors count data>`: `count` entries of hex `00RRGGBB` from entry 0.
fn palette_colors(
    ctx: &Ctx,
    node: roxmltree::Node,
    entries: &mut PaletteEntries,
    issues: &mut PaletteIssues,
) -> Result<(), FlameError> {
    let mut count: Option<i64> = None;
    let mut data = None;
    for attr in node.attributes() {
        match attr.name() {
            "count" => count = Some(attr_int(ctx, &attr)?),
            "data" => data = Some(attr),
            other => return Err(ctx.error(node, format!("<colors> has an unknown attribute {other}"))),
        }
    }
    let Some(data) = data else { return Err(ctx.error(node, "<colors> without data")) };
    hex_into(ctx, node, data.value(), HexLayout::Hex00Rgb, count, entries, issues)
}

/// `<palette>`: the hex form (`count`, `format` RGB|RGBA, hex content) fills entries and gives
/// `None`; the old form (`index0 hue0 index1 hue1 blend`) gives its two library palettes.
#[expect(clippy::type_complexity, reason = "the old form's five numbers, used once by the caller")]
fn palette_element(
    ctx: &Ctx,
    node: roxmltree::Node,
    entries: &mut PaletteEntries,
    issues: &mut PaletteIssues,
) -> Result<Option<(i32, f64, i32, f64, f64)>, FlameError> {
    let (mut old, mut new) = (false, false);
    let (mut index0, mut index1, mut hue0, mut hue1, mut blend) = (-1, -1, 0.0, 0.0, 0.5);
    let mut count = None;
    let mut layout = None;
    for attr in node.attributes() {
        let as_i32 = |v: i64| i32::try_from(v).map_err(|_| ctx.attr_error(&attr, "out of range"));
        match attr.name() {
            "index0" => (old, index0) = (true, as_i32(attr_int(ctx, &attr)?)?),
            "index1" => (old, index1) = (true, as_i32(attr_int(ctx, &attr)?)?),
            "hue0" => (old, hue0) = (true, attr_number(ctx, &attr)?),
            "hue1" => (old, hue1) = (true, attr_number(ctx, &attr)?),
            "blend" => (old, blend) = (true, attr_number(ctx, &attr)?),
            "count" => (new, count) = (true, Some(attr_int(ctx, &attr)?)),
            "format" => {
                new = true;
                layout = Some(match attr.value() {
                    "RGB" => HexLayout::Rgb,
                    "RGBA" => HexLayout::Rgba,
                    other => return Err(ctx.attr_error(&attr, format!("'{other}' is not RGB or RGBA"))),
                });
            }
            other => return Err(ctx.error(node, format!("<palette> has an unknown attribute {other}"))),
        }
    }
    if old && new {
        return Err(ctx.error(node, "<palette> mixes the old (index0, blend) and new (count, format) forms"));
    }
    if old {
        if index0 < 0 || index1 < 0 {
            return Err(
                ctx.error(node, "<palette> blends a random library palette (index -1), which a still cannot pick")
            );
        }
        return Ok(Some((index0, hue0, index1, hue1, blend)));
    }
    let Some(layout) = layout else { return Err(ctx.error(node, "<palette> without format=\"RGB\" or \"RGBA\"")) };
    let text: String = node.children().filter_map(|n| n.text()).collect();
    hex_into(ctx, node, &text, layout, count, entries, issues)?;
    Ok(None)
}

/// Hex colours from entry 0 into `entries`.
fn hex_into(
    ctx: &Ctx,
    node: roxmltree::Node,
    data: &str,
    layout: HexLayout,
    count: Option<i64>,
    entries: &mut PaletteEntries,
    issues: &mut PaletteIssues,
) -> Result<(), FlameError> {
    let count = count.unwrap_or(palette::PALETTE_LEN as i64);
    if count > palette::PALETTE_LEN as i64 {
        issues.extra_data += 1;
    }
    let max = count.clamp(0, palette::PALETTE_LEN as i64) as usize;
    let (colors, left_over) =
        palette::parse_hex_colors(data, layout, max).map_err(|palette::HexError::BadDigit { entry }| {
            ctx.error(node, format!("palette entry {entry}: not hexadecimal colour data"))
        })?;
    if colors.len() < max {
        issues.short_data += 1;
    } else if left_over {
        issues.extra_data += 1;
    }
    for (slot, c) in entries.entries.iter_mut().zip(colors) {
        *slot = Some(c);
    }
    Ok(())
}
