//! Point clouds out: binary little-endian PLY and glTF 2.0 binary (.glb) with a POINTS
//! primitive. Positions are in the scene's own coordinates; colours are the functions' colours
//! (linear RGB in glTF, as its COLOR_0 requires; sRGB bytes in PLY, as viewers expect).

use std::io::Write;

use glam::Vec3;

use crate::color;

pub fn write_ply(w: &mut dyn Write, points: &[Vec3], colors: &[[f32; 3]]) -> std::io::Result<()> {
    write_ply_header(w, points.len() as u64)?;
    write_ply_vertices(w, points, colors)
}

/// The header of a binary PLY of `count` coloured vertices; [`write_ply_vertices`] follows.
pub fn write_ply_header(w: &mut dyn Write, count: u64) -> std::io::Result<()> {
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by nlifs\nelement vertex {count}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
    )
}

/// Vertices of a PLY: position and sRGB colour bytes each. Called once or batch by batch.
pub fn write_ply_vertices(w: &mut dyn Write, points: &[Vec3], colors: &[[f32; 3]]) -> std::io::Result<()> {
    let mut buf = Vec::with_capacity(points.len() * 15);
    for (p, c) in points.iter().zip(colors) {
        for v in p.to_array() {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        for v in c {
            buf.push(color::linear_to_srgb8(*v));
        }
    }
    w.write_all(&buf)
}

/// A glTF 2.0 binary with one mesh of one POINTS primitive (POSITION float VEC3, COLOR_0
/// normalized unsigned byte VEC4), validated with the Khronos validator.
pub fn write_glb_points(w: &mut dyn Write, points: &[Vec3], colors: &[[f32; 3]]) -> std::io::Result<()> {
    let bounds = points.iter().fold(None, |b, p| Some(point_bounds(b, *p)));
    write_glb_points_streamed(
        w,
        points.len() as u64,
        bounds,
        |w| write_glb_positions(w, points),
        |w| write_glb_colors(w, colors),
    )
}

/// The bounds the GLB's POSITION accessor gives after `p`: `bounds` (None before the first
/// point) widened by `p`, in the order the points come (glam's min and max, whose NaN and
/// signed-zero results depend on the order).
pub fn point_bounds(bounds: Option<(Vec3, Vec3)>, p: Vec3) -> (Vec3, Vec3) {
    let (lo, hi) = bounds.unwrap_or((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)));
    (lo.min(p), hi.max(p))
}

/// POSITION bytes of [`write_glb_points_streamed`], batch by batch.
pub fn write_glb_positions(w: &mut dyn Write, points: &[Vec3]) -> std::io::Result<()> {
    let mut bin = Vec::with_capacity(points.len() * 12);
    for p in points {
        for v in p.to_array() {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    w.write_all(&bin)
}

/// COLOR_0 bytes of [`write_glb_points_streamed`], batch by batch.
pub fn write_glb_colors(w: &mut dyn Write, colors: &[[f32; 3]]) -> std::io::Result<()> {
    let mut bin = Vec::with_capacity(colors.len() * 4);
    for c in colors {
        for v in c {
            bin.push(color::linear_to_unorm8(*v));
        }
        bin.push(255);
    }
    w.write_all(&bin)
}

/// [`write_glb_points`] of `n` points whose bytes come from `positions` (n · 12 bytes, see
/// [`write_glb_positions`]) and then `colors` (n · 4 bytes, [`write_glb_colors`]), so that the
/// points need not be held: the same bytes. `bounds` are the points' ([`point_bounds`]; None
/// for no points).
pub fn write_glb_points_streamed(
    w: &mut dyn Write,
    n: u64,
    bounds: Option<(Vec3, Vec3)>,
    positions: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    colors: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let (lo, hi) = bounds.unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let color_offset = n * 12;
    let bin_len = n * 16;
    let json = serde_json::json!({
        "asset": { "version": "2.0", "generator": "nlifs" },
        "scene": 0,
        "scenes": [ { "nodes": [0] } ],
        "nodes": [ { "mesh": 0, "name": "attractor" } ],
        "meshes": [ { "name": "attractor", "primitives": [ {
            "attributes": { "POSITION": 0, "COLOR_0": 1 },
            "mode": 0
        } ] } ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
              "min": lo.to_array(), "max": hi.to_array() },
            { "bufferView": 1, "componentType": 5121, "normalized": true, "count": n, "type": "VEC4" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": color_offset, "target": 34962 },
            { "buffer": 0, "byteOffset": color_offset, "byteLength": bin_len - color_offset, "target": 34962 }
        ],
        "buffers": [ { "byteLength": bin_len } ]
    });
    write_glb_streamed(w, &json, bin_len, |w| {
        positions(w)?;
        colors(w)
    })
}

/// Writes a GLB container: header, JSON chunk padded with spaces, BIN chunk padded with zeros.
pub fn write_glb(w: &mut dyn Write, json: &serde_json::Value, bin: &[u8]) -> std::io::Result<()> {
    write_glb_streamed(w, json, bin.len() as u64, |w| w.write_all(bin))
}

/// [`write_glb`] with the BIN chunk's `bin_len` bytes written by `bin`. The size limit is checked
/// before anything is written.
pub fn write_glb_streamed(
    w: &mut dyn Write,
    json: &serde_json::Value,
    bin_len: u64,
    bin: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut json_bytes = serde_json::to_vec(json).map_err(std::io::Error::other)?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let bin_padded = bin_len.div_ceil(4) * 4;
    let (total, json_len, bin_chunk_len) =
        glb_lengths(json_bytes.len(), usize::try_from(bin_padded).unwrap_or(usize::MAX))?;
    w.write_all(b"glTF")?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&json_len.to_le_bytes())?;
    w.write_all(b"JSON")?;
    w.write_all(&json_bytes)?;
    w.write_all(&bin_chunk_len.to_le_bytes())?;
    w.write_all(b"BIN\0")?;
    bin(w)?;
    w.write_all(&vec![0u8; (bin_padded - bin_len) as usize])
}

/// The file, JSON chunk and BIN chunk lengths of a GLB with padded chunks of `json_bytes` and
/// `bin_bytes`. GLB stores them in 32 bits, so a file past 4 GiB is refused before anything is
/// written, with an error of kind `FileTooLarge` that gives the size.
pub fn glb_lengths(json_bytes: usize, bin_bytes: usize) -> std::io::Result<(u32, u32, u32)> {
    let total = 12 + 8 + json_bytes as u64 + 8 + bin_bytes as u64;
    match (u32::try_from(total), u32::try_from(json_bytes), u32::try_from(bin_bytes)) {
        (Ok(total), Ok(json), Ok(bin)) => Ok((total, json, bin)),
        _ => Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!(
                "the GLB would have {total} bytes, more than the {} (4 GiB) the format can hold; ask for fewer points or a lower depth",
                u32::MAX
            ),
        )),
    }
}
