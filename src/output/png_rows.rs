//! PNG written from rows made one at a time, for images too large to hold twice: the rows are
//! filtered and compressed as they come, so memory is one row and the compressed stream, not
//! the whole image.
//!
//! The bytes are those the `image` crate writes for the same pixels (its default PNG
//! settings: the `png` crate's adaptive filter and `fdeflate` fast compression, falling back to
//! stored blocks when compression would not pay), with the scene's iTXt chunks after the
//! header as [`super::png::save_rgb8`] splices them. So a streamed image is byte for byte the
//! one-shot image (tested below against `save_rgb8`). The filter heuristic is the `png`
//! crate's: per row the first of Up, Sub, Avg, Paeth with the smallest sum of |byte as i8|,
//! later filters winning ties, stopping at a zero sum.

use std::io::Write;
use std::path::Path;

use super::png::{SCENE_KEYWORD, SETTINGS_KEYWORD};
use super::{OutputError, Provenance};

/// The samples of a streamed PNG.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowLayout {
    /// 8-bit RGB.
    Rgb8,
    /// 8-bit RGBA.
    Rgba8,
    /// 16-bit RGB, big-endian samples.
    Rgb16,
    /// 16-bit RGBA, big-endian samples.
    Rgba16,
}

impl RowLayout {
    /// Bytes per pixel.
    pub fn bytes_per_pixel(self) -> usize {
        match self {
            RowLayout::Rgb8 => 3,
            RowLayout::Rgba8 => 4,
            RowLayout::Rgb16 => 6,
            RowLayout::Rgba16 => 8,
        }
    }

    /// IHDR bit depth and colour type.
    fn depth_and_color(self) -> (u8, u8) {
        match self {
            RowLayout::Rgb8 => (8, 2),
            RowLayout::Rgba8 => (8, 6),
            RowLayout::Rgb16 => (16, 2),
            RowLayout::Rgba16 => (16, 6),
        }
    }
}

/// Largest IDAT chunk the `png` crate writes (longer streams take several).
const MAX_IDAT_BYTES: usize = (u32::MAX >> 1) as usize;

/// Writes a `width`×`height` PNG of `layout` to `path` atomically, with `provenance` in iTXt
/// chunks. `row(y, bytes)` fills row `y` (`width` · bytes per pixel bytes); it may be called
/// twice per row (a second pass when compression does not pay) and must give the same bytes.
pub fn write_rows(
    path: &Path,
    width: u32,
    height: u32,
    layout: RowLayout,
    provenance: Option<&Provenance>,
    mut row: impl FnMut(u32, &mut [u8]),
) -> Result<(), OutputError> {
    let io = |source: std::io::Error| OutputError::Io { path: path.display().to_string(), source };
    let idat = compress(width, height, layout, &mut row).map_err(io)?;
    crate::io::write_atomic(path, |w| {
        w.write_all(&[0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'])?;
        let (depth, color) = layout.depth_and_color();
        let mut ihdr = Vec::with_capacity(13);
        ihdr.extend_from_slice(&width.to_be_bytes());
        ihdr.extend_from_slice(&height.to_be_bytes());
        ihdr.extend_from_slice(&[depth, color, 0, 0, 0]);
        write_chunk(w, b"IHDR", &ihdr)?;
        if let Some(p) = provenance {
            for (keyword, text) in [(SCENE_KEYWORD, p.scene_toml.as_str()), (SETTINGS_KEYWORD, &p.settings_text())] {
                let mut data = Vec::with_capacity(keyword.len() + 5 + text.len());
                data.extend_from_slice(keyword.as_bytes());
                data.extend_from_slice(&[0, 0, 0, 0, 0]);
                data.extend_from_slice(text.as_bytes());
                write_chunk(w, b"iTXt", &data)?;
            }
        }
        for chunk in idat.chunks(MAX_IDAT_BYTES) {
            write_chunk(w, b"IDAT", chunk)?;
        }
        write_chunk(w, b"IEND", &[])
    })
    .map_err(io)
}

fn write_chunk(w: &mut dyn Write, kind: &[u8; 4], data: &[u8]) -> std::io::Result<()> {
    w.write_all(&(data.len() as u32).to_be_bytes())?;
    let mut head = [0u8; 4];
    head.copy_from_slice(kind);
    w.write_all(&head)?;
    w.write_all(data)?;
    let crc = super::png::crc32_continue(super::png::crc32_continue(!0, kind), data);
    w.write_all(&(!crc).to_be_bytes())
}

/// The zlib stream of the filtered rows, as the `png` crate's `write_image_data` makes it with
/// `fdeflate`.
fn compress(
    width: u32,
    height: u32,
    layout: RowLayout,
    row: &mut impl FnMut(u32, &mut [u8]),
) -> std::io::Result<Vec<u8>> {
    let bpp = layout.bytes_per_pixel();
    let len = width as usize * bpp;
    let mut previous = vec![0u8; len];
    let mut current = vec![0u8; len];
    let mut filtered = vec![0u8; len + 1];
    let mut compressor = fdeflate::Compressor::new(std::io::Cursor::new(Vec::new()))?;
    for y in 0..height {
        row(y, &mut current);
        filtered[0] = adaptive_filter(bpp, &previous, &current, &mut filtered[1..]);
        compressor.write_data(&filtered)?;
        std::mem::swap(&mut previous, &mut current);
    }
    let compressed = compressor.finish()?.into_inner();
    if compressed.len() <= fdeflate::StoredOnlyCompressor::<()>::compressed_size((len + 1) * height as usize) {
        return Ok(compressed);
    }
    // Compression does not pay: stored blocks of the unfiltered rows, as the png crate does.
    drop(compressed);
    let mut stored = fdeflate::StoredOnlyCompressor::new(std::io::Cursor::new(Vec::new()))?;
    for y in 0..height {
        row(y, &mut current);
        stored.write_data(&[0])?;
        stored.write_data(&current)?;
    }
    Ok(stored.finish()?.into_inner())
}

/// PNG filter types.
const UP: u8 = 2;
const SUB: u8 = 1;
const AVG: u8 = 3;
const PAETH: u8 = 4;

/// Filters `current` (after `previous`) into `out` with the `png` crate's adaptive choice and
/// returns the filter type.
fn adaptive_filter(bpp: usize, previous: &[u8], current: &[u8], out: &mut [u8]) -> u8 {
    let mut min_cost = u64::MAX;
    let mut choice = 0;
    for filter in [UP, SUB, AVG, PAETH] {
        apply_filter(filter, bpp, previous, current, out);
        let cost = out.iter().map(|&b| u64::from((b as i8).unsigned_abs())).sum::<u64>();
        if cost <= min_cost {
            min_cost = cost;
            choice = filter;
            if cost == 0 {
                return choice;
            }
        }
    }
    if choice != PAETH {
        apply_filter(choice, bpp, previous, current, out);
    }
    choice
}

/// The PNG filter `filter` of row `current` above which lies `previous` (PNG spec, section 9).
fn apply_filter(filter: u8, bpp: usize, previous: &[u8], current: &[u8], out: &mut [u8]) {
    match filter {
        SUB => filter_row(bpp, previous, current, out, |x, a, _, _| x.wrapping_sub(a)),
        UP => filter_row(bpp, previous, current, out, |x, _, b, _| x.wrapping_sub(b)),
        AVG => filter_row(bpp, previous, current, out, |x, a, b, _| x.wrapping_sub(((a as u16 + b as u16) / 2) as u8)),
        _ => filter_row(bpp, previous, current, out, |x, a, b, c| x.wrapping_sub(paeth(a, b, c))),
    }
}

/// `out[i] = filter(x, a, b, c)` for each byte x of `current`, with a the byte `bpp` to its
/// left, b the byte above, c the one above a (0 left of the row). The first pixel apart, the
/// loop runs over offset slices without a branch, so that it compiles to vector code (the
/// filter is the encoder's largest cost, on one thread).
#[inline(always)]
fn filter_row(bpp: usize, previous: &[u8], current: &[u8], out: &mut [u8], filter: impl Fn(u8, u8, u8, u8) -> u8) {
    let n = current.len();
    let head = bpp.min(n);
    for i in 0..head {
        out[i] = filter(current[i], 0, previous[i], 0);
    }
    if n > bpp {
        let (x, b, a, c) = (&current[bpp..], &previous[bpp..n], &current[..n - bpp], &previous[..n - bpp]);
        for ((((o, &x), &a), &b), &c) in out[bpp..n].iter_mut().zip(x).zip(a).zip(b).zip(c) {
            *o = filter(x, a, b, c);
        }
    }
}

/// The Paeth predictor (p = a + b − c; the nearest of a, b, c to p, ties in that order),
/// written with selects rather than branches so that [`filter_row`] vectorizes.
#[inline(always)]
fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let (a16, b16, c16) = (a as i16, b as i16, c as i16);
    // p − a, p − b and p − c.
    let (pa, pb, pc) = ((b16 - c16).abs(), (a16 - c16).abs(), (a16 + b16 - 2 * c16).abs());
    let b_or_c = if pb <= pc { b } else { c };
    if pa <= pb && pa <= pc { a } else { b_or_c }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("nlifs-png-rows-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("x.png")
    }

    /// The PNG spec's filters (section 9), byte by byte: the oracle of [`apply_filter`].
    fn spec_filter(filter: u8, bpp: usize, previous: &[u8], current: &[u8]) -> Vec<u8> {
        (0..current.len())
            .map(|i| {
                let (x, b) = (current[i], previous[i]);
                let (a, c) = if i >= bpp { (current[i - bpp], previous[i - bpp]) } else { (0, 0) };
                let p = a as i16 + b as i16 - c as i16;
                let (pa, pb, pc) = ((p - a as i16).abs(), (p - b as i16).abs(), (p - c as i16).abs());
                let predictor = match filter {
                    SUB => a,
                    UP => b,
                    AVG => ((a as u16 + b as u16) / 2) as u8,
                    _ if pa <= pb && pa <= pc => a,
                    _ if pb <= pc => b,
                    _ => c,
                };
                x.wrapping_sub(predictor)
            })
            .collect()
    }

    /// Every filter of every layout's pixel size equals the spec's byte loop on random rows,
    /// rows of extreme bytes (where Paeth's ties and the average's carry matter) and rows
    /// shorter than a pixel's offset.
    #[test]
    fn filters_equal_the_spec() {
        let mut rng = crate::rng::Pcg32::for_stream(11, 0, 0);
        for case in 0..200 {
            let bpp = [3, 4, 6, 8][case % 4];
            let len = [1, 2, bpp, bpp + 1, 61 * bpp, 1000 + case][case % 6];
            let mut byte = || match case / 12 % 3 {
                0 => rng.next_u32() as u8,
                1 => [0, 1, 127, 128, 254, 255][rng.next_u32() as usize % 6],
                _ => (rng.next_u32() % 4) as u8,
            };
            let previous: Vec<u8> = (0..len).map(|_| byte()).collect();
            let current: Vec<u8> = (0..len).map(|_| byte()).collect();
            for filter in [UP, SUB, AVG, PAETH] {
                let mut out = vec![0; len];
                apply_filter(filter, bpp, &previous, &current, &mut out);
                assert_eq!(out, spec_filter(filter, bpp, &previous, &current), "case {case}, filter {filter}");
            }
        }
    }

    /// Streamed PNGs are the bytes `save_rgb8` writes (the `image` crate's encoder plus the text
    /// chunks): a smooth image, a noisy one (each filter wins some rows), a flat one (zero-cost
    /// rows), and pure noise (where compression does not pay and stored blocks are written).
    #[test]
    fn streamed_rgb8_equals_the_one_shot_bytes() {
        let provenance = Provenance {
            scene_toml: "version = 1\n".into(),
            t_secs: 0.5,
            settings: serde_json::json!({ "t_secs": 0.5 }),
        };
        let mut rng = crate::rng::Pcg32::for_stream(3, 0, 0);
        let noise: Vec<u8> = (0..61 * 37 * 3).map(|_| rng.next_u32() as u8).collect();
        let images: Vec<image::RgbImage> = vec![
            image::RgbImage::from_fn(61, 37, |x, y| image::Rgb([(x * 4) as u8, (y * 7) as u8, (x * y) as u8])),
            image::RgbImage::from_fn(61, 37, |x, y| {
                let n = ((x * 31 + y * 17) % 7) as u8;
                image::Rgb([n * 30, 255 - n * 20, if (x + y) % 5 == 0 { 255 } else { 0 }])
            }),
            image::RgbImage::from_pixel(61, 37, image::Rgb([10, 20, 30])),
            image::RgbImage::from_raw(61, 37, noise).unwrap(),
        ];
        for (i, img) in images.iter().enumerate() {
            let (a, b) = (temp(&format!("a{i}")), temp(&format!("b{i}")));
            super::super::png::save_rgb8(&a, img, Some(&provenance)).unwrap();
            write_rows(&b, img.width(), img.height(), RowLayout::Rgb8, Some(&provenance), |y, out| {
                let w = img.width() as usize * 3;
                out.copy_from_slice(&img.as_raw()[y as usize * w..(y as usize + 1) * w]);
            })
            .unwrap();
            assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "image {i}");
            let _ = std::fs::remove_dir_all(a.parent().unwrap());
            let _ = std::fs::remove_dir_all(b.parent().unwrap());
        }
    }
}
