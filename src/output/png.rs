//! PNG output: 8-bit and 16-bit, opaque or with alpha, and the scene that made the image in
//! iTXt chunks (`nlifs:scene` holds the scene's TOML verbatim, `nlifs:settings` a JSON object
//! with the time and the settings), so that any PNG nlifs writes can be reopened as its scene
//! ([`scene_from_png`]).
//!
//! The pixels are encoded by the `image` crate exactly as before and the text chunks are
//! spliced in after the header, so a PNG's bytes differ from one without provenance only by
//! those chunks.

use std::path::Path;

use crate::color::linear_to_srgb;
use crate::output::{Format, ImageLayers, OutputError, OutputOptions, Provenance};
use crate::scene::spec::MAX_TIME_SECS;

/// The keyword of the chunk holding the scene's TOML.
pub const SCENE_KEYWORD: &str = "nlifs:scene";
/// The keyword of the chunk holding the time and settings as JSON.
pub const SETTINGS_KEYWORD: &str = "nlifs:settings";

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// What an 8-bit unorm sample stores for a linear value: the resolve's `unorm8` of the sRGB
/// encode, so that an opaque 8-bit PNG made from layers equals `resolve_image`'s.
fn srgb8(v: f32) -> u8 {
    (linear_to_srgb(v) * 255.0 + 0.5) as u8
}

/// 16 bits from the linear value, with no 8-bit step in between.
fn srgb16(v: f32) -> u16 {
    (linear_to_srgb(v).clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
}

/// Encodes an image buffer as PNG bytes with the `image` crate's default settings.
fn encode<P>(img: &image::ImageBuffer<P, Vec<P::Subpixel>>) -> Result<Vec<u8>, image::ImageError>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
{
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    Ok(bytes)
}

/// Writes the plain 8-bit opaque image `img` (what `resolve_image` made) with `provenance`.
pub fn save_rgb8(path: &Path, img: &image::RgbImage, provenance: Option<&Provenance>) -> Result<(), OutputError> {
    let bytes = encode(img).map_err(|e| io_error(path, std::io::Error::other(e)))?;
    save_bytes(path, bytes, provenance)
}

/// Writes `layers` as a PNG in `options.format` (8 or 16 bits; RGBA where transparent).
pub fn write_layers(
    path: &Path,
    layers: &ImageLayers,
    options: &OutputOptions,
    provenance: Option<&Provenance>,
) -> Result<(), OutputError> {
    let (w, h) = (layers.width(), layers.height());
    let rgba = layers.rgba_straight(options.transparent);
    let sixteen = options.format == Format::Png16;
    let bytes = match (sixteen, options.transparent) {
        (false, false) => {
            let raw = rgba.iter().flat_map(|p| [srgb8(p[0]), srgb8(p[1]), srgb8(p[2])]).collect();
            encode(&image::RgbImage::from_raw(w, h, raw).expect("size"))
        }
        (false, true) => {
            let raw = rgba.iter().flat_map(|p| [srgb8(p[0]), srgb8(p[1]), srgb8(p[2]), alpha8(p[3])]).collect();
            encode(&image::RgbaImage::from_raw(w, h, raw).expect("size"))
        }
        (true, false) => {
            let raw = rgba.iter().flat_map(|p| [srgb16(p[0]), srgb16(p[1]), srgb16(p[2])]).collect();
            encode(&image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_raw(w, h, raw).expect("size"))
        }
        (true, true) => {
            let raw = rgba.iter().flat_map(|p| [srgb16(p[0]), srgb16(p[1]), srgb16(p[2]), alpha16(p[3])]).collect();
            encode(&image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_raw(w, h, raw).expect("size"))
        }
    }
    .map_err(|e| io_error(path, std::io::Error::other(e)))?;
    save_bytes(path, bytes, provenance)
}

/// Alpha is linear coverage: no sRGB encode.
fn alpha8(a: f32) -> u8 {
    (a.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

fn alpha16(a: f32) -> u16 {
    (a.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
}

fn io_error(path: &Path, source: std::io::Error) -> OutputError {
    OutputError::Io { path: path.display().to_string(), source }
}

fn save_bytes(path: &Path, bytes: Vec<u8>, provenance: Option<&Provenance>) -> Result<(), OutputError> {
    let bytes = match provenance {
        Some(p) => with_text_chunks(&bytes, &[(SCENE_KEYWORD, &p.scene_toml), (SETTINGS_KEYWORD, &p.settings_text())]),
        None => bytes,
    };
    crate::io::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| io_error(path, e))
}

/// `png` with uncompressed iTXt chunks (keyword, UTF-8 text) inserted after the IHDR chunk.
/// `png` must be a PNG whose first chunk is IHDR (as every encoder writes it).
pub fn with_text_chunks(png: &[u8], chunks: &[(&str, &str)]) -> Vec<u8> {
    // Signature, then IHDR: length (4) + type (4) + 13 data bytes + CRC (4).
    let after_ihdr = SIGNATURE.len() + 4 + 4 + 13 + 4;
    let mut out = Vec::with_capacity(png.len() + chunks.iter().map(|(k, t)| k.len() + t.len() + 17).sum::<usize>());
    out.extend_from_slice(&png[..after_ihdr]);
    for (keyword, text) in chunks {
        // iTXt: keyword, NUL, compression flag 0, method 0, empty language tag and
        // translated keyword (each NUL-terminated), then the UTF-8 text.
        let mut data = Vec::with_capacity(keyword.len() + 5 + text.len());
        data.extend_from_slice(keyword.as_bytes());
        data.extend_from_slice(&[0, 0, 0, 0, 0]);
        data.extend_from_slice(text.as_bytes());
        push_chunk(&mut out, b"iTXt", &data);
    }
    out.extend_from_slice(&png[after_ihdr..]);
    out
}

fn push_chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// The CRC-32 of PNG chunks (ISO 3309, polynomial 0xedb88320).
pub fn crc32(bytes: &[u8]) -> u32 {
    !crc32_continue(!0, bytes)
}

/// The CRC-32 register after `bytes`, from register `crc`: start with !0, complement at the end
/// ([`crc32`]). Chained, so that a chunk's data need not be copied next to its type.
pub fn crc32_continue(crc: u32, bytes: &[u8]) -> u32 {
    static TABLE: std::sync::OnceLock<[u32; 256]> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        let mut t = [0u32; 256];
        for (n, slot) in t.iter_mut().enumerate() {
            let mut c = n as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xedb8_8320 ^ (c >> 1) } else { c >> 1 };
            }
            *slot = c;
        }
        t
    });
    bytes.iter().fold(crc, |c, &b| table[((c ^ b as u32) & 0xff) as usize] ^ (c >> 8))
}

/// The uncompressed iTXt and tEXt chunks of PNG bytes as (keyword, text), in file order.
/// Stops at IDAT (nlifs writes its chunks before it). Chunks with a bad CRC are an error.
pub fn text_chunks(png: &[u8], path: &Path) -> Result<Vec<(String, String)>, OutputError> {
    let invalid = |message: String| OutputError::Invalid { path: path.display().to_string(), message };
    if png.len() < SIGNATURE.len() || png[..8] != SIGNATURE {
        return Err(invalid("not a PNG file".into()));
    }
    let mut out = Vec::new();
    let mut at = SIGNATURE.len();
    while at + 8 <= png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().expect("4 bytes")) as usize;
        let kind = &png[at + 4..at + 8];
        let end = at + 8 + len + 4;
        if end > png.len() {
            return Err(invalid(format!(
                "truncated {} chunk",
                crate::io::printable(&String::from_utf8_lossy(kind), false)
            )));
        }
        if kind == b"IDAT" || kind == b"IEND" {
            break;
        }
        let data = &png[at + 8..at + 8 + len];
        let crc = u32::from_be_bytes(png[end - 4..end].try_into().expect("4 bytes"));
        if (kind == b"iTXt" || kind == b"tEXt") && crc32(&png[at + 4..at + 8 + len]) != crc {
            return Err(invalid(format!(
                "{} chunk with a bad checksum",
                crate::io::printable(&String::from_utf8_lossy(kind), false)
            )));
        }
        if let Some(kw_end) = data.iter().position(|&b| b == 0) {
            // Escaped: the keyword appears in messages.
            let keyword = crate::io::printable(&String::from_utf8_lossy(&data[..kw_end]), false).into_owned();
            if kind == b"tEXt" {
                out.push((keyword, data[kw_end + 1..].iter().map(|&b| b as char).collect()));
            } else if kind == b"iTXt" && data.get(kw_end + 1) == Some(&0) {
                // Skip the flags, then the language tag and translated keyword.
                let rest = data.get(kw_end + 3..).unwrap_or_default();
                let mut parts = rest.splitn(3, |&b| b == 0);
                let (_lang, _translated, text) = (parts.next(), parts.next(), parts.next().unwrap_or_default());
                let text = String::from_utf8(text.to_vec())
                    .map_err(|_| invalid(format!("iTXt chunk `{keyword}` is not UTF-8")))?;
                out.push((keyword, text));
            }
        }
        at = end;
    }
    Ok(out)
}

/// The provenance nlifs wrote into the PNG at `path`: its scene's TOML, time and settings.
pub fn scene_from_png(path: &Path) -> Result<Provenance, OutputError> {
    let bytes = std::fs::read(path).map_err(|source| OutputError::Read { path: path.display().to_string(), source })?;
    scene_from_png_bytes(&bytes, path)
}

/// [`scene_from_png`] of a PNG's bytes (a file the browser read); `path` names it in errors.
pub fn scene_from_png_bytes(bytes: &[u8], path: &Path) -> Result<Provenance, OutputError> {
    let chunks = text_chunks(bytes, path)?;
    let find = |kw: &str| chunks.iter().find(|(k, _)| k == kw).map(|(_, t)| t.clone());
    let scene_toml = find(SCENE_KEYWORD).ok_or_else(|| OutputError::Invalid {
        path: path.display().to_string(),
        message: format!("no embedded scene (no `{SCENE_KEYWORD}` text chunk): not written by nlifs, or stripped"),
    })?;
    let settings: serde_json::Value = match find(SETTINGS_KEYWORD) {
        Some(text) => serde_json::from_str(&text).map_err(|e| OutputError::Invalid {
            path: path.display().to_string(),
            message: format!("`{SETTINGS_KEYWORD}` is not JSON: {e}"),
        })?,
        None => serde_json::json!({}),
    };
    // The time is printed and rendered at: a number of the scene format's key range, not
    // whatever the chunk holds (1e308 printed as 309 digits).
    let t_secs = match settings.get("t_secs") {
        None => 0.0,
        Some(t) => t.as_f64().filter(|t| (0.0..=MAX_TIME_SECS).contains(t)).ok_or_else(|| OutputError::Invalid {
            path: path.display().to_string(),
            message: format!(
                "`{SETTINGS_KEYWORD}` gives t_secs = {}, not a scene time (0 to {MAX_TIME_SECS:e} s)",
                match t.as_f64() {
                    Some(t) => format!("{t:e}"),
                    None =>
                        crate::io::printable(&t.to_string().chars().take(40).collect::<String>(), false).into_owned(),
                }
            ),
        })?,
    };
    Ok(Provenance { scene_toml, t_secs, settings })
}

/// Whether `bytes` begin with the PNG signature.
pub fn is_png_bytes(bytes: &[u8]) -> bool {
    bytes.starts_with(&SIGNATURE)
}

/// Whether `path` is a PNG file (by its signature), for commands that take a scene or an image.
pub fn is_png(path: &Path) -> bool {
    let mut head = [0u8; 8];
    std::fs::File::open(path).and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head)).is_ok()
        && head == SIGNATURE
}

/// Loads the scene at `path`, or the scene embedded in a PNG at `path`, with the time it was
/// rendered at (0 for a scene file).
pub fn load_scene_or_png(path: &Path) -> Result<(crate::scene::Scene, f64), OutputError> {
    if is_png(path) {
        let p = scene_from_png(path)?;
        let scene = p.scene(&format!("{} (embedded scene)", path.display()))?;
        Ok((scene, p.t_secs))
    } else {
        Ok((crate::scene::Scene::load(path)?, 0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_of_known_text() {
        assert_eq!(crc32(b"IEND"), 0xae42_6082);
        assert_eq!(crc32(b"123456789"), 0xcbf4_3926);
    }

    #[test]
    fn text_chunks_round_trip_and_leave_pixels() {
        let img = image::RgbImage::from_fn(7, 5, |x, y| image::Rgb([x as u8 * 30, y as u8 * 40, 7]));
        let plain = encode(&img).unwrap();
        let text = "name = \"ünïcode\"\n[render]\nwidth = 7\n";
        let with = with_text_chunks(&plain, &[(SCENE_KEYWORD, text), (SETTINGS_KEYWORD, "{\"t_secs\":1.5}")]);
        let decoded = image::load_from_memory(&with).unwrap().to_rgb8();
        assert_eq!(decoded, img);
        let chunks = text_chunks(&with, Path::new("x.png")).unwrap();
        assert_eq!(chunks[0], (SCENE_KEYWORD.to_string(), text.to_string()));
        assert_eq!(chunks[1].1, "{\"t_secs\":1.5}");
        let mut broken = with.clone();
        broken[45] ^= 1;
        assert!(text_chunks(&broken, Path::new("x.png")).is_err());
    }
}
