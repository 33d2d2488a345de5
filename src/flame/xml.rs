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
//! This file holds the document, positions and the `<flame>` attributes; `xml_palette.rs` the
//! palette elements; `xml_xform.rs` the `<xform>`, `<finalxform>` and `<symmetry>` elements.

use std::path::{Path, PathBuf};

use super::palette::{self, InlineForm, PaletteEntries, PaletteLibrary, PaletteSource};
use super::xml_palette::{PaletteIssues, palette_color, palette_colors, palette_element};
pub use super::xml_source::FlameError;
use super::xml_source::{Ctx, Source, attr_int, attr_number, attr_numbers};
use super::xml_xform::{self, XformRead};
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
    let mut reader = Reader { file: file_name, source: &source, options, library: None, out: FlameFile::default() };
    reader.scan(doc.root())?;
    if reader.out.flames.is_empty() {
        return Err(FlameError::File { file: file_name.into(), message: "no <flame> element".into() });
    }
    Ok(reader.out)
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
        let mut f = Flame::default();
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
                    for (k, (&x, slot)) in v.iter().zip(&mut f.center).enumerate() {
                        if let Some(x) = finite(ctx, x, &format!("center[{k}]")) {
                            *slot = x;
                        }
                    }
                }
                "background" => {
                    let v = attr_numbers(ctx, &attr, 3)?;
                    for (k, (&x, slot)) in v.iter().zip(&mut f.background).enumerate() {
                        if let Some(x) = finite(ctx, x, &format!("background[{k}]")) {
                            *slot = x;
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
                "filter_shape" => match FilterShape::parse(attr.value()) {
                    Some(shape) => f.filter_shape = shape,
                    None => ctx.warn(node, format!("unknown filter_shape '{}'; gaussian is used", attr.value())),
                },
                "palette_mode" => match PaletteMode::parse(attr.value()) {
                    Some(mode) => f.palette_mode = mode,
                    None => ctx.warn(node, format!("unknown palette_mode '{}'; step is used", attr.value())),
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
        // Other programs' xform attributes, named in one warning at the first xform with one.
        let mut xform_attributes_not_read: Option<(roxmltree::Node, Vec<&str>)> = None;
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
                    let XformRead { xform, chaos, not_read } =
                        xml_xform::xform(ctx, child, is_final, array_len, &label)?;
                    if !not_read.is_empty() {
                        let (_, names) = xform_attributes_not_read.get_or_insert((child, Vec::new()));
                        names.extend(not_read.into_iter().filter(|n| !names.contains(n)).collect::<Vec<_>>());
                    }
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
        if let Some((at, names)) = xform_attributes_not_read {
            ctx.warn(
                at,
                format!("xform attributes of other programs flam3 does not read, ignored: {}", names.join(", ")),
            );
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
