//! A flame's 256-entry palette as flam3 builds it from the XML (its `parser.c` and
//! `palettes.c`): the inline forms (`<color>`, `<colors>`, `<palette>` hex data), the numbered
//! palettes of flam3's library file with a hue rotation, and the interpolation that fills the
//! entries a file leaves out.
//!
//! flam3's quirks are kept, because the renderer must see the colours flam3 sees: `<color>`
//! entries are premultiplied by their alpha (the hex forms are not); a numbered palette
//! (`palette="N"`) replaces every inline entry; entries not given are interpolated in RGBA
//! between the given neighbours, wrapping around from the last given entry to the first; a
//! flame with no colour at all gets a black, fully transparent palette.
//!
//! The library (`flam3-palettes.xml`, GPL data) is never bundled: it is read from the system's
//! flam3 install, or from the file named by `NLIFS_FLAM3_PALETTES` (then flam3's own
//! `flam3_palettes`).

use std::path::{Path, PathBuf};

use super::Palette;

/// Entries in a palette.
pub const PALETTE_LEN: usize = 256;

/// Where flam3's Debian package installs its palette library.
pub const SYSTEM_PALETTE_LIBRARY: &str = "/usr/share/flam3/flam3-palettes.xml";

/// The palette library's path: `NLIFS_FLAM3_PALETTES`, else flam3's `flam3_palettes`, else
/// [`SYSTEM_PALETTE_LIBRARY`].
pub fn palette_library_path() -> PathBuf {
    ["NLIFS_FLAM3_PALETTES", "flam3_palettes"]
        .iter()
        .find_map(|var| std::env::var_os(var).filter(|v| !v.is_empty()))
        .map_or_else(|| PathBuf::from(SYSTEM_PALETTE_LIBRARY), PathBuf::from)
}

/// How a flame's palette was given in its file (for `nlifs info`).
#[derive(Clone, Debug, PartialEq)]
pub enum PaletteSource {
    /// No colour at all: flam3's black, transparent palette.
    None,
    /// `palette="N"` from the library, with `hue` (turns, in [0, 1)).
    Library { number: i32, hue_turns: f64 },
    /// `<palette index0 index1 blend>`: two library palettes blended in HSV.
    LibraryBlend { index0: i32, index1: i32, blend: f64 },
    /// Inline forms, with the number of entries given (the rest interpolated).
    Inline { form: InlineForm, given: usize },
}

/// The inline palette forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InlineForm {
    /// `<color index rgb|rgba>` elements.
    Color,
    /// `<colors count data>` (hex `00RRGGBB`).
    Colors,
    /// `<palette count format>` with hex RGB or RGBA content.
    HexPalette,
    /// More than one of the above in one flame.
    Mixed,
}

impl PaletteSource {
    /// A short description: `library 15 (hue 0.23)`, `<color> ×256`.
    pub fn describe(&self) -> String {
        match self {
            PaletteSource::None => "none (black)".into(),
            PaletteSource::Library { number, hue_turns } if *hue_turns != 0.0 => {
                format!("library {number} (hue {hue_turns:.4})")
            }
            PaletteSource::Library { number, .. } => format!("library {number}"),
            PaletteSource::LibraryBlend { index0, index1, blend } => {
                format!("library {index0} and {index1} blended {blend}")
            }
            PaletteSource::Inline { form, given } => {
                let name = match form {
                    InlineForm::Color => "<color>",
                    InlineForm::Colors => "<colors>",
                    InlineForm::HexPalette => "<palette> hex",
                    InlineForm::Mixed => "inline (mixed forms)",
                };
                format!("{name} ×{given}")
            }
        }
    }
}

/// A palette being read: the entries given so far (`None` = not given), as flam3's array with
/// index −1 for a missing entry.
#[derive(Clone, Debug)]
pub struct PaletteEntries {
    pub entries: Vec<Option<[f64; 4]>>,
}

impl Default for PaletteEntries {
    fn default() -> Self {
        Self { entries: vec![None; PALETTE_LEN] }
    }
}

impl PaletteEntries {
    pub fn given(&self) -> usize {
        self.entries.iter().filter(|e| e.is_some()).count()
    }

    /// The full palette, entries not given interpolated as flam3's `flam3_interp_missing_colors`
    /// does: each run of missing entries is a linear blend between the given entries on either
    /// side, the run before the first given entry and after the last one wrapping around
    /// (distances measured across the end of the table). No entry given: all black, alpha 0.
    pub fn filled(&self) -> Palette {
        let given: Vec<usize> = (0..PALETTE_LEN).filter(|&i| self.entries[i].is_some()).collect();
        let (Some(&first), Some(&last)) = (given.first(), given.last()) else {
            return vec![[0.0; 4]; PALETTE_LEN];
        };
        let color = |i: usize| self.entries[i].unwrap_or([0.0; 4]);
        let mut out: Palette = (0..PALETTE_LEN).map(color).collect();
        let mut i = 0;
        while i < PALETTE_LEN {
            if self.entries[i].is_some() {
                i += 1;
                continue;
            }
            let start = i;
            while i < PALETTE_LEN && self.entries[i].is_none() {
                i += 1;
            }
            // The run is start..i; its neighbours (as positions that may lie past the ends).
            let (left_pos, left) =
                if start == 0 { (last as f64 - 256.0, last) } else { ((start - 1) as f64, start - 1) };
            let (right_pos, right) = if i == PALETTE_LEN { ((first + 256) as f64, first) } else { (i as f64, i) };
            let (cl, cr) = (color(left), color(right));
            for (j, slot) in out.iter_mut().enumerate().take(i).skip(start) {
                let t = (j as f64 - left_pos) / (right_pos - left_pos);
                for k in 0..4 {
                    slot[k] = cl[k] * (1.0 - t) + cr[k] * t;
                }
            }
        }
        out
    }
}

/// Why a run of hex colours could not be read.
#[derive(Debug, PartialEq)]
pub enum HexError {
    /// A character that is not a hex digit, at this index of the colour list.
    BadDigit { entry: usize },
}

/// Hex colour data as flam3 writes it: `channels` bytes per entry (3 = RRGGBB, 4 = RRGGBBAA,
/// `Hex00Rgb` = 00RRGGBB as `<colors>` and the library write them), whitespace anywhere ignored.
/// Returns the entries (RGBA in [0, 1], not premultiplied) and whether characters were left
/// over (an incomplete last entry or data past `max_entries`).
pub fn parse_hex_colors(data: &str, layout: HexLayout, max_entries: usize) -> Result<(Vec<[f64; 4]>, bool), HexError> {
    let digits: Vec<u8> = data.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    let width = layout.chars_per_entry();
    let mut out = Vec::with_capacity((digits.len() / width).min(max_entries));
    for (entry, chunk) in digits.chunks(width).enumerate() {
        if out.len() == max_entries || chunk.len() < width {
            return Ok((out, true));
        }
        let byte = |k: usize| -> Result<f64, HexError> {
            let hi = (chunk[2 * k] as char).to_digit(16);
            let lo = (chunk[2 * k + 1] as char).to_digit(16);
            match (hi, lo) {
                (Some(hi), Some(lo)) => Ok(f64::from(hi * 16 + lo) / 255.0),
                _ => Err(HexError::BadDigit { entry }),
            }
        };
        let rgba = match layout {
            HexLayout::Rgb => [byte(0)?, byte(1)?, byte(2)?, 1.0],
            HexLayout::Rgba => [byte(0)?, byte(1)?, byte(2)?, byte(3)?],
            // flam3 wants the literal "00" first; any byte there is accepted here.
            HexLayout::Hex00Rgb => [byte(1)?, byte(2)?, byte(3)?, 1.0],
        };
        out.push(rgba);
    }
    Ok((out, false))
}

/// The byte layouts of flam3's hex colour data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexLayout {
    Rgb,
    Rgba,
    Hex00Rgb,
}

impl HexLayout {
    fn chars_per_entry(self) -> usize {
        match self {
            HexLayout::Rgb => 6,
            HexLayout::Rgba | HexLayout::Hex00Rgb => 8,
        }
    }
}

/// Each `<palette>` element's number and `data` in `text`, in the file's order (those without
/// a number that reads are left out). The library is 1.5 MB of hex text for 700 palettes, of
/// which a flame reads one or two: the values are taken raw (entities replaced where there are
/// any), not normalized as a document reader normalizes every attribute (its whitespace is
/// skipped when the hex is read); `Err` gives the line and column of what is not XML.
fn library_entries(text: &str) -> Result<Vec<(i32, String)>, String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut entries = Vec::new();
    let at = |reader: &quick_xml::Reader<&[u8]>, e: &dyn std::fmt::Display| {
        let offset = (reader.error_position() as usize).min(text.len());
        let before = text.as_bytes()[..offset].split(|&b| b == b'\n');
        let (lines, last) = before.fold((0, 0), |(n, _), line| (n + 1, line.len()));
        format!("{e} at {lines}:{}", last + 1)
    };
    // Elements open, and whether the root has been seen: a file cut short, or without any
    // element, is not a document.
    let (mut open, mut root) = (0usize, false);
    loop {
        let event = reader.read_event().map_err(|e| at(&reader, &e))?;
        match &event {
            Event::Start(_) => (open, root) = (open + 1, true),
            Event::Empty(_) => root = true,
            Event::End(_) => open = open.saturating_sub(1),
            Event::Eof if open > 0 => return Err(at(&reader, &"an element opened and never closed")),
            Event::Eof if !root => return Err("there is no element in it".to_string()),
            Event::Eof => return Ok(entries),
            _ => {}
        }
        let element = match event {
            Event::Start(e) | Event::Empty(e) if e.local_name().as_ref() == b"palette" => e,
            _ => continue,
        };
        let (mut number, mut data) = (None, String::new());
        for attribute in element.attributes() {
            let attribute = attribute.map_err(|e| at(&reader, &e))?;
            let raw = std::str::from_utf8(&attribute.value).map_err(|e| at(&reader, &e))?;
            let value = quick_xml::escape::unescape(raw).map_err(|e| at(&reader, &e))?;
            match attribute.key.local_name().as_ref() {
                b"number" => number = value.trim().parse::<i32>().ok(),
                b"data" => data = value.into_owned(),
                _ => {}
            }
        }
        if let Some(number) = number {
            entries.push((number, data));
        }
    }
}

/// flam3's palette library: numbered 256-entry RGB palettes (channels in [0, 1]), each kept as
/// its hex text and read when asked for (a flame names one or two of the library's 700).
#[derive(Clone, Debug, Default)]
pub struct PaletteLibrary {
    pub path: PathBuf,
    /// Each `<palette>`'s number and `data`, in the file's order.
    entries: Vec<(i32, String)>,
}

impl PaletteLibrary {
    /// Reads the library file; `Err` is a sentence naming the file.
    pub fn read(path: &Path) -> Result<Self, String> {
        let shown = path.display();
        let text =
            std::fs::read_to_string(path).map_err(|e| format!("cannot read the flam3 palette library {shown}: {e}"))?;
        let entries =
            library_entries(&text).map_err(|e| format!("the flam3 palette library {shown} is not valid XML: {e}"))?;
        Ok(Self { path: path.to_path_buf(), entries })
    }

    /// Palette `number`'s 256 RGB entries: the first entry of that number whose data reads (as
    /// flam3, which leaves the others out of the library).
    pub fn colors(&self, number: i32) -> Option<Vec<[f64; 3]>> {
        self.entries.iter().filter(|(n, _)| *n == number).find_map(|(_, data)| {
            let (colors, _) = parse_hex_colors(data, HexLayout::Hex00Rgb, PALETTE_LEN).ok()?;
            (colors.len() == PALETTE_LEN).then(|| colors.iter().map(|c| [c[0], c[1], c[2]]).collect())
        })
    }

    /// Palette `number` with its hue turned by `hue_turns` (flam3's `flam3_get_palette`: every
    /// entry through HSV, hue + 6·hue_turns sextants, alpha 1); `None` if the library lacks it.
    pub fn get(&self, number: i32, hue_turns: f64) -> Option<Palette> {
        let colors = self.colors(number)?;
        Some(
            colors
                .iter()
                .map(|&rgb| {
                    let mut hsv = rgb_to_hsv(rgb);
                    hsv[0] += hue_turns * 6.0;
                    let [r, g, b] = hsv_to_rgb(hsv);
                    [r, g, b, 1.0]
                })
                .collect(),
        )
    }
}

/// flam3's white palette, used when a numbered palette is missing from the library.
pub fn white() -> Palette {
    vec![[1.0; 4]; PALETTE_LEN]
}

/// flam3's `interpolate_cmap`: palettes `p0`, `p1` blended in HSV (hue the short way round)
/// with weight `blend` on `p1`, alpha linearly.
pub fn blend_hsv(p0: &Palette, p1: &Palette, blend: f64) -> Palette {
    p0.iter()
        .zip(p1)
        .map(|(a, b)| {
            let mut s = rgb_to_hsv([a[0], a[1], a[2]]);
            let t = rgb_to_hsv([b[0], b[1], b[2]]);
            if s[0] - t[0] > 3.0 {
                s[0] -= 6.0;
            }
            if s[0] - t[0] < -3.0 {
                s[0] += 6.0;
            }
            let mix = |x: f64, y: f64| (1.0 - blend) * x + blend * y;
            let [r, g, bl] = hsv_to_rgb([mix(s[0], t[0]), mix(s[1], t[1]), mix(s[2], t[2])]);
            [r, g, bl, mix(a[3], b[3])]
        })
        .collect()
}

/// RGB in [0, 1] to flam3's HSV: hue in sextants [0, 6), saturation and value in [0, 1].
pub fn rgb_to_hsv([r, g, b]: [f64; 3]) -> [f64; 3] {
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let del = max - min;
    let s = if max != 0.0 { del / max } else { 0.0 };
    let mut h = 0.0;
    if s != 0.0 {
        let (rc, gc, bc) = ((max - r) / del, (max - g) / del, (max - b) / del);
        h = if r == max {
            bc - gc
        } else if g == max {
            2.0 + rc - bc
        } else {
            4.0 + gc - rc
        };
        if h < 0.0 {
            h += 6.0;
        }
    }
    [h, s, max]
}

/// flam3's HSV (hue in sextants, any real) to RGB.
pub fn hsv_to_rgb([h, s, v]: [f64; 3]) -> [f64; 3] {
    let h = if h.is_finite() { h.rem_euclid(6.0) } else { 0.0 };
    let j = h.floor();
    let f = h - j;
    let p = v * (1.0 - s);
    let q = v * (1.0 - s * f);
    let t = v * (1.0 - s * (1.0 - f));
    match j as i32 {
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        5 => [v, p, q],
        _ => [v, t, p],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The library's entries as a document reader finds them: each `<palette>`'s number and
    /// data (entities replaced), whitespace aside; malformed files name their line and column.
    #[test]
    fn library_entries_are_the_documents_palettes() {
        let text = "<?xml version=\"1.0\"?>\n<!-- a <palette number=\"9\"/> in a comment -->\n<palettes>\n\
            <palette number=\" 3 \" name=\"a\" data=\"00010203\n 00040506\"/>\n\
            <palette number=\"x\" data=\"00ffffff\"/>\n\
            <palette data=\"00ffffff\" number=\"&#55;\"></palette>\n\
            <palette number=\"3\" data=\"&#48;0aabbcc\"/>\n</palettes>\n";
        let doc = roxmltree::Document::parse(text).expect("a document");
        let expected: Vec<(i32, String)> = doc
            .descendants()
            .filter(|n| n.has_tag_name("palette"))
            .filter_map(|n| Some((n.attribute("number")?.trim().parse().ok()?, n.attribute("data")?.to_string())))
            .collect();
        let found = library_entries(text).expect("entries");
        let digits = |s: &str| s.split_whitespace().collect::<String>();
        assert_eq!(found.len(), 3, "{found:?}");
        for ((n, data), (m, want)) in found.iter().zip(&expected) {
            assert_eq!((n, digits(data)), (m, digits(want)));
        }
        let bad = library_entries("<palettes>\n  <palette number=\"1\" data=\"00\">\n</palettes>\n").unwrap_err();
        assert!(bad.contains("3:"), "{bad}");
        assert!(library_entries("<palettes>\n<palette number=\"1\" number=\"2\"/></palettes>").is_err());
        assert!(library_entries("<palettes>\n<palette number=\"1\" data=\"00\"/>\n").is_err(), "cut short");
        assert!(library_entries("  \n").is_err(), "no element");
    }

    #[test]
    fn hsv_round_trip() {
        for rgb in [[0.2, 0.5, 0.9], [1.0, 0.0, 0.0], [0.3, 0.3, 0.3], [0.9, 0.8, 0.1]] {
            let back = hsv_to_rgb(rgb_to_hsv(rgb));
            for c in 0..3 {
                assert!((back[c] - rgb[c]).abs() < 1e-12, "{rgb:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn missing_entries_blend_between_neighbours_and_wrap() {
        let mut p = PaletteEntries::default();
        p.entries[10] = Some([1.0, 0.0, 0.0, 1.0]);
        p.entries[20] = Some([0.0, 1.0, 0.0, 1.0]);
        let full = p.filled();
        // Halfway between 10 and 20.
        assert_eq!(full[15], [0.5, 0.5, 0.0, 1.0]);
        // The leading run 0..=9 blends the last given entry (20, placed at 20 − 256) to red
        // (10); the trailing run 21..=255 blends green (20) to the first (10, at 10 + 256).
        let t = (0.0 - (20.0 - 256.0)) / (10.0 - (20.0 - 256.0));
        let want = [t, 1.0 - t, 0.0, 1.0];
        for k in 0..4 {
            assert!((full[0][k] - want[k]).abs() < 1e-12, "{:?} vs {want:?}", full[0]);
        }
        let t = (100.0 - 20.0) / (266.0 - 20.0);
        assert!((full[100][0] - t).abs() < 1e-12);
    }

    #[test]
    fn no_entries_give_black_transparent() {
        assert!(PaletteEntries::default().filled().iter().all(|c| *c == [0.0; 4]));
    }

    #[test]
    fn hex_layouts() {
        let (c, left) = parse_hex_colors("ff0000 00ff00\n0000", HexLayout::Rgb, 256).unwrap();
        assert_eq!(c, vec![[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]]);
        assert!(left);
        let (c, left) = parse_hex_colors("00ff8000", HexLayout::Hex00Rgb, 256).unwrap();
        assert_eq!(c, vec![[1.0, 128.0 / 255.0, 0.0, 1.0]]);
        assert!(!left);
        let (c, _) = parse_hex_colors("ffffff80", HexLayout::Rgba, 256).unwrap();
        assert_eq!(c[0][3], 128.0 / 255.0);
        assert_eq!(parse_hex_colors("00zz0000", HexLayout::Hex00Rgb, 256), Err(HexError::BadDigit { entry: 0 }));
        let (c, left) = parse_hex_colors("000000ffffff", HexLayout::Rgb, 1).unwrap();
        assert_eq!((c.len(), left), (1, true));
    }

    #[test]
    fn hsv_round_trip_and_hue_turn() {
        for rgb in [[0.2, 0.4, 0.9], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [0.9, 0.1, 0.1], [0.3, 0.8, 0.3]] {
            let back = hsv_to_rgb(rgb_to_hsv(rgb));
            for k in 0..3 {
                assert!((back[k] - rgb[k]).abs() < 1e-12, "{rgb:?} -> {back:?}");
            }
        }
        // A third of a turn takes red to green.
        let mut hsv = rgb_to_hsv([1.0, 0.0, 0.0]);
        hsv[0] += 6.0 / 3.0;
        let g = hsv_to_rgb(hsv);
        assert!((g[0]).abs() < 1e-12 && (g[1] - 1.0).abs() < 1e-12 && g[2].abs() < 1e-12);
    }
}
