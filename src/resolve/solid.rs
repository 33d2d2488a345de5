//! The solid look's light on the CPU (part of the resolve, `src/resolve.rs`, twin of the same
//! functions in `shaders/resolve.wgsl`): normals fitted to the depth buffer, the lights fixed
//! to the camera, ambient occlusion from the depth buffer, and the key light's shadow
//! (`shadow.rs`). The constants are the resolve's (`super::KEY_LIGHT` …); the module comment
//! of `src/resolve.rs` explains the method.

use glam::Vec3;

use super::*;

/// Offset `i` (0..8) of ring `ring` (0..2) of the occlusion samples, in units of
/// `occlusion_step_px`: the ring's two base offsets (along an axis and off it) turned by
/// (i / 2) quarter turns, and one over its length.
pub(super) fn occlusion_offset(ring: i32, i: i32) -> (i32, i32, f32) {
    let odd = i % 2 == 1;
    let (mut ox, mut oy, inv_length) = if ring == 0 {
        if odd { (2, 2, INV_LENGTH_2_2) } else { (3, 0, INV_LENGTH_3_0) }
    } else if odd {
        (3, 6, INV_LENGTH_6_3)
    } else {
        (6, 3, INV_LENGTH_6_3)
    };
    for _ in 0..i / 2 {
        (ox, oy) = (-oy, ox);
    }
    (ox, oy, inv_length)
}

/// View depth per key depth unit, in footprints (the view-space size of a pixel at the key's
/// depth), so that slopes are dimensionless (1: 45°) in both projections.
pub(super) fn footprints_per_unit(p: &ResolveParams, key: u32) -> f32 {
    let d = p.near + depth_of(key) * (p.far - p.near);
    let footprint = if p.perspective != 0 { p.pixel_size * d } else { p.pixel_size };
    (p.far - p.near) / DEPTH_SCALE / footprint
}

/// The slopes (depth change per pixel step right and down, in footprints) of a plane fitted to
/// the keys around accumulation pixel (x, y), whose key is `key`.
pub fn fitted_slopes(p: &ResolveParams, accum: &[u32], x: i32, y: i32, key: u32) -> (f32, f32) {
    let z_per_unit = footprints_per_unit(p, key);
    let depth0 = (key >> 8) as i32;
    // Weighted least-squares plane z = z̄ + slope · (offset − offset̄) through the keys of the
    // (2 r + 1)² window (r = `p.normal_radius_px`): empty pixels do not count, and a neighbour's weight
    // falls with its slope from the centre (half at SLOPE_SCALE), so that a silhouette's far
    // side does not tilt the near side's normal. The centre counts with weight 1 at z = 0.
    let (mut sw, mut sx, mut sy, mut sz) = (1.0f32, 0.0f32, 0.0f32, 0.0f32);
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let r = p.normal_radius_px as i32;
    for dy in -r..=r {
        for dx in -r..=r {
            let k = key_at(p, accum, x + dx, y + dy);
            if k != EMPTY && (dx != 0 || dy != 0) {
                let z = ((k >> 8) as i32 - depth0) as f32 * z_per_unit;
                let (fx, fy) = (dx as f32, dy as f32);
                // 1 / (1 + q² / r²) with one division (divisions are the light's largest cost,
                // on the CPU and on lavapipe).
                let (q, r2) = (z / SLOPE_SCALE, fx * fx + fy * fy);
                let w = r2 / (q * q + r2);
                sw += w;
                sx += w * fx;
                sy += w * fy;
                sz += w * z;
                sxx += w * fx * fx;
                sxy += w * fx * fy;
                syy += w * fy * fy;
                sxz += w * fx * z;
                syz += w * fy * z;
            }
        }
    }
    // The ridge term pulls an underdetermined fit (a lone pixel, a line of them) towards the
    // view-facing plane, and bounds the solve's condition number.
    let inv_sw = 1.0 / sw;
    let cxx = sxx - sx * sx * inv_sw + RIDGE;
    let cyy = syy - sy * sy * inv_sw + RIDGE;
    let cxy = sxy - sx * sy * inv_sw;
    let cxz = sxz - sx * sz * inv_sw;
    let cyz = syz - sy * sz * inv_sw;
    let inv_det = 1.0 / (cxx * cyy - cxy * cxy);
    let slope_x = ((cyy * cxz - cxy * cyz) * inv_det).clamp(-SLOPE_MAX, SLOPE_MAX);
    let slope_y = ((cxx * cyz - cxy * cxz) * inv_det).clamp(-SLOPE_MAX, SLOPE_MAX);
    (slope_x, slope_y)
}

/// The unit normal of a surface with `slopes` ([`fitted_slopes`]) seen at accumulation pixel
/// (x, y), and the unit direction from there to the eye, in view space.
pub fn normal_and_eye(p: &ResolveParams, x: i32, y: i32, slopes: (f32, f32)) -> (Vec3, Vec3) {
    let (slope_x, slope_y) = slopes;
    // Tangents per pixel step, in footprints: one pixel across plus the slope along the ray
    // (image y grows downwards, view y upwards).
    let sx_screen = (x as f32 + 0.5 - 0.5 * p.width as f32) * p.pixel_size;
    let sy_screen = (0.5 * p.height as f32 - (y as f32 + 0.5)) * p.pixel_size;
    let ray = if p.perspective != 0 { Vec3::new(sx_screen, sy_screen, -1.0) } else { Vec3::new(0.0, 0.0, -1.0) };
    let tangent_x = ray * slope_x + Vec3::X;
    let tangent_y = ray * slope_y - Vec3::Y;
    (tangent_y.cross(tangent_x).normalize(), (-ray).normalize())
}

/// The lights on a surface of unit `normal` seen from the unit direction `to_eye`: the diffuse
/// factor (ambient, key and fill) and the white highlight.
pub fn lit(normal: Vec3, to_eye: Vec3) -> (f32, f32) {
    lit_by(normal, to_eye, Vec3::from_array(KEY_LIGHT), 1.0)
}

/// [`lit`] with the key light towards `key_light` (unit), of which the fraction `key_visible`
/// reaches the surface (1 but in shadow).
pub fn lit_by(normal: Vec3, to_eye: Vec3, key_light: Vec3, key_visible: f32) -> (f32, f32) {
    let fill_light = Vec3::from_array(FILL_LIGHT);
    let key_diffuse = KEY * normal.dot(key_light).max(0.0) * key_visible;
    let diffuse = AMBIENT + key_diffuse + FILL * normal.dot(fill_light).max(0.0);
    // Blinn-Phong with exponent 32 by five squarings (exact, and defined at 0, unlike pow).
    let s1 = normal.dot((key_light + to_eye).normalize()).max(0.0);
    let s2 = s1 * s1;
    let s4 = s2 * s2;
    let s8 = s4 * s4;
    let s16 = s8 * s8;
    (diffuse, SPECULAR * (s16 * s16) * key_visible)
}

/// Occlusion of the key `key` at accumulation pixel (x, y) with `slopes` ([`fitted_slopes`]):
/// the fraction in [0, 1] of the light that [`OCCLUSION_GAIN`] and `occlusion` 1 take away.
pub fn occlusion(p: &ResolveParams, accum: &[u32], x: i32, y: i32, key: u32, slopes: (f32, f32)) -> f32 {
    let z_per_unit = footprints_per_unit(p, key);
    let depth0 = (key >> 8) as i32;
    let (slope_x, slope_y) = slopes;

    // Ambient occlusion: each sample's elevation above the fitted plane, seen from the centre
    // (tangent e, in footprints over pixels), occludes e / (1 + e), less for samples far in
    // front (a foreground object, not a crease: falloff past OCCLUSION_FALLOFF). Empty samples
    // do not count, so a sparse cloud is not darker than a dense one.
    // One division a sample: e / (1 + e) / (1 + f²) as one quotient, 1 / step and
    // 1 / OCCLUSION_FALLOFF as factors.
    let step = p.occlusion_step_px as i32;
    let inv_step = 1.0 / step as f32;
    let (mut occluded, mut samples) = (0.0f32, 0.0f32);
    for ring in 0..OCCLUSION_RINGS {
        for i in 0..OCCLUSION_DIRECTIONS {
            let (ox, oy, inv_length) = occlusion_offset(ring, i);
            let k = key_at(p, accum, x + ox * step, y + oy * step);
            if k != EMPTY {
                let z = ((k >> 8) as i32 - depth0) as f32 * z_per_unit;
                let above = slope_x * (ox * step) as f32 + slope_y * (oy * step) as f32 - z;
                let e = (above * (inv_length * inv_step) - OCCLUSION_BIAS).max(0.0);
                let f = e * INV_OCCLUSION_FALLOFF;
                occluded += e / ((1.0 + e) * (1.0 + f * f));
                samples += 1.0;
            }
        }
    }
    if samples > 0.0 { (OCCLUSION_GAIN * occluded / samples).min(1.0) } else { 0.0 }
}

/// The solid look's colour of the key `key` with colour `albedo` at accumulation pixel (x, y),
/// before the depth cue, with `slope_offset` added to the fitted slopes (0 but in error bounds).
pub(super) fn light(
    p: &ResolveParams,
    inputs: &ResolveInputs<'_>,
    x: i32,
    y: i32,
    key: u32,
    albedo: Vec3,
    slope_offset: (f32, f32),
) -> Vec3 {
    let accum = inputs.accum;
    let fitted = fitted_slopes(p, accum, x, y, key);
    let slopes = (fitted.0 + slope_offset.0, fitted.1 + slope_offset.1);
    let (normal, to_eye) = normal_and_eye(p, x, y, slopes);
    let mut key_visible = 1.0f32;
    if p.shadows > 0.0 {
        key_visible = 1.0 - p.shadows * shadow::shadow_at(p, inputs.shadow, x, y, key, normal);
    }
    let key_light = Vec3::new(p.key_light[0], p.key_light[1], p.key_light[2]);
    let (diffuse, specular) = lit_by(normal, to_eye, key_light, key_visible);
    let mut visible = 1.0f32;
    if p.occlusion > 0.0 {
        visible = 1.0 - p.occlusion * occlusion(p, accum, x, y, key, slopes);
    }
    // WGSL's mix(1, diffuse, shading), written out so that both sides round alike.
    let factor = (1.0 - p.shading) + diffuse * p.shading;
    albedo * (factor * visible) + Vec3::splat(specular * p.shading * visible)
}
