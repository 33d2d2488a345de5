//! Partial renders of one still, for splitting it over machines: `nlifs render --part K/N
//! --raw OUT.part` runs chunks [(K−1)·C/N, K·C/N) of the still's C chaos-game chunks (each chunk
//! draws from its own random streams) and writes the accumulation; `nlifs merge` combines the N
//! parts. The accumulation is a min of keys (closest mode) or sums (average, density), so
//! the merged framebuffer, and the image, have the same bytes as one render of all points.
//!
//! A part file, little-endian: the magic `NLIFSPRT`, format version, K, N, the fingerprint of
//! scene + time + settings ([`Provenance::fingerprint`]), mode, width, height, the chunk range
//! and total, the provenance (JSON: scene TOML, time, settings, so that `merge` can rebuild the
//! view and embed the scene), the payload (one u32 key per pixel, or four u32 sums per pixel,
//! then the key light's shadow map where the still casts shadows), and an FNV-1a checksum of
//! everything before it. Merging checks all of it before writing.

use std::ops::Range;
use std::path::Path;

use crate::output::{OutputError, Provenance};
use crate::scene::Scene;
use crate::scene::spec::{DensityEstimation, Look, RenderSettings, SplatMode};
use crate::shot::{Framing, Shot};
use crate::splat::Framebuffer;

const MAGIC: &[u8; 8] = b"NLIFSPRT";
/// 2: the payload ends with the shadow map's keys where the still casts shadows.
const VERSION: u32 = 2;

/// 64-bit FNV-1a: a stable hash for fingerprints and checksums (std's hasher may change).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Fnv {
    pub fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    pub fn finish(self) -> u64 {
        self.0
    }
}

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}

/// Part K of N (1-based K).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartSpec {
    pub k: u32,
    pub n: u32,
}

impl PartSpec {
    /// Parses `K/N` with 1 ≤ K ≤ N.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (k, n) = text.split_once('/').ok_or_else(|| format!("`{text}` is not a part; write K/N, e.g. 1/4"))?;
        let k: u32 = k.trim().parse().map_err(|_| format!("`{k}` in --part {text} is not a part number"))?;
        let n: u32 = n.trim().parse().map_err(|_| format!("`{n}` in --part {text} is not a part count"))?;
        if n == 0 || k == 0 || k > n {
            return Err(format!("--part {text} is out of range: K must lie in 1..=N (parts are numbered from 1)"));
        }
        Ok(Self { k, n })
    }

    /// The chunks of `chunks` this part runs.
    pub fn chunk_range(&self, chunks: u32) -> Range<u32> {
        let at = |k: u32| (k as u64 * chunks as u64 / self.n as u64) as u32;
        at(self.k - 1)..at(self.k)
    }
}

/// The still's shot, prepared as `nlifs render` prepares it, so that parts and a full render
/// agree; `origin` names the scene in errors.
fn shot_of(scene: &Scene, t_secs: f64, settings: &RenderSettings, origin: &str) -> Result<Shot, OutputError> {
    Shot::prepare(scene, t_secs, settings, Framing::Fit, None)
        .map_err(|e| OutputError::Invalid { path: origin.into(), message: e.to_string() })
}

/// A rendered part: its accumulation and what made it.
pub struct Part {
    pub spec: PartSpec,
    pub provenance: Provenance,
    pub chunks: Range<u32>,
    pub total_chunks: u32,
    pub framebuffer: Framebuffer,
}

/// Renders part `spec` of the still of `scene` at `t_secs` with `settings`. `progress(done,
/// total)` follows finished chunks of this part.
pub fn render_part(
    scene: &Scene,
    t_secs: f64,
    settings: &RenderSettings,
    spec: PartSpec,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Part, OutputError> {
    let shot = shot_of(scene, t_secs, settings, &scene.name)?;
    let total_chunks = shot.plan.chunks();
    let chunks = spec.chunk_range(total_chunks);
    let done = std::sync::atomic::AtomicU64::new(0);
    let todo = chunks.len() as u64;
    let accumulation = crate::shot::Accumulation::for_view(&shot.view);
    let framebuffer = shot.splat_chunks(chunks.clone(), accumulation, || {
        progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1, todo)
    });
    let provenance = Provenance::for_render(scene, t_secs, settings);
    Ok(Part { spec, provenance, chunks, total_chunks, framebuffer })
}

fn provenance_json(p: &Provenance) -> String {
    serde_json::json!({ "scene_toml": p.scene_toml, "t_secs": p.t_secs, "settings": p.settings }).to_string()
}

/// Writes `part` to `path` atomically.
pub fn write_part(path: &Path, part: &Part) -> Result<(), OutputError> {
    let fb = &part.framebuffer;
    let image: &[u32] = match fb.view.mode {
        SplatMode::Closest => &fb.closest,
        _ => bytemuck::cast_slice(&fb.accum),
    };
    // The shadow map (empty without shadows) follows the image's accumulation.
    let payload = || image.iter().chain(&fb.shadow);
    let payload_words = image.len() + fb.shadow.len();
    let prov = provenance_json(&part.provenance);
    let mut head = Vec::new();
    head.extend_from_slice(MAGIC);
    for v in [VERSION, part.spec.k, part.spec.n] {
        head.extend_from_slice(&v.to_le_bytes());
    }
    head.extend_from_slice(&part.provenance.fingerprint().to_le_bytes());
    let v = fb.view;
    for x in [v.mode.index(), v.width, v.height, part.chunks.start, part.chunks.end, part.total_chunks] {
        head.extend_from_slice(&x.to_le_bytes());
    }
    head.extend_from_slice(&(prov.len() as u32).to_le_bytes());
    head.extend_from_slice(prov.as_bytes());
    head.extend_from_slice(&(payload_words as u64 * 4).to_le_bytes());
    crate::io::write_atomic(path, |w| {
        let mut hash = Fnv::new();
        hash.write(&head);
        w.write_all(&head)?;
        let mut buf = Vec::with_capacity(1 << 16);
        let mut words = payload().peekable();
        while words.peek().is_some() {
            buf.clear();
            for x in words.by_ref().take(1 << 14) {
                buf.extend_from_slice(&x.to_le_bytes());
            }
            hash.write(&buf);
            w.write_all(&buf)?;
        }
        w.write_all(&hash.finish().to_le_bytes())
    })
    .map_err(|source| OutputError::Io { path: path.display().to_string(), source })
}

/// A part file, read and checked.
struct PartFile {
    spec: PartSpec,
    fingerprint: u64,
    mode: u32,
    width: u32,
    height: u32,
    chunks: Range<u32>,
    total_chunks: u32,
    provenance: Provenance,
    payload: Vec<u32>,
}

fn read_part(path: &Path) -> Result<PartFile, OutputError> {
    let name = path.display().to_string();
    let invalid = |message: String| OutputError::Invalid { path: name.clone(), message };
    let bytes = std::fs::read(path).map_err(|source| OutputError::Read { path: name.clone(), source })?;
    if bytes.len() < MAGIC.len() || &bytes[..8] != MAGIC {
        return Err(invalid("not an nlifs part file (written by `nlifs render --part K/N --raw`)".into()));
    }
    let truncated = || invalid(format!("truncated part file ({} bytes)", bytes.len()));
    let mut at = 8;
    let u32_at = |at: &mut usize| -> Result<u32, OutputError> {
        let v = bytes.get(*at..*at + 4).ok_or_else(truncated)?;
        *at += 4;
        Ok(u32::from_le_bytes(v.try_into().expect("4 bytes")))
    };
    let version = u32_at(&mut at)?;
    if version != VERSION {
        return Err(invalid(format!("part file version {version}; this nlifs reads version {VERSION}")));
    }
    let (k, n) = (u32_at(&mut at)?, u32_at(&mut at)?);
    let lo = u32_at(&mut at)? as u64;
    let hi = u32_at(&mut at)? as u64;
    let fingerprint = lo | hi << 32;
    let mode = u32_at(&mut at)?;
    let (width, height) = (u32_at(&mut at)?, u32_at(&mut at)?);
    let chunks = u32_at(&mut at)?..u32_at(&mut at)?;
    let total_chunks = u32_at(&mut at)?;
    let prov_len = u32_at(&mut at)? as usize;
    let prov = bytes.get(at..at + prov_len).ok_or_else(truncated)?;
    at += prov_len;
    let payload_len = bytes.get(at..at + 8).ok_or_else(truncated)?;
    let payload_len = u64::from_le_bytes(payload_len.try_into().expect("8 bytes")) as usize;
    at += 8;
    if bytes.len() != at + payload_len + 8 {
        return Err(truncated());
    }
    let mut hash = Fnv::new();
    hash.write(&bytes[..at + payload_len]);
    let stored = u64::from_le_bytes(bytes[at + payload_len..].try_into().expect("8 bytes"));
    if hash.finish() != stored {
        return Err(invalid("checksum mismatch: the part file is damaged".into()));
    }
    if k == 0 || k > n {
        return Err(invalid(format!("part {k}/{n} is out of range")));
    }
    let prov: serde_json::Value =
        serde_json::from_slice(prov).map_err(|e| invalid(format!("unreadable provenance: {e}")))?;
    let provenance = Provenance {
        scene_toml: prov["scene_toml"].as_str().unwrap_or_default().to_string(),
        t_secs: prov["t_secs"].as_f64().unwrap_or(0.0),
        settings: prov["settings"].clone(),
    };
    let payload = bytes[at..at + payload_len]
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
        .collect();
    Ok(PartFile {
        spec: PartSpec { k, n },
        fingerprint,
        mode,
        width,
        height,
        chunks,
        total_chunks,
        provenance,
        payload,
    })
}

/// What merging parts gives: the whole still's framebuffer, its camera and provenance.
pub struct Merged {
    pub framebuffer: Framebuffer,
    pub camera: crate::camera::OrbitCamera,
    pub provenance: Provenance,
    /// The look the settings ask for (what a render of all the points resolves with).
    pub style: crate::resolve::ResolveStyle,
    /// Density estimation, as the settings ask for it.
    pub density_estimation: Option<DensityEstimation>,
}

/// Reads, checks and merges the part files `paths`: all parts of one still (same fingerprint,
/// the same N, each K exactly once, all N present).
pub fn merge_parts(paths: &[std::path::PathBuf]) -> Result<Merged, OutputError> {
    let first_path = paths
        .first()
        .ok_or_else(|| OutputError::Invalid { path: "merge".into(), message: "no part files given".into() })?;
    let mut merged: Option<(PartFile, Shot, Framebuffer)> = None;
    let mut seen: Vec<(u32, String)> = Vec::new();
    for path in paths {
        let name = path.display().to_string();
        let part = read_part(path)?;
        let Some((first, _, fb)) = &mut merged else {
            let settings = settings_of(&part.provenance, &name)?;
            let scene = part.provenance.scene(&format!("{name} (embedded scene)"))?;
            let s = shot_of(&scene, part.provenance.t_secs, &settings, &name)?;
            if (s.view.width, s.view.height, s.view.mode.index()) != (part.width, part.height, part.mode)
                || part.payload.len() != payload_len(&s.view)
            {
                return Err(OutputError::Invalid {
                    path: name,
                    message: "size or mode differs from its settings".into(),
                });
            }
            let mut fb = Framebuffer::new(s.view, s.compiled.colors.clone());
            absorb(&mut fb, &part.payload);
            seen.push((part.spec.k, name));
            merged = Some((PartFile { payload: Vec::new(), ..part }, s, fb));
            continue;
        };
        let mismatch = |what: &str| OutputError::Invalid {
            path: name.clone(),
            message: format!(
                "{what} differs from {}'s: parts of different stills cannot be merged",
                first_path.display()
            ),
        };
        if part.fingerprint != first.fingerprint || part.provenance != first.provenance {
            return Err(mismatch("the scene, time or settings"));
        }
        if part.spec.n != first.spec.n || part.total_chunks != first.total_chunks {
            return Err(mismatch(&format!("the part count ({})", part.spec.n)));
        }
        if (part.width, part.height, part.mode) != (first.width, first.height, first.mode)
            || part.payload.len() != payload_len(&fb.view)
        {
            return Err(mismatch("the image size or mode"));
        }
        if part.chunks != part.spec.chunk_range(part.total_chunks) {
            return Err(OutputError::Invalid { path: name, message: "its chunk range does not match its part".into() });
        }
        if let Some((_, other)) = seen.iter().find(|(k, _)| *k == part.spec.k) {
            return Err(OutputError::Invalid {
                path: name,
                message: format!("part {}/{} is given twice (also {other})", part.spec.k, part.spec.n),
            });
        }
        absorb(fb, &part.payload);
        seen.push((part.spec.k, name));
    }
    let (first, s, mut framebuffer) = merged.expect("at least one part");
    let missing: Vec<String> = (1..=first.spec.n)
        .filter(|k| !seen.iter().any(|(s, _)| s == k))
        .map(|k| format!("{k}/{}", first.spec.n))
        .collect();
    if !missing.is_empty() {
        return Err(OutputError::Invalid {
            path: first_path.display().to_string(),
            message: format!("missing parts {} of this still", missing.join(", ")),
        });
    }
    // Every chunk of the still, in one part or another.
    framebuffer.points_drawn = s.plan.splats();
    let density_estimation = s.settings.density_estimation;
    Ok(Merged { framebuffer, camera: s.camera, style: s.style, density_estimation, provenance: first.provenance })
}

/// u32 words of a part's payload for `view`: the image's accumulation, then the shadow map's
/// keys.
fn payload_len(view: &crate::splat::SplatView) -> usize {
    let pixels = view.width as usize * view.height as usize;
    let image = if view.mode == SplatMode::Closest { pixels } else { 4 * pixels };
    image + view.shadow.map_or(0, |s| s.texels())
}

/// Merges a part's payload into `fb` as [`Framebuffer::merge`] does.
fn absorb(fb: &mut Framebuffer, payload: &[u32]) {
    let image_words = fb.closest.len() + 4 * fb.accum.len();
    let (image, shadow) = payload.split_at(image_words.min(payload.len()));
    for (a, &b) in fb.closest.iter_mut().zip(image) {
        *a = (*a).min(b);
    }
    let sums: &mut [u32] = bytemuck::cast_slice_mut(&mut fb.accum);
    for (a, &b) in sums.iter_mut().zip(image) {
        *a = a.saturating_add(b);
    }
    for (a, &b) in fb.shadow.iter_mut().zip(shadow) {
        *a = (*a).min(b);
    }
}

/// The render settings a render provenance describes: the scene's at its time, with the
/// overrides it records.
fn settings_of(p: &Provenance, origin: &str) -> Result<RenderSettings, OutputError> {
    let scene = p.scene(origin)?;
    let mut settings = scene.render_at(p.t_secs);
    let s = &p.settings;
    let bad = |field: &str| OutputError::Invalid { path: origin.into(), message: format!("settings lack `{field}`") };
    settings.width = s["width"].as_u64().ok_or_else(|| bad("width"))? as u32;
    settings.height = s["height"].as_u64().ok_or_else(|| bad("height"))? as u32;
    settings.points = s["points"].as_u64().ok_or_else(|| bad("points"))?;
    settings.seed = s["seed"].as_u64().ok_or_else(|| bad("seed"))? as u32;
    settings.mode = s["mode"].as_str().and_then(SplatMode::parse).ok_or_else(|| bad("mode"))?;
    // Overrides of the scene's look, tone and density estimation (`Provenance::for_render`).
    let floats = |v: &serde_json::Value| -> Option<Vec<f32>> {
        v.as_array()?.iter().map(|x| x.as_f64().map(|x| x as f32)).collect()
    };
    if let Some(v) = s.get("look") {
        settings.look =
            if v.is_null() { None } else { Some(v.as_str().and_then(Look::parse).ok_or_else(|| bad("look"))?) };
    }
    if let Some(v) = s.get("shading") {
        settings.shading = v.as_f64().map(|x| x as f32);
    }
    if let Some(v) = s.get("occlusion") {
        settings.occlusion = v.as_f64().map(|x| x as f32);
    }
    if let Some(v) = s.get("tone") {
        let tone = floats(v).filter(|t| t.len() == 5).ok_or_else(|| bad("tone"))?;
        for (slot, x) in settings.tone_mut().into_iter().zip(tone) {
            *slot = x;
        }
    }
    if let Some(v) = s.get("density_estimation") {
        settings.density_estimation = if v.is_null() {
            None
        } else {
            let d = floats(v).filter(|d| d.len() == 3).ok_or_else(|| bad("density_estimation"))?;
            Some(DensityEstimation { max_radius_px: d[0], min_radius_px: d[1], curve: d[2] })
        };
    }
    // The key light.
    if let Some(v) = s.get("shadows") {
        settings.shadows = v.as_f64().map(|x| x as f32);
    }
    if let Some(v) = s.get("light") {
        let light = floats(v).filter(|l| l.len() == 2).ok_or_else(|| bad("light"))?;
        (settings.light_yaw_deg, settings.light_pitch_deg) = (light[0], light[1]);
    }
    // Depth of field.
    if let Some(v) = s.get("aperture") {
        settings.aperture = v.as_f64().ok_or_else(|| bad("aperture"))? as f32;
    }
    if let Some(v) = s.get("focus_distance") {
        settings.focus_distance = v.as_f64().map(|x| x as f32);
    }
    palette_settings_of(s, &mut settings).ok_or_else(|| bad("palette"))?;
    Ok(settings)
}

/// The palette-colour overrides of `Provenance::for_render` (`color`, `palette` with its
/// entries) set in `settings`; None when they are malformed.
fn palette_settings_of(s: &serde_json::Value, settings: &mut RenderSettings) -> Option<()> {
    if let Some(v) = s.get("color") {
        settings.color = v.as_str().and_then(crate::scene::spec::ColorMode::parse)?;
    }
    if let Some(v) = s.get("palette") {
        settings.palette = if v.is_null() {
            None
        } else {
            let samples = v["sample_bits"]
                .as_array()?
                .iter()
                .map(|c| {
                    let c = c.as_array().filter(|c| c.len() == 3)?;
                    let bits = |k: usize| c[k].as_u64().and_then(|b| u32::try_from(b).ok());
                    Some([bits(0)?, bits(1)?, bits(2)?].map(f32::from_bits))
                })
                .collect::<Option<Vec<[f32; 3]>>>()
                .filter(|s| s.len() == crate::palette::SAMPLES)?;
            Some(crate::palette::Palette { source: v["source"].as_str()?.to_string(), samples })
        };
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_cover_the_chunks_once() {
        for (chunks, n) in [(1, 4), (7, 3), (100, 4), (5, 5)] {
            let mut covered = Vec::new();
            for k in 1..=n {
                covered.extend(PartSpec { k, n }.chunk_range(chunks));
            }
            assert_eq!(covered, (0..chunks).collect::<Vec<_>>(), "{chunks} chunks in {n} parts");
        }
    }

    #[test]
    fn part_specs_parse() {
        assert_eq!(PartSpec::parse("2/4"), Ok(PartSpec { k: 2, n: 4 }));
        for bad in ["0/4", "5/4", "1/0", "1", "a/2"] {
            assert!(PartSpec::parse(bad).is_err(), "{bad}");
        }
    }
}
