//! The resolve on the CPU: the twin of `shaders/resolve.wgsl` (host side `src/gpu/resolve.rs`),
//! turning a splat's accumulation (a [`Framebuffer`]) into an image. Same constants, same
//! parameters ([`ResolveParams`], the one mirror of the WGSL struct, shared by both sides), same
//! loop shape: [`resolve_fragment`] is the fragment stage `resolve` for one pixel, [`max_count`]
//! the density mode's reduction, and [`resolve_image`] runs the fragment over every pixel and
//! writes what an 8-bit unorm target stores. Keep in sync with `shaders/resolve.wgsl`.
//! The unit tests are in `resolve/tests.rs`.
//!
//! Closest keys become depth-cued function colours, widened to a point radius (each pixel shows
//! the nearest key within it); sums become average colours, which density mode scales by
//! log(1 + count) / log(1 + max count). With [`ResolveStyle::PAPER`] (the default: no shading,
//! no occlusion, radius 0) the image is the plain resolve that `nlifs render` has always
//! written.
//!
//! The solid look ([`ResolveStyle::SOLID`], closest mode) makes 3D point sets read as solids,
//! from the depth buffer alone:
//! - Normals: a plane fitted by weighted least squares to the depths of the 5×5 window around
//!   the key ([`fitted_slopes`]). Empty pixels do not count and a neighbour's weight falls with
//!   its slope from the centre, so holes in a sparse cloud and the far side of a silhouette
//!   neither tilt nor flip the normal; a small ridge term pulls what the window cannot
//!   determine (a lone pixel) towards the view-facing normal. Neighbouring pixels share most of
//!   their window, so the normal changes smoothly and a converging cloud does not sparkle.
//! - Lights fixed to the camera ([`lit`]): ambient, a key light up-left-front (Lambert plus a
//!   Blinn-Phong highlight) and a weaker fill light low right. `shading` blends the flat colour
//!   (0) into the lit one (1).
//! - Ambient occlusion: 16 samples in a fixed pattern (2 rings × 8 directions, no noise, so no
//!   blur is needed) measure how far the neighbourhood rises above the fitted plane; a crease
//!   darkens, a plane or a convex bump does not. `occlusion` scales how much light it takes.
//!
//! - Cast shadows: the points splatted again from the key light into a shadow map, each visible
//!   pixel tested against it with percentage-closer filtering (`resolve/shadow.rs`); the shadow
//!   takes away the key light's diffuse and highlight. `shadows` scales it.
//!
//! The depth cue applies after the light, as in the paper's look.
//!
//! The average and density modes take flam3's tone controls (exposure, gamma with a linear
//! threshold, vibrancy, highlight power; [`Tone`], formula in `resolve/tone.rs`); their defaults
//! leave the image as it was.

use glam::Vec3;
use rayon::prelude::*;

use crate::camera::{OrbitCamera, Projection};
use crate::color::linear_to_srgb;
use crate::scene::spec::{BlendSpace, DensityScale, Look, RenderSettings, SplatMode};
use crate::splat::{Framebuffer, ShadowView, SplatView};

mod light_rows;
mod linear;
pub mod shadow;
mod solid;
mod tone;
pub use light_rows::LightRows;
pub use linear::{LinearImage, resolve_linear};
pub use shadow::{KEY_LIGHT_PITCH_DEG, KEY_LIGHT_YAW_DEG, SOLID_SHADOWS};
pub use solid::{fitted_slopes, lit, lit_by, normal_and_eye, occlusion};
pub use tone::{HIGHLIGHT_OFF, Tone, ToneUniforms, gamma_ramp, toned};

/// The closest mode's number in `ResolveParams::mode` ([`SplatMode::index`]).
pub const MODE_CLOSEST: u32 = 0;
/// The average mode's number in `ResolveParams::mode`.
pub const MODE_AVERAGE: u32 = 1;
/// The empty closest-point key (`EMPTY` in the shader; the splat's [`crate::splat::EMPTY`]).
pub const EMPTY: u32 = u32::MAX;
/// Largest key depth: depth fraction t = (key >> 8) / DEPTH_SCALE (24 bits of depth).
pub const DEPTH_SCALE: f32 = 16_777_215.0;
/// Colour sums are of channels scaled to 0..=COLOR_SCALE ([`crate::splat::COLOR_SCALE`]).
pub const COLOR_SCALE: f32 = 255.0;
/// Largest point radius the resolve draws: the closest mode's neighbourhood is (2r + 1)² key
/// reads per pixel, which a software rasterizer pays in full.
pub const MAX_POINT_RADIUS_PX: u32 = 8;

// The solid look (`light`). Lights are in view space (x right, y up, z towards the viewer), so
// they move with the camera: the key light up, left and in front, the fill light low right.
/// Direction towards the key light (unit).
pub const KEY_LIGHT: [f32; 3] = [-0.4511292, 0.5513802, 0.7017566];
/// Direction towards the fill light (unit).
pub const FILL_LIGHT: [f32; 3] = [0.6115766, -0.2038589, 0.7644708];
/// Light that reaches every normal.
pub const AMBIENT: f32 = 0.15;
/// The key light's diffuse strength.
pub const KEY: f32 = 0.9;
/// The fill light's diffuse strength.
pub const FILL: f32 = 0.25;
/// The key light's Blinn-Phong highlight strength (white, exponent 32).
pub const SPECULAR: f32 = 0.2;
/// The normal's plane fit reads the (2r + 1)² window of this radius (the largest the resolve
/// takes; the live view fits in a window of [`NAVIGATING_NORMAL_RADIUS_PX`] while navigating).
pub const NORMAL_RADIUS_PX: u32 = 2;
/// The plane fit's radius while the live view navigates (a dragged camera, a playing timeline):
/// 9 keys a pixel instead of 25, the normals a little rougher, the lit frame cheaper.
pub const NAVIGATING_NORMAL_RADIUS_PX: u32 = 1;
/// The plane fit weighs a neighbour half at this slope from the centre (tan 63°).
pub const SLOPE_SCALE: f32 = 2.0;
/// Ridge of the plane fit, in the units of one full-weight neighbour one pixel away.
pub const RIDGE: f32 = 1.0;
/// Slopes beyond this (tan 83°) are clamped: the normal barely turns past it.
pub const SLOPE_MAX: f32 = 8.0;
/// Occlusion samples: rings of directions, radii 3 and 6.7 steps (the second ring turned by
/// half a direction, so that the 16 samples point in 16 directions).
pub const OCCLUSION_RINGS: i32 = 2;
pub const OCCLUSION_DIRECTIONS: i32 = 8;
/// One over the lengths of the base offsets (3, 0), (2, 2) and (6, 3).
pub const INV_LENGTH_3_0: f32 = 0.33333334;
pub const INV_LENGTH_2_2: f32 = 0.35355338;
pub const INV_LENGTH_6_3: f32 = 0.1490712;
/// Elevation (tangent) past which a sample stops occluding: something that far in front is
/// another object, not the wall of a crease.
pub const OCCLUSION_FALLOFF: f32 = 3.0;
pub const INV_OCCLUSION_FALLOFF: f32 = 1.0 / OCCLUSION_FALLOFF;
/// Elevation (tangent, about 6°) that a sample must exceed to occlude: the fitted plane is
/// flattened a little by the ridge and depths are quantized, so a plane's own samples may sit
/// slightly above it.
pub const OCCLUSION_BIAS: f32 = 0.1;
/// The mean occlusion of the samples times this, at most 1, is what `occlusion` 1 takes away.
pub const OCCLUSION_GAIN: f32 = 2.0;
/// Occlusion strength of the solid look.
pub const SOLID_OCCLUSION: f32 = 0.6;
/// The look of 3D scenes that do not name one, in `render`, `record` and the viewer (2D scenes
/// stay paper; `look = "paper"` or `--look paper` gives the paper's depth-cued flat colour).
/// The viewer keeps ≥ 20 fps with it on lavapipe (docs/performance.md, "The solid look's cost").
pub const DEFAULT_LOOK_3D: Look = Look::Solid;

const _: () = assert!(EMPTY == crate::splat::EMPTY);
const _: () = assert!(DEPTH_SCALE == ((1u32 << crate::splat::DEPTH_BITS) - 1) as f32);
const _: () = assert!(COLOR_SCALE == crate::splat::COLOR_SCALE);

/// Mirrors `struct ResolveParams` in `shaders/resolve.wgsl`: keep in sync.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ResolveParams {
    /// rgb: linear background; w: depth cue.
    pub background: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub mode: u32,
    /// 1: the fragment writes sRGB-encoded values (unorm target); 0: linear (sRGB target).
    pub encode_srgb: u32,
    /// 0: flat colours; 1: fully lit (closest mode).
    pub shading: f32,
    /// View-space depth range of the keys, for normals from depth.
    pub near: f32,
    pub far: f32,
    /// View-space size of a pixel at unit distance (perspective) or absolute (parallel).
    pub pixel_size: f32,
    pub perspective: u32,
    /// Closest mode: each pixel shows the nearest key within this radius.
    pub point_radius_px: u32,
    /// Target pixel of the accumulation's pixel (0, 0) (the GPU draw's viewport origin).
    pub origin_x: u32,
    pub origin_y: u32,
    /// Ambient occlusion strength (closest mode): 0 none.
    pub occlusion: f32,
    /// Pixels per unit of the occlusion samples' offsets.
    pub occlusion_step_px: u32,
    /// The tone map (average and density modes, [`ToneUniforms`]): 2^exposure, 1 / gamma, the
    /// gamma's linear threshold, vibrancy and highlight power.
    pub brightness: f32,
    pub inv_gamma: f32,
    pub gamma_threshold: f32,
    pub vibrancy: f32,
    pub highlight_power: f32,
    // Shadows (`resolve/shadow.rs`).
    /// Shadow strength (closest mode): 0 none (the shadow map is not read).
    pub shadows: f32,
    /// xyz: direction towards the key light (view space, unit); w: 0.
    pub key_light: [f32; 4],
    /// Texel x, texel y and depth fraction of the shadow map from view space (glam's column
    /// order, WGSL's `mat4x4`).
    pub shadow_from_view: [[f32; 4]; 4],
    /// The shadow map is this many texels square.
    pub shadow_side_px: u32,
    /// World size of a texel, and one over the world length of the map's depth range.
    pub shadow_texel_world: f32,
    pub shadow_inv_depth_world: f32,
    /// The normal's plane fit reads the (2r + 1)² window of this radius, 1 ..= [`NORMAL_RADIUS_PX`].
    pub normal_radius_px: u32,
    /// Density mode: s of the absolute density ln(1 + count · s); 0: relative to the densest
    /// pixel ([`ResolveArgs::count_scale`]).
    pub count_scale: f32,
    /// flam3's spatial filter (average and density modes, [`filter`]): the taps along each
    /// axis (odd; 0: off; the pipeline constant `FILTER_TAPS` holds the same value) and their
    /// weights.
    pub filter_taps: u32,
    /// 1: the colours and background are sRGB-encoded values ([`Tone::blend`] `Srgb`), which
    /// the output takes as they are (unorm target) or decoded (sRGB target, linear outputs); 0:
    /// linear.
    pub blend_srgb: u32,
    pub pad: u32,
    pub filter_weights: filter::Weights,
}
const _: () = assert!(std::mem::size_of::<ResolveParams>() == 272);

/// How the resolve draws, beyond the splat's own settings (mode, background, depth cue). The
/// default is the paper look: flat colours, one pixel per key, the bytes `nlifs render` has
/// always written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolveStyle {
    /// Lighting strength in [0, 1] (closest mode): 0 flat, 1 fully lit.
    pub shading: f32,
    /// Ambient occlusion strength in [0, 1] (closest mode): 0 none.
    pub occlusion: f32,
    /// Closest mode: each pixel shows the nearest key within this radius (at most
    /// [`MAX_POINT_RADIUS_PX`]).
    pub point_radius_px: u32,
    /// The tone map of the average and density modes.
    pub tone: Tone,
    // Shadows (`resolve/shadow.rs`).
    /// Cast shadow strength in [0, 1] (closest mode): 0 none.
    pub shadows: f32,
    /// The key light's direction relative to the camera ([`shadow::key_light`]).
    pub light_yaw_deg: f32,
    pub light_pitch_deg: f32,
}

impl Default for ResolveStyle {
    fn default() -> Self {
        Self::PAPER
    }
}

impl ResolveStyle {
    /// The paper's look: depth-cued flat colour.
    pub const PAPER: Self = Self {
        shading: 0.0,
        occlusion: 0.0,
        point_radius_px: 0,
        tone: Tone::NEUTRAL,
        shadows: 0.0,
        light_yaw_deg: KEY_LIGHT_YAW_DEG,
        light_pitch_deg: KEY_LIGHT_PITCH_DEG,
    };
    /// The solid look: lit, with ambient occlusion and cast shadows.
    pub const SOLID: Self = Self {
        shading: 1.0,
        occlusion: SOLID_OCCLUSION,
        point_radius_px: 0,
        tone: Tone::NEUTRAL,
        shadows: SOLID_SHADOWS,
        light_yaw_deg: KEY_LIGHT_YAW_DEG,
        light_pitch_deg: KEY_LIGHT_PITCH_DEG,
    };

    pub fn of_look(look: Look) -> Self {
        match look {
            Look::Paper => Self::PAPER,
            Look::Solid => Self::SOLID,
        }
    }

    /// The style a scene's render settings ask for, for a scene of `dimension` (2 or 3): its
    /// look (unnamed: [`DEFAULT_LOOK_3D`] in 3D, paper in 2D, where depth is flat), with the
    /// scene's `shading` and `occlusion` over the look's, and the scene's tone.
    pub fn of(settings: &RenderSettings, dimension: usize) -> Self {
        let default_look = if dimension >= 3 { DEFAULT_LOOK_3D } else { Look::Paper };
        let look = Self::of_look(settings.look.unwrap_or(default_look));
        Self {
            shading: settings.shading.unwrap_or(look.shading),
            occlusion: settings.occlusion.unwrap_or(look.occlusion),
            point_radius_px: look.point_radius_px,
            tone: Tone::of(settings),
            shadows: settings.shadows.unwrap_or(look.shadows),
            light_yaw_deg: settings.light_yaw_deg,
            light_pitch_deg: settings.light_pitch_deg,
        }
    }
}

/// What the resolve needs besides the accumulation: the splat's colour settings, the style and
/// the view's geometry (for normals from depth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolveArgs {
    pub mode: SplatMode,
    pub background: [f32; 3],
    pub depth_cue: f32,
    /// 0: flat colours; 1: fully lit (closest mode only).
    pub shading: f32,
    /// Ambient occlusion strength in [0, 1] (closest mode only).
    pub occlusion: f32,
    /// Closest mode: each pixel shows the nearest key within this radius.
    pub point_radius_px: u32,
    pub near: f32,
    pub far: f32,
    /// View-space size of a pixel at unit distance (perspective) or absolute (parallel).
    pub pixel_size: f32,
    pub perspective: bool,
    /// Where in the target the accumulation's pixel (0, 0) goes: the GPU draw covers the
    /// rectangle of the accumulation's size there (the rest of the target is cleared to black).
    /// The CPU resolve writes the accumulation's rectangle only and takes (0, 0).
    pub origin_px: [u32; 2],
    /// The tone map (average and density modes only).
    pub tone: Tone,
    // Shadows (`resolve/shadow.rs`).
    /// Cast shadow strength in [0, 1] (closest mode, with a shadow map only).
    pub shadows: f32,
    /// Direction towards the key light (view space, unit).
    pub key_light: [f32; 3],
    /// The splat's shadow map, if it has one.
    pub shadow: Option<ShadowView>,
    /// The radius of the normals' plane fit (clamped to 1 ..= [`NORMAL_RADIUS_PX`]).
    pub normal_radius_px: u32,
    // The absolute density scale (density mode, `Tone::density_scale`).
    /// The area of a pixel in square scene units at the camera's target.
    pub pixel_area: f32,
    /// The points the chaos game drew into the accumulation (those outside the view counted).
    pub points_drawn: u64,
}

/// The area of one of `height_px` rows' square pixels in square scene units at the camera's
/// target (where a parallel projection's pixels all are).
pub fn pixel_area(camera: &OrbitCamera, height_px: u32) -> f32 {
    let side = 2.0 * camera.half_height_at_target() / height_px.max(1) as f32;
    side * side
}

/// View-space size of one of `height_px` pixel rows at unit distance (perspective) or
/// absolute (parallel), and whether the projection is perspective.
pub fn pixel_footprint(camera: &OrbitCamera, height_px: u32) -> (f32, bool) {
    match camera.projection {
        Projection::Perspective => (2.0 * (0.5 * camera.fov_y_deg.to_radians()).tan() / height_px as f32, true),
        Projection::Parallel => (2.0 * camera.half_height_at_target() / height_px as f32, false),
    }
}

impl ResolveArgs {
    /// The resolve of a splat of `view` seen by `camera`, drawn with `style`.
    pub fn new(view: &SplatView, camera: &OrbitCamera, style: &ResolveStyle) -> Self {
        let (pixel_size, perspective) = pixel_footprint(camera, view.height);
        Self {
            mode: view.mode,
            background: view.background,
            depth_cue: view.depth_cue,
            shading: style.shading,
            occlusion: style.occlusion,
            point_radius_px: style.point_radius_px,
            near: view.near,
            far: view.far,
            pixel_size,
            perspective,
            origin_px: [0, 0],
            tone: style.tone,
            shadows: style.shadows,
            key_light: style.key_light().to_array(),
            shadow: view.shadow,
            normal_radius_px: NORMAL_RADIUS_PX,
            pixel_area: pixel_area(camera, view.height),
            points_drawn: 0,
        }
    }

    /// These arguments for an accumulation of `points_drawn` points.
    pub fn drawn(self, points_drawn: u64) -> Self {
        Self { points_drawn, ..self }
    }

    /// The factor s of the absolute density ln(1 + count · s): 1 / (points drawn · pixel area);
    /// 0 selects the relative scale (and average and closest modes ignore it).
    pub fn count_scale(&self) -> f32 {
        if self.tone.density_scale != DensityScale::Absolute {
            return 0.0;
        }
        let s = 1.0 / (self.points_drawn.max(1) as f64 * f64::from(self.pixel_area));
        if s.is_finite() && s > 0.0 { s as f32 } else { f32::MIN_POSITIVE }
    }

    /// The shader's parameters for an accumulation of `width`×`height` pixels. Shading,
    /// occlusion and point radius apply to closest mode only (zero otherwise, so that the GPU
    /// picks the unshaded pipeline); the radius is clamped to [`MAX_POINT_RADIUS_PX`], the
    /// strengths to [0, 1]. The occlusion samples reach 3 and 6.7 pixels per 480 rows.
    pub fn params(&self, width: u32, height: u32, encode_srgb: bool) -> ResolveParams {
        let closest = self.mode == SplatMode::Closest;
        let tone = ToneUniforms::of(&self.tone);
        let (filter_taps, filter_weights) =
            if closest { (0, [[0.0; 4]; 4]) } else { filter::uniforms(self.tone.filter) };
        ResolveParams {
            background: [self.background[0], self.background[1], self.background[2], self.depth_cue],
            width,
            height,
            mode: self.mode.index(),
            encode_srgb: encode_srgb as u32,
            shading: if closest { self.shading.clamp(0.0, 1.0) } else { 0.0 },
            near: self.near,
            far: self.far,
            pixel_size: self.pixel_size,
            perspective: self.perspective as u32,
            point_radius_px: if closest { self.point_radius_px.min(MAX_POINT_RADIUS_PX) } else { 0 },
            origin_x: self.origin_px[0],
            origin_y: self.origin_px[1],
            occlusion: if closest { self.occlusion.clamp(0.0, 1.0) } else { 0.0 },
            occlusion_step_px: ((height + 240) / 480).max(1),
            brightness: tone.brightness,
            inv_gamma: tone.inv_gamma,
            gamma_threshold: tone.gamma_threshold,
            vibrancy: tone.vibrancy,
            highlight_power: tone.highlight_power,
            shadows: 0.0,
            key_light: [self.key_light[0], self.key_light[1], self.key_light[2], 0.0],
            shadow_from_view: [[0.0; 4]; 4],
            shadow_side_px: 0,
            shadow_texel_world: 0.0,
            shadow_inv_depth_world: 0.0,
            normal_radius_px: self.normal_radius_px.clamp(1, NORMAL_RADIUS_PX),
            count_scale: if self.mode == SplatMode::Density { self.count_scale() } else { 0.0 },
            filter_taps,
            blend_srgb: (self.mode.blend_space(self.tone.blend) == BlendSpace::Srgb) as u32,
            pad: 0,
            filter_weights,
        }
        .with_shadow(self, closest)
    }
}

/// The resolve's bindings: the accumulation in the GPU's layout (closest mode: one key per
/// pixel; otherwise r, g, b sums and the count, four u32 per pixel), the function colours
/// (linear RGB) and the maximum count ([`max_count`], density mode).
#[derive(Clone, Copy, Debug)]
pub struct ResolveInputs<'a> {
    pub accum: &'a [u32],
    pub colors: &'a [[f32; 3]],
    pub max_count: u32,
    /// The shadow map's keys (empty without one).
    pub shadow: &'a [u32],
}

impl<'a> ResolveInputs<'a> {
    /// The bindings for `framebuffer` (the maximum count computed for density mode only, as the
    /// GPU runs its reduction only then).
    pub fn of(framebuffer: &'a Framebuffer) -> Self {
        let accum: &[u32] = match framebuffer.view.mode {
            SplatMode::Closest => &framebuffer.closest,
            SplatMode::Average | SplatMode::Density => bytemuck::cast_slice(&framebuffer.accum),
        };
        let width_px = framebuffer.view.width as usize;
        let height_px = framebuffer.view.height as usize;
        let max_count =
            if framebuffer.view.mode == SplatMode::Density { max_count(accum, width_px * height_px) } else { 0 };
        Self { accum, colors: &framebuffer.colors, max_count, shadow: &framebuffer.shadow }
    }
}

/// The maximum count over the first `pixels` pixels of a sum accumulation: the twin of the
/// shader's `max_count` (a workgroup reduction there, `atomicMax` into `stats[0]`).
pub fn max_count(accum: &[u32], pixels: usize) -> u32 {
    accum.chunks_exact(4).take(pixels).map(|a| a[3]).max().unwrap_or(0)
}

/// The shader's `linear_to_srgb` (the same function as the scene's).
fn encode(c: [f32; 3]) -> [f32; 3] {
    c.map(linear_to_srgb)
}

/// A resolved colour (in the blend space, [`ResolveParams::blend_srgb`]) as the target takes
/// it: sRGB-encoded where `p.encode_srgb` is set, else linear. The shader's `output_color`.
pub(crate) fn output_color(p: &ResolveParams, c: [f32; 3]) -> [f32; 3] {
    match (p.blend_srgb != 0, p.encode_srgb != 0) {
        (false, true) => encode(c),
        (false, false) => c,
        (true, true) => c.map(|v| v.clamp(0.0, 1.0)),
        (true, false) => crate::color::srgb_to_linear(c.map(|v| v.clamp(0.0, 1.0))),
    }
}

fn cue(p: &ResolveParams, color: [f32; 3], t: f32) -> [f32; 3] {
    let k = p.background[3] * t;
    [0, 1, 2].map(|c| color[c] + (p.background[c] - color[c]) * k)
}

fn key_at(p: &ResolveParams, accum: &[u32], x: i32, y: i32) -> u32 {
    if x < 0 || y < 0 || x >= p.width as i32 || y >= p.height as i32 {
        return EMPTY;
    }
    accum[y as usize * p.width as usize + x as usize]
}

fn depth_of(key: u32) -> f32 {
    (key >> 8) as f32 / DEPTH_SCALE
}

/// The fragment stage `resolve` at accumulation pixel (x, y) (the shader's fragment position
/// less the origin): the colour the shader returns, sRGB-encoded when `p.encode_srgb` is set.
/// The mode and the lighting switch on the uniforms, which [`ResolveArgs::params`] makes equal
/// to the GPU pipeline's constants `RESOLVE_MODE` and `SHADED` (shading or occlusion on).
pub fn resolve_fragment(p: &ResolveParams, inputs: &ResolveInputs<'_>, x: u32, y: u32) -> [f32; 3] {
    resolve_fragment_perturbed(p, inputs, x, y, (0.0, 0.0))
}

/// [`resolve_fragment`] with `slope_offset` added to the solid look's fitted slopes: how much
/// the colour moves with an error in the slopes, for error bounds (`tests/resolve.rs`).
pub fn resolve_fragment_perturbed(
    p: &ResolveParams,
    inputs: &ResolveInputs<'_>,
    x: u32,
    y: u32,
    slope_offset: (f32, f32),
) -> [f32; 3] {
    fragment(p, inputs, x, y, Light::Fitted(slope_offset))
}

/// Where a fragment's solid light comes from.
#[derive(Clone, Copy)]
enum Light<'a> {
    /// Computed for the pixel ([`solid::light`]), with this offset added to the fitted slopes.
    Fitted((f32, f32)),
    /// Read from the light factors of its rows (the GPU's light cache; the same bits).
    Rows(&'a LightRows),
}

/// Resolves row `y`: `pixel(x, colour)` for each pixel left to right, the colours
/// [`resolve_fragment`] gives, with the solid look's light computed for the row's pixels
/// together ([`LightRows`], eight at a time) rather than one fragment at a time.
pub fn resolve_row(p: &ResolveParams, inputs: &ResolveInputs<'_>, y: u32, mut pixel: impl FnMut(usize, [f32; 3])) {
    let lit = p.mode == MODE_CLOSEST && (p.shading > 0.0 || p.occlusion > 0.0);
    // The keys within the point radius may sit on the rows around.
    let r = p.point_radius_px as i32;
    let rows = lit.then(|| LightRows::new(p, inputs, y as i32 - r..=y as i32 + r));
    let light = rows.as_ref().map_or(Light::Fitted((0.0, 0.0)), Light::Rows);
    for x in 0..p.width {
        pixel(x as usize, fragment(p, inputs, x, y, light));
    }
}

/// [`resolve_row`] with the solid look's light read from `light` (a cache of every row, some
/// of them refreshed for this draw: [`LightRows::whole`], [`LightRows::refresh`]), as the GPU's
/// draw reads its light cache: the same colours where the cache is current.
pub fn resolve_row_cached(
    p: &ResolveParams,
    inputs: &ResolveInputs<'_>,
    y: u32,
    light: &LightRows,
    mut pixel: impl FnMut(usize, [f32; 3]),
) {
    for x in 0..p.width {
        pixel(x as usize, fragment(p, inputs, x, y, Light::Rows(light)));
    }
}

fn fragment(p: &ResolveParams, inputs: &ResolveInputs<'_>, x: u32, y: u32, light: Light<'_>) -> [f32; 3] {
    let accum = inputs.accum;
    let mut c = [p.background[0], p.background[1], p.background[2]];
    if x < p.width && y < p.height {
        let pixel = (y * p.width + x) as usize;
        if p.mode == MODE_CLOSEST {
            let mut key = accum[pixel];
            let mut at = (x as i32, y as i32);
            let r = p.point_radius_px as i32;
            // r = 0 skips the loop (the shader's `r > 0` in its loop condition): the pixel's
            // own key is the only one within radius 0.
            if r > 0 {
                for dy in -r..=r {
                    for dx in -r..=r {
                        let k = key_at(p, accum, x as i32 + dx, y as i32 + dy);
                        if dx * dx + dy * dy <= r * r && k < key {
                            key = k;
                            at = (x as i32 + dx, y as i32 + dy);
                        }
                    }
                }
            }
            if key != EMPTY {
                let fi = (key & 0xff) as usize;
                let t = depth_of(key);
                // The GPU's table has 256 entries; keys only hold indices of compiled functions.
                let mut base = inputs.colors[fi.min(inputs.colors.len() - 1)];
                if p.shading > 0.0 || p.occlusion > 0.0 {
                    base = match light {
                        Light::Fitted(slope_offset) => {
                            solid::light(p, inputs, at.0, at.1, key, Vec3::from_array(base), slope_offset).to_array()
                        }
                        Light::Rows(rows) => rows.lit(at.0, at.1, base),
                    };
                }
                c = cue(p, base, t);
            }
        } else {
            // A pixel's average colour and linear density (None: no points).
            let sample = |x: u32, y: u32| {
                let slot = 4 * (y * p.width + x) as usize;
                let count = accum[slot + 3];
                (count > 0).then(|| {
                    let n = count as f32 * COLOR_SCALE;
                    let avg = [accum[slot] as f32 / n, accum[slot + 1] as f32 / n, accum[slot + 2] as f32 / n];
                    (avg, density_of(p, inputs, count))
                })
            };
            let drawn = if p.filter_taps > 0 { filter::gather(p, x, y, sample) } else { sample(x, y) };
            if let Some((avg, a0)) = drawn {
                c = toned(&tone_uniforms(p), avg, a0, background(p), p.mode != MODE_AVERAGE).0;
            }
        }
    }
    output_color(p, c)
}

/// The linear density of a pixel with `count` points: 1 in average mode, else
/// [`log_density`].
fn density_of(p: &ResolveParams, inputs: &ResolveInputs<'_>, count: u32) -> f32 {
    if p.mode == MODE_AVERAGE {
        return 1.0;
    }
    log_density(p, count as f32, inputs.max_count.max(1) as f32)
}

/// Density mode's linear density of a pixel with `count` points (a float: density estimation
/// spreads counts), the largest being `max_count` (≥ 1): log(1 + count) / log(1 + max count),
/// or log(1 + count · s) on the absolute scale (`p.count_scale` s > 0). The shader's
/// `log_density`.
pub fn log_density(p: &ResolveParams, count: f32, max_count: f32) -> f32 {
    if p.count_scale > 0.0 {
        return log_1p(count * p.count_scale);
    }
    (1.0 + count).ln() / (1.0 + max_count).ln()
}

/// log(1 + x) for x ≥ 0 to a few ULP also where x is small, the shader's `log_1p`: below 1/8 its
/// series to x⁸ (the rest is below 2^-24 relative), where 1 + x would round away most of x and
/// WGSL's log is only held to 2^-21 absolute; log(1 + x) above, where that is ≤ 2^-17.9 relative.
fn log_1p(x: f32) -> f32 {
    if x < 0.125 {
        let mut sum = -1.0 / 8.0;
        for k in (1..8).rev() {
            let term = 1.0 / k as f32;
            sum = if k % 2 == 1 { term } else { -term } + x * sum;
        }
        x * sum
    } else {
        (1.0 + x).ln()
    }
}

fn background(p: &ResolveParams) -> [f32; 3] {
    [p.background[0], p.background[1], p.background[2]]
}

fn tone_uniforms(p: &ResolveParams) -> ToneUniforms {
    ToneUniforms {
        brightness: p.brightness,
        inv_gamma: p.inv_gamma,
        gamma_threshold: p.gamma_threshold,
        vibrancy: p.vibrancy,
        highlight_power: p.highlight_power,
    }
}

/// What an 8-bit unorm target stores for a fragment value: round to nearest.
fn unorm8(v: f32) -> u8 {
    (v * 255.0 + 0.5) as u8
}

/// Resolves `framebuffer` (seen by `camera`, for the normals of the shading) with `style` to an
/// 8-bit sRGB image, as the GPU resolve draws it into an RGBA8 unorm target.
/// Rows are resolved in parallel (every pixel is a pure function of the accumulation).
pub fn resolve_image(framebuffer: &Framebuffer, camera: &OrbitCamera, style: &ResolveStyle) -> image::RgbImage {
    let view = &framebuffer.view;
    let params =
        ResolveArgs::new(view, camera, style).drawn(framebuffer.points_drawn).params(view.width, view.height, true);
    let inputs = ResolveInputs::of(framebuffer);
    let width_px = view.width as usize;
    let mut bytes = vec![0u8; 3 * width_px * view.height as usize];
    bytes.par_chunks_mut(3 * width_px.max(1)).enumerate().for_each(|(y, row)| {
        resolve_row(&params, &inputs, y as u32, |x, c| row[3 * x..3 * x + 3].copy_from_slice(&c.map(unorm8)));
    });
    image::RgbImage::from_raw(view.width, view.height, bytes).expect("3 bytes for each of width × height pixels")
}

pub mod density_estimation;
pub mod filter;

#[cfg(test)]
mod tests;
