//! Image outputs for pipelines: the file formats a still or a frame is written in (8-bit PNG,
//! 16-bit PNG, multi-layer OpenEXR), the scene that made a PNG carried inside it, and the
//! partial accumulations (`part`) that split one still over several machines.
//!
//! Every writer takes the resolve in linear light ([`crate::resolve::resolve_linear`]) plus the
//! framebuffer's layers ([`ImageLayers`]), so that no format goes through 8-bit quantisation
//! first. The 8-bit opaque PNG is the same bytes as [`crate::resolve::resolve_image`] encodes
//! (plus the scene's text chunks). Every file is written atomically (`crate::io`).

use std::path::Path;

use crate::camera::OrbitCamera;
use crate::resolve::{self, LinearImage, ResolveStyle};
use crate::scene::Scene;
use crate::scene::spec::{RenderSettings, SplatMode};
use crate::splat::{EMPTY, Framebuffer};

pub mod exr;
pub mod memory;
pub mod part;
pub mod png;
pub mod png_rows;

/// An output file format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG (RGB, or RGBA with a transparent background).
    #[default]
    Png,
    /// 16-bit sRGB PNG, encoded from the linear colour.
    Png16,
    /// OpenEXR: linear RGBA plus the depth, function-id and count layers the mode has.
    Exr,
}

impl Format {
    pub const ALL: [Format; 3] = [Format::Png, Format::Png16, Format::Exr];

    pub fn name(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Png16 => "png16",
            Format::Exr => "exr",
        }
    }

    pub fn parse(text: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name().eq_ignore_ascii_case(text))
    }

    /// The file extension (without the dot) of files in this format.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png | Format::Png16 => "png",
            Format::Exr => "exr",
        }
    }

    /// The format a path asks for by its extension: .exr → EXR, .png → 8-bit PNG.
    pub fn for_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(Format::Exr),
            "png" => Some(Format::Png),
            _ => None,
        }
    }

    /// The format for `path` given an explicit choice: the choice must match the extension.
    pub fn resolve(path: &Path, chosen: Option<Format>) -> Result<Format, OutputError> {
        let by_ext = Self::for_path(path);
        match (chosen, by_ext) {
            (None, Some(f)) => Ok(f),
            (Some(f), Some(e)) if f.extension() == e.extension() => Ok(f),
            (Some(f), _) => Err(OutputError::Extension { path: path.display().to_string(), expected: f.extension() }),
            (None, None) => Err(OutputError::Extension { path: path.display().to_string(), expected: "png or .exr" }),
        }
    }
}

/// How an image is written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OutputOptions {
    pub format: Format,
    /// An alpha channel with the background left transparent (coverage as alpha).
    pub transparent: bool,
    /// EXR: RGBA as 16-bit halves instead of 32-bit floats (depth, id and count stay f32).
    pub half: bool,
}

impl OutputOptions {
    /// Whether this output is the plain 8-bit opaque PNG that [`resolve::resolve_image`] makes.
    pub fn is_plain_png(&self) -> bool {
        self.format == Format::Png && !self.transparent
    }
}

/// What made an image: the scene (as TOML), the scene time and the settings. PNGs carry it in
/// iTXt chunks (`nlifs:scene`, `nlifs:settings`); part files carry it to check that parts
/// belong together.
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    pub scene_toml: String,
    pub t_secs: f64,
    /// The settings as a JSON object (always with `t_secs` and `command`).
    pub settings: serde_json::Value,
}

impl Provenance {
    /// A still rendered by `nlifs render`.
    pub fn for_render(scene: &Scene, t_secs: f64, r: &RenderSettings) -> Self {
        let settings = r;
        let settings = serde_json::json!({
            "command": "render",
            "t_secs": t_secs,
            "width": settings.width,
            "height": settings.height,
            "points": settings.points,
            "seed": settings.seed,
            "mode": settings.mode.name(),
            "depth_cue": settings.depth_cue,
            "background": settings.background,
        });
        // What the command line set over the scene's own `[render]` (look, tone, density
        // estimation), so that a merge of parts resolves as the render would; named only where
        // it differs from the scene's, so that other images keep their bytes.
        let mut settings = settings;
        let own = scene.render_at(t_secs);
        let extra = settings.as_object_mut().expect("an object");
        if r.look != own.look {
            extra.insert("look".into(), r.look.map(|l| l.name()).into());
        }
        if r.shading != own.shading {
            extra.insert("shading".into(), r.shading.into());
        }
        if r.occlusion != own.occlusion {
            extra.insert("occlusion".into(), r.occlusion.into());
        }
        if r.tone() != own.tone() {
            extra.insert("tone".into(), r.tone().to_vec().into());
        }
        if r.density_estimation != own.density_estimation {
            let de = r.density_estimation.map(|d| vec![d.max_radius_px, d.min_radius_px, d.curve]);
            extra.insert("density_estimation".into(), de.into());
        }
        // Depth of field (`--aperture`, `--focus-distance`).
        if r.aperture != own.aperture {
            extra.insert("aperture".into(), r.aperture.into());
        }
        // The key light (`--shadows`, `--light-yaw-deg`, `--light-pitch-deg`).
        if r.shadows != own.shadows {
            extra.insert("shadows".into(), r.shadows.into());
        }
        if [r.light_yaw_deg, r.light_pitch_deg] != [own.light_yaw_deg, own.light_pitch_deg] {
            extra.insert("light".into(), vec![r.light_yaw_deg, r.light_pitch_deg].into());
        }
        if r.focus_distance != own.focus_distance {
            extra.insert("focus_distance".into(), r.focus_distance.into());
        }
        // Palette colour over the scene's: the mode, and the palette with its entries as f32 bit
        // patterns (exact through JSON; an image strip need not be where the merge runs).
        if r.color != own.color {
            extra.insert("color".into(), r.color.name().into());
        }
        if r.palette != own.palette {
            let palette = r.palette.as_ref().map(|p| {
                let bits: Vec<[u32; 3]> = p.samples.iter().map(|c| c.map(f32::to_bits)).collect();
                serde_json::json!({ "source": p.source, "sample_bits": bits })
            });
            extra.insert("palette".into(), palette.into());
        }
        Self { scene_toml: scene.to_toml(), t_secs, settings }
    }

    /// Any other image of `scene` at `t_secs` made by `command` (e.g. `snapshot`, the viewer's
    /// screenshot) with `settings` (a JSON object; `command` and `t_secs` are added).
    pub fn for_command(scene: &Scene, t_secs: f64, command: &str, mut settings: serde_json::Value) -> Self {
        if let Some(obj) = settings.as_object_mut() {
            obj.insert("command".into(), command.into());
            obj.insert("t_secs".into(), t_secs.into());
        }
        Self { scene_toml: scene.to_toml(), t_secs, settings }
    }

    /// Frame `frame` of a recording at time `t_secs`; `settings` describes the recorder.
    pub fn for_frame(scene: &Scene, frame: u32, t_secs: f64, mut settings: serde_json::Value) -> Self {
        if let Some(obj) = settings.as_object_mut() {
            obj.insert("command".into(), "record".into());
            obj.insert("frame".into(), frame.into());
            obj.insert("t_secs".into(), t_secs.into());
        }
        Self { scene_toml: scene.to_toml(), t_secs, settings }
    }

    /// The settings JSON as compact text.
    pub fn settings_text(&self) -> String {
        self.settings.to_string()
    }

    /// A 64-bit fingerprint of scene, time and settings (FNV-1a; stable across builds).
    pub fn fingerprint(&self) -> u64 {
        let mut h = part::Fnv::new();
        h.write(self.scene_toml.as_bytes());
        h.write(&[0]);
        h.write(self.settings_text().as_bytes());
        h.finish()
    }

    /// The scene, parsed; `origin` names where the text came from in errors.
    pub fn scene(&self, origin: &str) -> Result<Scene, OutputError> {
        Scene::parse(&self.scene_toml, origin).map_err(|e| OutputError::Scene { origin: origin.into(), source: e })
    }
}

/// A resolved image with the framebuffer's layers, as float arrays of width × height.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageLayers {
    pub color: LinearImage,
    /// Closest mode: view distance along the view axis in scene units; +inf where empty.
    pub depth: Option<Vec<f32>>,
    /// Closest mode: the index of the nearest point's function; -1 where empty.
    pub function_id: Option<Vec<f32>>,
    /// Average and density modes: points that landed on the pixel.
    pub count: Option<Vec<f32>>,
    /// Closest mode with the solid look: the shading normal in view space (x right, y up, z
    /// towards the viewer), unit length; 0 where empty ([`normals`]).
    pub normal: Option<Vec<[f32; 3]>>,
}

/// Names of the layers an EXR can hold besides `R G B A`: `Z` and `id` (closest mode), `count`
/// (average and density modes), `N` (the shading normal, closest mode with the solid look:
/// channels `N.x N.y N.z`).
pub const LAYER_NAMES: [&str; 4] = ["Z", "id", "count", "N"];

/// The layers (of [`LAYER_NAMES`]) a render in `mode` drawn with `style` has.
pub fn layer_names_of(mode: SplatMode, style: &ResolveStyle) -> Vec<&'static str> {
    match mode {
        SplatMode::Closest if style.shading > 0.0 || style.occlusion > 0.0 => vec!["Z", "id", "N"],
        SplatMode::Closest => vec!["Z", "id"],
        SplatMode::Average | SplatMode::Density => vec!["count"],
    }
}

/// The shading normals of `framebuffer` (closest mode) seen by `camera` with `style`: per pixel
/// the normal the solid look lights ([`resolve::fitted_slopes`], [`resolve::normal_and_eye`]) at
/// the key it draws (the nearest within the point radius), in view space; 0 where empty.
pub fn normals(framebuffer: &Framebuffer, camera: &OrbitCamera, style: &ResolveStyle) -> Vec<[f32; 3]> {
    let view = &framebuffer.view;
    let p = resolve::ResolveArgs::new(view, camera, style).params(view.width, view.height, false);
    let keys = &framebuffer.closest;
    let (w, h) = (view.width as i32, view.height as i32);
    let key_at = |x: i32, y: i32| if x < 0 || y < 0 || x >= w || y >= h { EMPTY } else { keys[(y * w + x) as usize] };
    let r = p.point_radius_px as i32;
    let mut out = Vec::with_capacity(keys.len());
    for y in 0..h {
        for x in 0..w {
            // The nearest key within the radius, as the resolve's fragment picks it.
            let (mut key, mut at) = (key_at(x, y), (x, y));
            for dy in -r..=r {
                for dx in -r..=r {
                    let k = key_at(x + dx, y + dy);
                    if r > 0 && dx * dx + dy * dy <= r * r && k < key {
                        (key, at) = (k, (x + dx, y + dy));
                    }
                }
            }
            if key == EMPTY {
                out.push([0.0; 3]);
            } else {
                let slopes = resolve::fitted_slopes(&p, keys, at.0, at.1, key);
                out.push(resolve::normal_and_eye(&p, at.0, at.1, slopes).0.to_array());
            }
        }
    }
    out
}

impl ImageLayers {
    /// The layers of `framebuffer` seen by `camera`, resolved with `style`: every layer the mode
    /// and look have ([`layer_names_of`]), the shading normal included with the solid look.
    pub fn of(framebuffer: &Framebuffer, camera: &OrbitCamera, style: &ResolveStyle) -> Self {
        let color = resolve::resolve_linear(framebuffer, camera, style);
        let view = &framebuffer.view;
        let (mut depth, mut function_id, mut count) = (None, None, None);
        match view.mode {
            SplatMode::Closest => {
                let range = view.far - view.near;
                depth = Some(
                    framebuffer
                        .closest
                        .iter()
                        .map(|&k| {
                            if k == EMPTY {
                                f32::INFINITY
                            } else {
                                view.near + (k >> 8) as f32 / resolve::DEPTH_SCALE * range
                            }
                        })
                        .collect(),
                );
                function_id = Some(
                    framebuffer.closest.iter().map(|&k| if k == EMPTY { -1.0 } else { (k & 0xff) as f32 }).collect(),
                );
            }
            SplatMode::Average | SplatMode::Density => {
                count = Some(framebuffer.accum.iter().map(|a| a[3] as f32).collect());
            }
        }
        let normal = layer_names_of(view.mode, style).contains(&"N").then(|| normals(framebuffer, camera, style));
        Self { color, depth, function_id, count, normal }
    }

    /// Keeps the layers named in `names` (of [`LAYER_NAMES`]) and drops the others.
    pub fn keep_only(&mut self, names: &[String]) {
        let keep = |n: &str| names.iter().any(|m| m == n);
        if !keep("Z") {
            self.depth = None;
        }
        if !keep("id") {
            self.function_id = None;
        }
        if !keep("count") {
            self.count = None;
        }
        if !keep("N") {
            self.normal = None;
        }
    }

    pub fn width(&self) -> u32 {
        self.color.width
    }

    pub fn height(&self) -> u32 {
        self.color.height
    }

    /// The temporal samples of one motion-blurred frame as one: colour and coverage averaged,
    /// depth the nearest (with its function id), counts summed. Panics on an empty list.
    pub fn average(samples: Vec<ImageLayers>) -> ImageLayers {
        let n = samples.len() as f32;
        let mut it = samples.into_iter();
        let mut out = it.next().expect("at least one sample");
        for s in it {
            for (a, b) in out.color.rgb.iter_mut().zip(&s.color.rgb) {
                for c in 0..3 {
                    a[c] += b[c];
                }
            }
            for (a, b) in out.color.alpha.iter_mut().zip(&s.color.alpha) {
                *a += b;
            }
            if let (Some(d), Some(id), Some(sd), Some(sid)) =
                (&mut out.depth, &mut out.function_id, &s.depth, &s.function_id)
            {
                for i in 0..d.len() {
                    if sd[i] < d[i] {
                        d[i] = sd[i];
                        id[i] = sid[i];
                        if let (Some(n), Some(sn)) = (&mut out.normal, &s.normal) {
                            n[i] = sn[i];
                        }
                    }
                }
            }
            if let (Some(c), Some(sc)) = (&mut out.count, &s.count) {
                for (a, b) in c.iter_mut().zip(sc) {
                    *a += b;
                }
            }
        }
        for a in &mut out.color.rgb {
            *a = a.map(|v| v / n);
        }
        for a in &mut out.color.alpha {
            *a /= n;
        }
        out
    }

    /// Channel `c` (0..4: R, G, B, A) of [`Self::rgba_premultiplied`], pixel by pixel.
    pub fn premultiplied_channel(&self, c: usize, transparent: bool) -> impl Iterator<Item = f32> + '_ {
        let bg = self.color.background;
        self.color.rgb.iter().zip(&self.color.alpha).map(move |(rgb, &a)| match (c, transparent) {
            (3, true) => a,
            (3, false) => 1.0,
            // rgb = premultiplied + bg · (1 − a): the resolve lays the colour over the background.
            (c, true) => (rgb[c] - bg[c] * (1.0 - a)).max(0.0),
            (c, false) => rgb[c],
        })
    }

    /// Linear RGBA per pixel: opaque (the colour over the background, alpha 1), or with
    /// `transparent` premultiplied by the coverage (the background taken out).
    pub fn rgba_premultiplied(&self, transparent: bool) -> Vec<[f32; 4]> {
        let mut channels = [0, 1, 2, 3].map(|c| self.premultiplied_channel(c, transparent));
        (0..self.color.rgb.len()).map(|_| channels.each_mut().map(|ch| ch.next().unwrap_or(0.0))).collect()
    }

    /// Linear RGBA per pixel with straight (not premultiplied) colour, as PNG stores it.
    pub fn rgba_straight(&self, transparent: bool) -> Vec<[f32; 4]> {
        self.rgba_premultiplied(transparent)
            .into_iter()
            .map(|[r, g, b, a]| if a > 0.0 && a < 1.0 { [r / a, g / a, b / a, a] } else { [r, g, b, a] })
            .collect()
    }
}

/// Problems writing or reading outputs. All but `Io` are the user's input.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("output {path} must end in .{expected}")]
    Extension { path: String, expected: &'static str },
    #[error("cannot write {path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("cannot read {path}: {source}")]
    Read { path: String, source: std::io::Error },
    #[error("{path}: {message}")]
    Invalid { path: String, message: String },
    #[error(transparent)]
    Load(#[from] crate::scene::LoadError),
    #[error("the scene embedded in {origin} does not load: {source}")]
    Scene { origin: String, source: crate::scene::SceneError },
}

impl OutputError {
    /// Whether the error is the user's input (a wrong name, a bad file given to read) rather
    /// than a failure of the machine.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, OutputError::Io { .. })
    }
}

/// Writes `layers` to `path` as `options` say, atomically; PNGs carry `provenance`.
pub fn write_image(
    path: &Path,
    layers: &ImageLayers,
    options: &OutputOptions,
    provenance: Option<&Provenance>,
) -> Result<(), OutputError> {
    match options.format {
        Format::Png | Format::Png16 => png::write_layers(path, layers, options, provenance),
        Format::Exr => exr::write(path, layers, options),
    }
}
