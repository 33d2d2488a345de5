//! Colour at the edges of the program. Inside nlifs every colour is linear RGB in [0, 1]; sRGB
//! appears only where colours enter or leave: `#rrggbb` and `[r, g, b]` in scene text, 8-bit
//! images, PLY bytes. This file holds the sRGB transfer curve both ways, the one 8-bit sRGB
//! encode that every image and file writer uses (a formula, and a table that gives the same
//! bytes without a `powf` for hot loops), `#rrggbb` parsing and printing, and the default
//! palette of function colours.

/// Default per-function colours (sRGB bytes), chosen to stay distinct when depth-cued; function
/// `i` without a colour of its own takes entry `i % 8`.
pub const PALETTE: [[u8; 3]; 8] = [
    [0xf2, 0x6d, 0x4f],
    [0x4f, 0xb3, 0xf2],
    [0x8c, 0xe0, 0x5a],
    [0xf2, 0xc9, 0x4c],
    [0xc0, 0x7c, 0xf2],
    [0x4c, 0xe0, 0xc4],
    [0xf2, 0x8c, 0xc6],
    [0xd9, 0xd9, 0xd9],
];

/// The linear colour of palette entry `i % PALETTE.len()`.
pub fn palette_color(i: usize) -> [f32; 3] {
    PALETTE[i % PALETTE.len()].map(srgb8_to_linear)
}

/// One sRGB-encoded channel in [0, 1] to linear light.
fn decode(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// An sRGB colour with channels in [0, 1] to linear RGB.
pub fn srgb_to_linear(c: [f32; 3]) -> [f32; 3] {
    c.map(decode)
}

/// An sRGB byte to linear light.
pub fn srgb8_to_linear(byte: u8) -> f32 {
    decode(byte as f32 / 255.0)
}

/// One linear channel to sRGB in [0, 1], clamping first.
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// The 8-bit sRGB encode of one linear channel: every PNG and PLY byte nlifs writes comes from
/// here or from [`Srgb8Table`], which gives the same bytes. NaN encodes as 0.
pub fn linear_to_srgb8(v: f32) -> u8 {
    (linear_to_srgb(v) * 255.0 + 0.5) as u8
}

/// A linear channel as a normalized byte with no transfer curve (glTF's COLOR_0 is linear).
pub fn linear_to_unorm8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// [`linear_to_srgb8`] without a `powf` per channel, for loops over many pixels: the smallest
/// linear value at which each byte 1…255 starts, found once by bisection over the f32 order,
/// and the byte of v is the number of those at or below v. Exact because the formula is
/// monotonic in v (the test checks both sides of every step and a sweep of [0, 1]).
pub struct Srgb8Table {
    starts: [f32; 255],
}

impl Srgb8Table {
    pub fn new() -> Self {
        let mut starts = [0.0f32; 255];
        for (k, start) in starts.iter_mut().enumerate() {
            // Bit patterns of non-negative floats are ordered like the floats; 1.0 gives 255.
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if linear_to_srgb8(f32::from_bits(mid)) as usize > k { hi = mid } else { lo = mid }
            }
            *start = f32::from_bits(hi);
        }
        Self { starts }
    }

    /// The same byte as [`linear_to_srgb8`]`(v)`.
    #[inline]
    pub fn encode(&self, v: f32) -> u8 {
        self.starts.partition_point(|&s| s <= v) as u8
    }
}

impl Default for Srgb8Table {
    fn default() -> Self {
        Self::new()
    }
}

/// The sRGB bytes of `"#rrggbb"` or `"rrggbb"` (six hex digits, either case); None otherwise.
pub fn parse_hex(text: &str) -> Option<[u8; 3]> {
    let hex = text.strip_prefix('#').unwrap_or(text);
    if hex.len() != 6 || !hex.chars().all(|ch| ch.is_ascii_hexdigit()) {
        return None;
    }
    // Six ASCII digits, so the byte slices fall on character boundaries.
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    Some([byte(0)?, byte(2)?, byte(4)?])
}

/// `"#rrggbb"` in lower case, what [`parse_hex`] reads back.
pub fn hex_text(srgb: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", srgb[0], srgb[1], srgb[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every byte decodes and encodes back to itself; the decode is increasing.
    #[test]
    fn srgb8_round_trips() {
        for b in 0..=255u8 {
            let v = srgb8_to_linear(b);
            assert_eq!(linear_to_srgb8(v), b, "byte {b} via {v}");
            assert_eq!(srgb_to_linear([b as f32 / 255.0; 3]), [v; 3]);
            if b > 0 {
                assert!(v > srgb8_to_linear(b - 1), "decode increases at {b}");
            }
        }
        // The curve's two pieces meet at the threshold (to f32 rounding).
        assert!((linear_to_srgb(0.003_130_8) - 0.003_130_8 * 12.92).abs() < 1e-6);
        assert!((decode(0.04045) - 0.04045 / 12.92).abs() < 1e-6);
    }

    /// The table against the formula on both sides of every step, at the ends and on a sweep
    /// of every 101st float in [0, 1] (about 10 million values).
    #[test]
    fn srgb8_table_matches_the_formula() {
        let table = Srgb8Table::new();
        for (k, &start) in table.starts.iter().enumerate() {
            let below = f32::from_bits(start.to_bits() - 1);
            assert_eq!(table.encode(start), linear_to_srgb8(start), "step {k} at {start}");
            assert_eq!(table.encode(below), linear_to_srgb8(below), "below step {k} at {below}");
            assert_eq!(table.encode(start) as usize, k + 1, "step {k} starts byte {}", k + 1);
        }
        for v in [-1.0, -0.0, 0.0, 1.0, 2.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
            assert_eq!(table.encode(v), linear_to_srgb8(v), "at {v}");
        }
        for bits in (0..=1.0f32.to_bits()).step_by(101) {
            let v = f32::from_bits(bits);
            assert_eq!(table.encode(v), linear_to_srgb8(v), "at {v}");
        }
    }

    #[test]
    fn unorm8_rounds_to_nearest_and_clamps() {
        assert_eq!([-0.5, 0.0, 0.5, 1.0, 7.0].map(linear_to_unorm8), [0, 0, 128, 255, 255]);
        for b in 0..=255u8 {
            assert_eq!(linear_to_unorm8(b as f32 / 255.0), b);
        }
    }

    #[test]
    fn hex_parses_and_prints_back() {
        assert_eq!(parse_hex("#0B0d14"), Some([0x0b, 0x0d, 0x14]));
        assert_eq!(parse_hex("ffffff"), Some([255; 3]));
        for bad in ["", "#", "#fff", "#12345", "#1234567", "##123456", "#12345g", "+12345", "#12 345", "#ééé"] {
            assert_eq!(parse_hex(bad), None, "{bad:?}");
        }
        // Seeded by the loop index so a failure replays.
        for i in 0..1000u32 {
            let h = crate::rng::pcg_hash(i);
            let srgb = [h as u8, (h >> 8) as u8, (h >> 16) as u8];
            assert_eq!(parse_hex(&hex_text(srgb)), Some(srgb), "case {i}");
        }
    }

    #[test]
    fn palette_colors_are_the_palette_bytes() {
        for i in 0..2 * PALETTE.len() {
            assert_eq!(palette_color(i).map(linear_to_srgb8), PALETTE[i % PALETTE.len()], "entry {i}");
        }
    }
}
