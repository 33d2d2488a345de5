//! The palette elements of a `<flame>` as flam3's `parser.c` reads them: `<color>`, `<colors>`
//! and `<palette>` (hex data, or the old blend of two library palettes), into the entries that
//! `palette.rs` completes. Out-of-range values are clamped and bad indices left out, each kind
//! counted and said in one warning per flame; data that is not hex is an error.

use super::palette::{self, HexLayout, PaletteEntries};
use super::xml_source::FlameError;
use super::xml_source::{Ctx, attr_int, attr_number, attr_numbers};

/// Palette troubles counted over a flame, said in one warning each kind.
#[derive(Default)]
pub(super) struct PaletteIssues {
    clamped: usize,
    bad_index: Vec<i64>,
    short_data: usize,
    extra_data: usize,
}

impl PaletteIssues {
    pub fn report(&self, ctx: &mut Ctx, node: roxmltree::Node) {
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
pub(super) fn palette_color(
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
pub(super) fn palette_colors(
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
pub(super) fn palette_element(
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
