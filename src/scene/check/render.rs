//! Checks `[render]`: the image size, points and seed, the splat mode, background, depth cue and
//! look, the tone controls (`spec::TONE_FIELDS`), the density scale, density estimation, the
//! key light, the lens and the colour fields.

use toml::Spanned;

use crate::scene::file::RenderToml;
use crate::scene::spec::{BlendSpace, DensityScale, Look, MAX_POINTS, RenderSettings, SplatMode, TONE_FIELDS};

use super::{Checker, Res};

impl Checker<'_> {
    pub(super) fn render(&self, r: &RenderToml) -> Res<RenderSettings> {
        let mut out = RenderSettings::default();
        let int = |v: &Spanned<i64>, field: &str, lo: i64, hi: i64| -> Res<i64> {
            let x = *v.get_ref();
            if x < lo || x > hi {
                return Err(self.err(v.span(), field, format!("must lie in {lo}..={hi}, found {x}")));
            }
            Ok(x)
        };
        if let Some(v) = &r.width {
            out.width = int(v, "render.width", 1, 16384)? as u32;
        }
        if let Some(v) = &r.height {
            out.height = int(v, "render.height", 1, 16384)? as u32;
        }
        if let Some(v) = &r.points {
            out.points = int(v, "render.points", 1, MAX_POINTS as i64)? as u64;
        }
        if let Some(v) = &r.seed {
            out.seed = int(v, "render.seed", 0, u32::MAX as i64)? as u32;
        }
        if let Some(v) = &r.mode {
            out.mode =
                self.named(v, "render.mode", SplatMode::parse, "a mode", "\"closest\", \"average\" or \"density\"")?;
        }
        if let Some(b) = &r.background {
            out.background = self.color(b, "render.background")?;
        }
        if let Some(d) = &r.depth_cue {
            let v = self.finite(d, "render.depth_cue")?;
            if !(0.0..=1.0).contains(&v) {
                return Err(self.err(d.span(), "render.depth_cue", "must lie in 0..1"));
            }
            out.depth_cue = v as f32;
        }
        if let Some(l) = &r.look {
            out.look = Some(Look::parse(l.get_ref()).ok_or_else(|| {
                self.err(
                    l.span(),
                    "render.look",
                    format!("`{}` is not a look; use \"solid\" or \"paper\"", l.get_ref()),
                )
            })?);
        }
        for (value, field, slot) in
            [(&r.shading, "render.shading", &mut out.shading), (&r.occlusion, "render.occlusion", &mut out.occlusion)]
        {
            if let Some(s) = value {
                let v = self.finite(s, field)?;
                if !(0.0..=1.0).contains(&v) {
                    return Err(self.err(s.span(), field, "must lie in 0..1"));
                }
                *slot = Some(v as f32);
            }
        }
        // The tone controls.
        for ((value, (name, lo, hi)), slot) in r.tone().into_iter().zip(TONE_FIELDS).zip(out.tone_mut()) {
            if let Some(v) = value {
                *slot = self.in_range(v, &format!("render.{name}"), lo, hi)? as f32;
            }
        }
        if let Some(v) = &r.density_scale {
            out.density_scale = self.named(
                v,
                "render.density_scale",
                DensityScale::parse,
                "a density scale",
                "\"relative\" or \"absolute\"",
            )?;
        }
        if let Some(v) = &r.blend_space {
            out.blend_space =
                self.named(v, "render.blend_space", BlendSpace::parse, "a blend space", "\"linear\" or \"srgb\"")?;
        }
        if let Some(v) = &r.palette_mode {
            out.palette_mode = self.named(
                v,
                "render.palette_mode",
                crate::flame::PaletteMode::parse,
                "a palette mode",
                "\"step\" or \"linear\"",
            )?;
        }
        out.density_estimation = self.density_estimation(r)?;
        out.filter = self.filter(r)?;
        // The key light.
        let [shadows, yaw, pitch] = r.light();
        let [(_, lo, hi), yaw_field, pitch_field] = crate::scene::spec::LIGHT_FIELDS;
        if let Some(v) = shadows {
            out.shadows = Some(self.in_range(v, "render.shadows", lo, hi)? as f32);
        }
        for ((value, (name, lo, hi)), slot) in
            [yaw, pitch].into_iter().zip([yaw_field, pitch_field]).zip(out.light_mut())
        {
            if let Some(v) = value {
                *slot = self.in_range(v, &format!("render.{name}"), lo, hi)? as f32;
            }
        }
        let (aperture, focus_distance) = self.lens(&r.aperture, &r.focus_distance, "render")?;
        out.aperture = aperture.unwrap_or(0.0);
        out.focus_distance = focus_distance;
        self.color_fields(r, &mut out)?;
        Ok(out)
    }
}
