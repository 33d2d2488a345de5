//! The solid look's cast shadows on the CPU, twin of `shadow_at` in `shaders/resolve.wgsl`
//! (same constants, same loop shape; keep in sync). The attractor's points were splatted a
//! second time from the key light into a shadow map of closest depths (`src/splat/shadow.rs`).
//! Each visible pixel's view-space position is rebuilt from its key depth, carried into the map,
//! and compared with the map's depths in a fixed 3×3 pattern of texels around it
//! (percentage-closer filtering, no noise): the fraction of the taps with an occluder nearer to
//! the light is the pixel's shadow, which takes the key light's diffuse and highlight away
//! (ambient and fill stay).
//!
//! Each tap compares with the receiver's depth extrapolated along its fitted plane to that tap
//! (receiver-plane depth), so that a surface tilted against the light does not shadow itself at
//! the outer taps; what is left, the point's place within its texel and the normal's error, is
//! covered by a bias of a texel (or an image pixel, if larger) that grows with the slope.
//!
//! The light's direction is given by yaw and pitch relative to the camera
//! ([`key_light`]); the defaults give [`super::KEY_LIGHT`] to the bit.

use glam::{Mat4, Vec3, Vec4Swizzles};

use super::{EMPTY, KEY_LIGHT, ResolveArgs, ResolveParams, ResolveStyle, depth_of};
use crate::scene::spec::SplatMode;

/// Yaw and pitch of [`KEY_LIGHT`] (defined with the scene's fields, which default to them).
pub use crate::scene::spec::{KEY_LIGHT_PITCH_DEG, KEY_LIGHT_YAW_DEG};
/// Shadow strength of the solid look.
pub const SOLID_SHADOWS: f32 = 0.6;
/// The PCF taps: (2 SHADOW_PCF_RADIUS + 1)² texels around the receiver's.
pub const SHADOW_PCF_RADIUS: i32 = 1;
/// Constant part of the bias, in texels (or image pixels, whichever is larger).
pub const SHADOW_BIAS_TEXELS: f32 = 1.5;
/// Part of the bias per unit of the slope (tangent of the angle between normal and light).
pub const SHADOW_BIAS_SLOPE: f32 = 1.0;
/// The slope is clamped here (tan 76°): the receiver plane and the bias stop growing.
pub const SHADOW_SLOPE_MAX: f32 = 4.0;

impl ResolveStyle {
    /// The key light's direction in view space (unit).
    pub fn key_light(&self) -> Vec3 {
        Vec3::from_array(key_light(self.light_yaw_deg, self.light_pitch_deg))
    }

    /// Whether this style draws shadows on a splat of `mode`: then the splat view needs a
    /// shadow map ([`SplatView::with_shadow`]).
    pub fn casts_shadows(&self, mode: SplatMode) -> bool {
        mode == SplatMode::Closest && self.shadows > 0.0 && self.shading > 0.0
    }
}

impl ResolveParams {
    /// These parameters with `args`' shadow map, where it has one and shadows are on
    /// (closest mode and shading on only: the shadow takes away part of the key light).
    pub(super) fn with_shadow(self, args: &ResolveArgs, closest: bool) -> Self {
        match args.shadow {
            Some(view) if closest && self.shading > 0.0 && args.shadows > 0.0 => Self {
                shadows: args.shadows.min(1.0),
                shadow_from_view: view.map_from_view.to_cols_array_2d(),
                shadow_side_px: view.side_px,
                shadow_texel_world: view.texel_world,
                shadow_inv_depth_world: 1.0 / view.depth_world,
                ..self
            },
            _ => self,
        }
    }
}

/// Direction towards the key light in view space (unit) at `yaw_deg` and `pitch_deg`:
/// [`KEY_LIGHT`] itself at the defaults, so that a solid image without shadows keeps its bytes.
pub fn key_light(yaw_deg: f32, pitch_deg: f32) -> [f32; 3] {
    if yaw_deg == KEY_LIGHT_YAW_DEG && pitch_deg == KEY_LIGHT_PITCH_DEG {
        return KEY_LIGHT;
    }
    let (yaw, pitch) = (yaw_deg.to_radians(), pitch_deg.to_radians());
    [pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos()]
}

/// The view-space position of the key `key` seen at accumulation pixel (x, y): on the pixel
/// centre's ray at the key's view distance.
pub fn view_position(p: &ResolveParams, x: i32, y: i32, key: u32) -> Vec3 {
    let d = p.near + depth_of(key) * (p.far - p.near);
    let sx_screen = (x as f32 + 0.5 - 0.5 * p.width as f32) * p.pixel_size;
    let sy_screen = (0.5 * p.height as f32 - (y as f32 + 0.5)) * p.pixel_size;
    if p.perspective != 0 { Vec3::new(sx_screen * d, sy_screen * d, -d) } else { Vec3::new(sx_screen, sy_screen, -d) }
}

/// The shadowed fraction in [0, 1] of the key `key` at accumulation pixel (x, y) with unit
/// `normal` (view space), from the shadow map `map` of `p`'s shadow view.
pub fn shadow_at(p: &ResolveParams, map: &[u32], x: i32, y: i32, key: u32, normal: Vec3) -> f32 {
    let map_from_view = Mat4::from_cols_array_2d(&p.shadow_from_view);
    let q = map_from_view * view_position(p, x, y, key).extend(1.0);
    let to_light = Vec3::from_array([p.key_light[0], p.key_light[1], p.key_light[2]]);
    // The receiver's plane in the map: depth fraction per texel step along x and y, from the
    // normal's components across the map (rows 0 and 1 of the matrix are right / texel and
    // −up / texel) over its component towards the light.
    let cos = normal.dot(to_light).max(1.0 / SHADOW_SLOPE_MAX);
    let tan = ((1.0 - cos * cos).max(0.0).sqrt() / cos).min(SHADOW_SLOPE_MAX);
    let texel_depth = p.shadow_texel_world * p.shadow_inv_depth_world;
    let row0 = map_from_view.row(0).xyz() * p.shadow_texel_world;
    let row1 = map_from_view.row(1).xyz() * p.shadow_texel_world;
    let gradient_x = (normal.dot(row0) / cos).clamp(-SHADOW_SLOPE_MAX, SHADOW_SLOPE_MAX) * texel_depth;
    let gradient_y = (normal.dot(row1) / cos).clamp(-SHADOW_SLOPE_MAX, SHADOW_SLOPE_MAX) * texel_depth;
    let d = p.near + depth_of(key) * (p.far - p.near);
    let footprint = if p.perspective != 0 { p.pixel_size * d } else { p.pixel_size };
    let bias =
        (SHADOW_BIAS_TEXELS + SHADOW_BIAS_SLOPE * tan) * p.shadow_texel_world.max(footprint) * p.shadow_inv_depth_world;
    let side = p.shadow_side_px as i32;
    let (cx, cy) = (q.x.floor() as i32, q.y.floor() as i32);
    // The receiver's depth at the centre texel's centre.
    let t0 = q.z + gradient_x * (cx as f32 + 0.5 - q.x) + gradient_y * (cy as f32 + 0.5 - q.y) - bias;
    let (mut occluded, mut taps) = (0.0f32, 0.0f32);
    for j in -SHADOW_PCF_RADIUS..=SHADOW_PCF_RADIUS {
        for i in -SHADOW_PCF_RADIUS..=SHADOW_PCF_RADIUS {
            let (tx, ty) = (cx + i, cy + j);
            if tx >= 0 && ty >= 0 && tx < side && ty < side {
                let k = map[(ty * side + tx) as usize];
                let t = t0 + gradient_x * i as f32 + gradient_y * j as f32;
                if k != EMPTY && depth_of(k) < t {
                    occluded += 1.0;
                }
            }
            taps += 1.0;
        }
    }
    occluded / taps
}

#[cfg(test)]
#[path = "shadow_tests.rs"]
mod tests;
