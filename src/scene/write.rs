//! Writing a scene back as TOML: every setting explicit, numbers in Rust's shortest round-trip
//! form and colours as hex when that is exact, so that reading the text back gives an equal
//! scene. This is the text of a scene without a file (and of recovery files and PNG metadata);
//! a save over the scene's own file edits that file instead (`rewrite.rs`, which compares two
//! such full texts to find what changed).

use std::path::Path;

use glam::{DMat3, DVec3};

use crate::camera::Projection;
use crate::color;
use crate::model::builder::Step;
use crate::scene::Scene;
use crate::scene::file::FORMAT_VERSION;
use crate::scene::spec::{
    BlendSpace, CameraSpec, ColorMode, DensityScale, FlameDef, FunctionDef, LIGHT_FIELDS, RenderSettings, TONE_FIELDS,
};
use crate::scene::timeline::RenderKey;

/// TOML text of a number that reads back to the same f64 (Rust's shortest round-trip form).
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn nums(xs: &[f64]) -> String {
    format!("[{}]", xs.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", "))
}

fn vec_dim(v: DVec3, dim: usize) -> String {
    nums(&v.to_array()[..dim])
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A linear colour as "#rrggbb" when that reads back exactly, else as sRGB [r, g, b].
fn color_text(c: [f32; 3]) -> String {
    let srgb = c.map(color::linear_to_srgb);
    // The nearest byte; hex is written only when it decodes back to `c` exactly.
    let bytes = srgb.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8);
    if bytes.map(color::srgb8_to_linear) == c {
        format!("\"{}\"", color::hex_text(bytes))
    } else {
        format!("[{}]", srgb.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(", "))
    }
}

fn matrix_text(m: &DMat3, dim: usize) -> String {
    let rows: Vec<String> = (0..dim).map(|r| nums(&(0..dim).map(|c| m.col(c)[r]).collect::<Vec<_>>())).collect();
    format!("[{}]", rows.join(", "))
}

fn step_text(s: &Step, dim: usize) -> String {
    let v = |p: DVec3| vec_dim(p, dim);
    match s {
        Step::Scale { by, center } => format!("{{ op = \"scale\", by = {}, center = {} }}", v(*by), v(*center)),
        Step::Rotate { axis, degrees, center } => {
            format!(
                "{{ op = \"rotate\", axis = \"{}\", degrees = {}, center = {} }}",
                axis.name(),
                num(*degrees),
                v(*center)
            )
        }
        Step::Translate { by } => format!("{{ op = \"translate\", by = {} }}", v(*by)),
        Step::Taper { axis, amount, range, center } => {
            format!(
                "{{ op = \"taper\", axis = \"{}\", amount = {}, range = {}, center = {} }}",
                axis.name(),
                num(*amount),
                nums(range),
                v(*center)
            )
        }
        Step::Twist { axis, along, degrees, range, center } => format!(
            "{{ op = \"twist\", axis = \"{}\", along = \"{}\", degrees = {}, range = {}, center = {} }}",
            axis.name(),
            along.name(),
            num(*degrees),
            nums(range),
            v(*center)
        ),
        Step::Bend { axis, toward, degrees, range, center } => format!(
            "{{ op = \"bend\", axis = \"{}\", toward = \"{}\", degrees = {}, range = {}, center = {} }}",
            axis.name(),
            toward.name(),
            num(*degrees),
            nums(range),
            v(*center)
        ),
        Step::Affine { matrix, offset } => {
            format!("{{ op = \"affine\", matrix = {}, offset = {} }}", matrix_text(matrix, dim), v(*offset))
        }
    }
}

/// The number-holding fields of a definition (what a key may override), one per line.
fn def_fields(def: &FunctionDef, dim: usize) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    match def {
        FunctionDef::Grid { points } => {
            out += "points = [\n";
            for p in points {
                let _ = writeln!(out, "  {},", vec_dim(*p, dim));
            }
            out += "]\n";
        }
        FunctionDef::Builder { builder, .. } => {
            out += "steps = [\n";
            for s in &builder.steps {
                let _ = writeln!(out, "  {},", step_text(s, dim));
            }
            out += "]\n";
        }
        FunctionDef::Affine(a) => {
            let _ = writeln!(out, "matrix = {}", matrix_text(&a.matrix, dim));
            let _ = writeln!(out, "offset = {}", vec_dim(a.offset, dim));
        }
        FunctionDef::Julia(j) => {
            let _ = writeln!(out, "c = {}", nums(&j.c));
        }
        FunctionDef::Flame(f) => {
            let _ = writeln!(out, "coefs = {}", nums(&f.coefs));
            if let Some(post) = &f.post {
                let _ = writeln!(out, "post = {}", nums(post));
            }
            if let Some(c) = &f.variation_coefs {
                let _ = writeln!(out, "variation_coefs = {}", nums(c));
            }
            let weights: Vec<String> =
                f.variations.iter().map(|t| format!("{} = {}", t.variation.name(), num(t.weight))).collect();
            let _ = writeln!(out, "variations = {{ {} }}", weights.join(", "));
            let params: Vec<String> = f
                .variations
                .iter()
                .flat_map(|t| {
                    t.variation.info().params.iter().zip(&t.params).map(|((n, _), v)| format!("{n} = {}", num(*v)))
                })
                .collect();
            if !params.is_empty() {
                let _ = writeln!(out, "params = {{ {} }}", params.join(", "));
            }
            let _ = writeln!(out, "color_speed = {}", num(f.color_speed));
            if f.opacity != FlameDef::DEFAULT_OPACITY {
                let _ = writeln!(out, "opacity = {}", num(f.opacity));
            }
        }
    }
    out
}

fn camera_fields(c: &CameraSpec) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    if let Some(t) = c.target {
        let _ = writeln!(out, "target = {}", nums(&t.to_array()));
    }
    for (name, v) in
        [("yaw_deg", c.yaw_deg), ("pitch_deg", c.pitch_deg), ("distance", c.distance), ("fov_y_deg", c.fov_y_deg)]
    {
        if let Some(v) = v {
            let _ = writeln!(out, "{name} = {}", num(v));
        }
    }
    if let Some(p) = c.projection {
        let _ =
            writeln!(out, "projection = \"{}\"", if p == Projection::Perspective { "perspective" } else { "parallel" });
    }
    out
}

impl Scene {
    /// Writes [`Scene::to_toml`] to `path` atomically.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        self.save_over(path, None).map(drop)
    }

    /// Writes the scene to `path` atomically: as `original` (the text of the file the scene
    /// was read from) edited where the scene differs from it ([`Scene::to_toml_over`]), or in
    /// full without one. Returns the text written. A palette image the scene names that is not
    /// on disk next to it (the palette of a flame imported in memory) is written there, as the
    /// strip of its entries, so that the saved scene reads back with its palette.
    pub fn save_over(&self, path: &Path, original: Option<&str>) -> std::io::Result<String> {
        let text = match original {
            Some(original) => self.to_toml_over(original),
            None => self.to_toml(),
        };
        if let Some(palette) = &self.render.palette
            && let Some(image) = palette.image_path(path.parent().unwrap_or(Path::new("")))
            && !image.exists()
        {
            crate::io::save_png(&image, &palette.strip_image())?;
        }
        crate::io::write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
        Ok(text)
    }

    /// The scene as `original` (a scene file's text) edited to hold it: the file's comments,
    /// layout, order and number spellings stay, only what differs changes, and defaults the
    /// file leaves unset stay unset (`rewrite.rs`). Reading the text back gives an equal scene;
    /// where an edit cannot give that (text that is not a scene), [`Scene::to_toml`].
    pub fn to_toml_over(&self, original: &str) -> String {
        super::rewrite::edit_over(self, original).unwrap_or_else(|| self.to_toml())
    }

    /// The scene as format-version-1 TOML, with every setting explicit; reading it back gives
    /// an equal scene (colours are written as hex when that is exact, else as sRGB floats).
    pub fn to_toml(&self) -> String {
        use std::fmt::Write;
        let dim = self.domain.dimension();
        let mut out = String::new();
        let _ = writeln!(out, "version = {FORMAT_VERSION}");
        let _ = writeln!(out, "name = {}", toml_string(&self.name));
        if !self.description.is_empty() {
            let _ = writeln!(out, "description = {}", toml_string(&self.description));
        }
        let _ = writeln!(out, "probabilities = \"{}\"", self.probability_mode.name());
        out += "\n[grid]\n";
        for (a, name) in self.domain.axes.iter().zip(["x", "y", "z"]).take(dim) {
            let _ = writeln!(out, "{name} = {}", nums(a));
        }
        for f in &self.functions {
            out += "\n[[function]]\n";
            let _ = writeln!(out, "name = {}", toml_string(&f.name));
            let _ = writeln!(out, "kind = \"{}\"", f.def.kind());
            let _ = writeln!(out, "color = {}", color_text(f.color));
            if let Some(p) = f.probability {
                let _ = writeln!(out, "probability = {}", num(p));
            }
            if !f.enabled {
                out += "enabled = false\n";
            }
            if let Some(c) = f.palette_index {
                let _ = writeln!(out, "palette_index = {}", num(c));
            }
            if !f.xaos.is_empty() {
                let _ = writeln!(out, "xaos = {}", nums(&f.xaos));
            }
            match &f.def {
                FunctionDef::Builder { resolution, .. } => {
                    let _ = writeln!(
                        out,
                        "resolution = [{}]",
                        resolution[..dim].iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
                    );
                }
                FunctionDef::Julia(j) => {
                    let _ = writeln!(out, "sign = {}", num(j.sign));
                }
                _ => {}
            }
            out += &def_fields(&f.def, dim);
        }
        if let Some(f) = &self.final_xform {
            out += "\n[final]\n";
            let _ = writeln!(out, "palette_index = {}", num(f.palette_index));
            out += &def_fields(&FunctionDef::Flame(f.def.clone()), dim);
        }
        let camera = camera_fields(&self.camera);
        if !camera.is_empty() {
            out += "\n[camera]\n";
            out += &camera;
        }
        let r = &self.render;
        out += "\n[render]\n";
        let _ = writeln!(out, "width = {}\nheight = {}\npoints = {}\nseed = {}", r.width, r.height, r.points, r.seed);
        let _ = writeln!(
            out,
            "mode = \"{}\"\nbackground = {}\ndepth_cue = {:?}",
            r.mode.name(),
            color_text(r.background),
            r.depth_cue
        );
        // Written only when set, so that a scene without them reads back unchanged.
        if let Some(look) = r.look {
            let _ = writeln!(out, "look = \"{}\"", look.name());
        }
        if let Some(v) = r.shading {
            let _ = writeln!(out, "shading = {v:?}");
        }
        if let Some(v) = r.occlusion {
            let _ = writeln!(out, "occlusion = {v:?}");
        }
        // The tone controls, written where they differ from the default.
        for ((name, _, _), (v, default)) in
            TONE_FIELDS.into_iter().zip(r.tone().into_iter().zip(RenderSettings::default().tone()))
        {
            if v != default {
                let _ = writeln!(out, "{name} = {v:?}");
            }
        }
        // The key light: shadows when set, the direction where it differs from the default.
        if let Some(v) = r.shadows {
            let _ = writeln!(out, "shadows = {v:?}");
        }
        let default = RenderSettings::default();
        for ((name, _, _), (v, d)) in LIGHT_FIELDS[1..]
            .iter()
            .zip([(r.light_yaw_deg, default.light_yaw_deg), (r.light_pitch_deg, default.light_pitch_deg)])
        {
            if v != d {
                let _ = writeln!(out, "{name} = {v:?}");
            }
        }
        if r.density_scale != DensityScale::Relative {
            let _ = writeln!(out, "density_scale = \"{}\"", r.density_scale.name());
        }
        if r.palette_mode != crate::flame::PaletteMode::Step {
            let _ = writeln!(out, "palette_mode = \"{}\"", r.palette_mode.name());
        }
        if r.blend_space != BlendSpace::Linear {
            let _ = writeln!(out, "blend_space = \"{}\"", r.blend_space.name());
        }
        if let Some(de) = r.density_estimation {
            let _ = writeln!(
                out,
                "estimator_radius = {:?}\nestimator_minimum = {:?}\nestimator_curve = {:?}",
                de.max_radius_px, de.min_radius_px, de.curve
            );
        }
        if let Some(f) = r.filter {
            let _ = writeln!(out, "filter = {:?}", f.radius_px);
            if f.shape != crate::flame::FilterShape::Gaussian {
                let _ = writeln!(out, "filter_shape = \"{}\"", f.shape.name());
            }
        }
        // Depth of field, written only when on or set.
        if r.aperture != 0.0 {
            let _ = writeln!(out, "aperture = {:?}", r.aperture);
        }
        if let Some(f) = r.focus_distance {
            let _ = writeln!(out, "focus_distance = {f:?}");
        }
        // Palette colour, written where set.
        if r.color != ColorMode::Function {
            let _ = writeln!(out, "color = \"{}\"", r.color.name());
        }
        if let Some(p) = &r.palette {
            let _ = writeln!(out, "palette = {}", toml_string(&p.source));
        }
        if let Some(tl) = &self.timeline {
            out += "\n[timeline]\n";
            let _ = writeln!(out, "loop = \"{}\"\nduration_secs = {}", tl.loop_mode.name(), num(tl.duration_secs));
            for k in &tl.keys {
                out += "\n[[key]]\n";
                let _ = writeln!(
                    out,
                    "t_secs = {}\ninterpolation = \"{}\"\nease = \"{}\"",
                    num(k.t_secs),
                    k.interpolation.name(),
                    k.ease.name()
                );
                for fk in &k.functions {
                    out += "[[key.function]]\n";
                    let _ = writeln!(out, "name = {}", toml_string(&self.functions[fk.function].name));
                    out += &def_fields(&fk.def, dim);
                }
                let camera = camera_fields(&k.camera);
                if !camera.is_empty() {
                    out += "[key.camera]\n";
                    out += &camera;
                }
                let kr = &k.render;
                if kr != &RenderKey::default() {
                    out += "[key.render]\n";
                    if let Some(p) = kr.points {
                        let _ = writeln!(out, "points = {p}");
                    }
                    if let Some(b) = kr.background {
                        let _ = writeln!(out, "background = {}", color_text(b));
                    }
                    if let Some(d) = kr.depth_cue {
                        let _ = writeln!(out, "depth_cue = {d:?}");
                    }
                    for ((name, _, _), v) in TONE_FIELDS.into_iter().zip(kr.tone.iter()) {
                        if let Some(v) = v {
                            let _ = writeln!(out, "{name} = {v:?}");
                        }
                    }
                    for ((name, _, _), v) in LIGHT_FIELDS.into_iter().zip(kr.light.iter()) {
                        if let Some(v) = v {
                            let _ = writeln!(out, "{name} = {v:?}");
                        }
                    }
                    for (name, v) in [("aperture", kr.aperture), ("focus_distance", kr.focus_distance)] {
                        if let Some(v) = v {
                            let _ = writeln!(out, "{name} = {v:?}");
                        }
                    }
                }
            }
        }
        out
    }
}
