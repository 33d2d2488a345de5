//! Palettes for colouring by a colour coordinate (`[render] color = "palette"`): 256 linear-RGB
//! samples indexed by the quantized coordinate [`index_of`]. A palette is one of the built-in
//! ones ([`BUILTIN`], each a few colour stops of this program's own, blended in sRGB and sampled
//! to 256 entries) or the middle row of a PNG or JPEG image (a strip), resampled to 256 entries
//! and decoded from sRGB to linear.
//!
//! The colour coordinate itself is carried by the chaos game (`chaos_game.rs`): each function i
//! has a coordinate c_i in [0, 1], a point's c becomes (c + c_i) / 2 at every step (flam3's
//! rule), and the point is splatted with palette entry [`index_of`]`(c)` in place of its
//! function's colour.

use std::path::{Path, PathBuf};

use crate::color;

/// Entries of every palette.
pub const SAMPLES: usize = 256;

/// The palette's entry for colour coordinate `c` in [0, 1]: ⌊256 c⌋, 255 for c = 1 (flam3's
/// step rule: every entry covers 1/256 of the coordinate; c outside [0, 1] gives some entry,
/// callers keep it inside). The one quantization of the colour coordinate (the CPU kernels'
/// and the shader's `palette_entry`).
#[inline(always)]
pub fn index_of(c: f32) -> u8 {
    // Through i32: for c in [0, 1] the same as a direct cast, without its saturation code.
    ((c * 256.0) as i32).min(255) as u8
}

/// The palette's entry for colour coordinate `c` in [0, 1] with flam3's linear interpolation
/// (`palette_mode = "linear"`), as a dither: flam3 draws (1 − f) · entry i + f · entry i + 1
/// for 256 c = i + f (entry 255 from c = 255/256 on); a point here carries entry i + 1 when
/// `dither` (uniform over the u32s) falls below f · 2^32, entry i otherwise, so that a pixel's
/// mean colour is flam3's interpolated colour. The shader's `palette_entry_linear`.
#[inline(always)]
pub fn index_linear(c: f32, dither: u32) -> u8 {
    let t = c * 256.0;
    let i = t as i32;
    if i >= 255 {
        return 255;
    }
    let i = i.max(0);
    let f = t - i as f32;
    // f in [0, 1) to 24 bits (exact in f32), against the dither's top 24 bits.
    (i + i32::from(((dither >> 8) as f32) < f * 16_777_216.0)) as u8
}

/// A dither value for a point at (x, y) with colour coordinate `c`: a hash of their bits (the
/// points of an orbit wander chaotically, so it is as good as uniform and independent of the
/// coordinate's fraction), the same on every thread count. The shader's `dither_of`.
#[inline(always)]
pub fn dither_of(x: f32, y: f32, c: f32) -> u32 {
    let mut h = x.to_bits() ^ y.to_bits().rotate_left(11) ^ c.to_bits().rotate_left(22);
    // The lowbias32 finalizer (Wellons): every input bit reaches every output bit.
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

/// The built-in palettes: name and colour stops (sRGB bytes), spread evenly over [0, 1].
pub const BUILTIN: &[(&str, &[[u8; 3]])] = &[
    ("ember", &[[0x12, 0x06, 0x10], [0x7a, 0x10, 0x1c], [0xd8, 0x4a, 0x12], [0xf6, 0xa8, 0x2e], [0xfb, 0xee, 0xb4]]),
    ("lagoon", &[[0x0a, 0x16, 0x3a], [0x0e, 0x5c, 0x7e], [0x1f, 0xa8, 0x9c], [0x9c, 0xdc, 0xa4], [0xf2, 0xe6, 0xc0]]),
    ("moss", &[[0x14, 0x22, 0x10], [0x3c, 0x62, 0x24], [0x8a, 0x9c, 0x30], [0xd6, 0xc0, 0x52]]),
    ("dusk", &[[0x22, 0x14, 0x5a], [0x7c, 0x2a, 0x8c], [0xd4, 0x4c, 0x7c], [0xf6, 0x9a, 0x6c], [0xfc, 0xdc, 0xa8]]),
    ("glacier", &[[0x08, 0x10, 0x30], [0x1c, 0x4c, 0x9c], [0x48, 0xa8, 0xdc], [0xc4, 0xec, 0xf8]]),
    (
        "spectrum",
        &[
            [0xe0, 0x3c, 0x3c],
            [0xe8, 0xb0, 0x30],
            [0x5c, 0xc8, 0x4c],
            [0x2c, 0xb4, 0xc8],
            [0x44, 0x5c, 0xe0],
            [0xb4, 0x48, 0xd8],
        ],
    ),
];

/// The palette of `[render] color = "palette"` when the scene names none.
pub const DEFAULT: &str = "dusk";

/// A palette: where it came from (a built-in name or an image path, as written) and its
/// [`SAMPLES`] linear-RGB entries.
#[derive(Clone, Debug, PartialEq)]
pub struct Palette {
    pub source: String,
    pub samples: Vec<[f32; 3]>,
}

/// Why a palette could not be made; every message names the palette or the file.
#[derive(Debug, thiserror::Error)]
pub enum PaletteError {
    #[error("unknown palette \"{name}\": not a built-in one ({known}) and no file {path}")]
    Unknown { name: String, path: PathBuf, known: String },
    #[error("cannot read palette image {path}: {cause}")]
    Unreadable { path: PathBuf, cause: String },
    #[error("palette image {path} has no pixels")]
    Empty { path: PathBuf },
}

impl Palette {
    /// The built-in palette `name`, or None.
    pub fn builtin(name: &str) -> Option<Self> {
        let (_, stops) = BUILTIN.iter().find(|(n, _)| *n == name)?;
        let srgb = |k: usize| stops[k].map(|b| b as f32 / 255.0);
        let samples = (0..SAMPLES)
            .map(|i| {
                let x = i as f32 / (SAMPLES - 1) as f32 * (stops.len() - 1) as f32;
                let k = (x as usize).min(stops.len() - 2);
                let t = x - k as f32;
                let (a, b) = (srgb(k), srgb(k + 1));
                color::srgb_to_linear([0, 1, 2].map(|j| a[j] + (b[j] - a[j]) * t))
            })
            .collect();
        Some(Self { source: name.to_string(), samples })
    }

    /// The names of the built-in palettes, comma-separated (for messages and help).
    pub fn known() -> String {
        BUILTIN.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
    }

    /// The palette `spec` names: a built-in name, else an image file, relative to `base_dir`
    /// when it is relative (a scene's directory; None: the working directory). `source` keeps
    /// `spec` as written.
    pub fn resolve(spec: &str, base_dir: Option<&Path>) -> Result<Self, PaletteError> {
        if let Some(p) = Self::builtin(spec) {
            return Ok(p);
        }
        let path = match base_dir {
            Some(dir) if Path::new(spec).is_relative() => dir.join(spec),
            _ => PathBuf::from(spec),
        };
        if !path.exists() {
            return Err(PaletteError::Unknown { name: spec.to_string(), path, known: Self::known() });
        }
        let samples = Self::strip_samples(&path)?;
        Ok(Self { source: spec.to_string(), samples })
    }

    /// The middle row of the PNG or JPEG at `path`, resampled to [`SAMPLES`] entries (linear
    /// interpolation between pixel centres, in linear light).
    fn strip_samples(path: &Path) -> Result<Vec<[f32; 3]>, PaletteError> {
        let unreadable = |cause: String| PaletteError::Unreadable { path: path.to_path_buf(), cause };
        let reader = image::ImageReader::open(path).map_err(|e| unreadable(e.to_string()))?;
        let reader = reader.with_guessed_format().map_err(|e| unreadable(e.to_string()))?;
        let img = reader.decode().map_err(|e| unreadable(e.to_string()))?.to_rgb8();
        let (width, height) = img.dimensions();
        if width == 0 || height == 0 {
            return Err(PaletteError::Empty { path: path.to_path_buf() });
        }
        let row: Vec<[f32; 3]> =
            (0..width).map(|x| img.get_pixel(x, height / 2).0.map(color::srgb8_to_linear)).collect();
        Ok((0..SAMPLES)
            .map(|i| {
                // Entry i samples the strip at (i + ½) / SAMPLES of its width.
                let x = ((i as f32 + 0.5) / SAMPLES as f32 * width as f32 - 0.5).clamp(0.0, (width - 1) as f32);
                let k = (x as usize).min(row.len() - 1);
                let next = (k + 1).min(row.len() - 1);
                let t = x - k as f32;
                [0, 1, 2].map(|j| row[k][j] + (row[next][j] - row[k][j]) * t)
            })
            .collect())
    }

    /// The palette as a strip image: [`SAMPLES`] × 1 pixels, the entries encoded to sRGB bytes
    /// (a palette read from such a strip reads back exactly, each entry the pixel itself).
    pub fn strip_image(&self) -> image::RgbImage {
        image::RgbImage::from_fn(self.samples.len() as u32, 1, |x, _| {
            image::Rgb(self.samples[x as usize].map(color::linear_to_srgb8))
        })
    }

    /// Where this palette's image is, relative to `base_dir` (a scene's directory); None for
    /// a built-in one.
    pub fn image_path(&self, base_dir: &Path) -> Option<PathBuf> {
        if Self::builtin(&self.source).is_some() {
            return None;
        }
        Some(if Path::new(&self.source).is_relative() {
            base_dir.join(&self.source)
        } else {
            PathBuf::from(&self.source)
        })
    }

    /// The entry for colour coordinate `c` (see [`index_of`]).
    pub fn at(&self, c: f32) -> [f32; 3] {
        self.samples[index_of(c.clamp(0.0, 1.0)) as usize]
    }
}

/// Function `i`'s colour coordinate of `n` functions when the scene gives none: i / (n − 1),
/// spread evenly over [0, 1] (½ for a single function).
pub fn default_index(i: usize, n: usize) -> f64 {
    if n < 2 { 0.5 } else { i as f64 / (n - 1) as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dithered entry averages to flam3's interpolation: over many points the share of
    /// entry i + 1 is the fraction f of 256 c (within 4 standard deviations), entry i + 1 never
    /// when f = 0, and entry 255 from c = 255/256 on.
    #[test]
    fn linear_entries_average_to_the_interpolation() {
        let n = 200_000u32;
        for c in [0.1f32, 0.30078125 + 0.25 / 256.0, 0.5 + 0.9 / 256.0, 254.5 / 256.0] {
            let t = c * 256.0;
            let (i, f) = (t.floor(), t - t.floor());
            let mut upper = 0u32;
            for k in 0..n {
                // Points of a wandering orbit: positions that differ from point to point.
                let (x, y) = ((k as f32 * 0.618_034).fract(), (k as f32 * 0.414_213_57).fract() - 0.5);
                let e = index_linear(c, dither_of(x, y, c));
                assert!(e as f32 == i || e as f32 == i + 1.0, "c {c}: entry {e}");
                upper += u32::from(e as f32 == i + 1.0);
            }
            let share = upper as f64 / n as f64;
            let sd = (f64::from(f) * (1.0 - f64::from(f)) / n as f64).sqrt();
            assert!((share - f64::from(f)).abs() <= 4.0 * sd + 1e-9, "c {c}: share {share} against {f}");
        }
        assert_eq!(index_linear(0.25, 0), 64);
        assert_eq!(index_linear(0.25, u32::MAX), 64, "f = 0 never takes the next entry");
        assert_eq!(index_linear(1.0, 0), 255);
        assert_eq!(index_linear(255.0 / 256.0, u32::MAX), 255);
        assert_eq!(index_linear(0.0, 0), 0);
    }

    #[test]
    fn builtins_hit_their_end_stops_and_have_256_entries() {
        for (name, stops) in BUILTIN {
            let p = Palette::builtin(name).unwrap();
            assert_eq!(p.samples.len(), SAMPLES);
            // The first and last entries are the end stops exactly (t = 0 and t = 1).
            assert_eq!(p.samples[0], stops[0].map(color::srgb8_to_linear), "{name}");
            assert_eq!(p.samples[SAMPLES - 1], stops[stops.len() - 1].map(color::srgb8_to_linear), "{name}");
        }
    }

    #[test]
    fn index_rounds_to_nearest_entry() {
        assert_eq!(index_of(0.0), 0);
        assert_eq!(index_of(1.0), 255);
        assert_eq!(index_of(0.5), 128);
        assert_eq!(index_of(10.0 / 255.0), 10);
    }

    #[test]
    fn strip_is_its_middle_row_resampled() {
        let dir = std::env::temp_dir().join(format!("nlifs-palette-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 256 × 3: the middle row is a grey ramp, the other rows red; 256 wide resamples to
        // the pixels themselves (x = i exactly).
        let img =
            image::RgbImage::from_fn(
                256,
                3,
                |x, y| if y == 1 { image::Rgb([x as u8; 3]) } else { image::Rgb([255, 0, 0]) },
            );
        let path = dir.join("strip.png");
        img.save(&path).unwrap();
        let p = Palette::resolve("strip.png", Some(&dir)).unwrap();
        for (i, s) in p.samples.iter().enumerate() {
            assert_eq!(*s, [color::srgb8_to_linear(i as u8); 3], "entry {i}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn errors_name_the_palette_or_file() {
        let e = Palette::resolve("no-such-palette", Some(Path::new("/nonexistent-dir"))).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("no-such-palette") && text.contains("ember") && text.contains("spectrum"), "{text}");
        let dir = std::env::temp_dir().join(format!("nlifs-palette-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("bad.png"), b"not an image").unwrap();
        let text = Palette::resolve("bad.png", Some(&dir)).unwrap_err().to_string();
        assert!(text.contains("cannot read palette image") && text.contains("bad.png"), "{text}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
