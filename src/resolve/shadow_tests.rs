//! Unit tests of the cast shadows (`resolve/shadow.rs` and the shadow splat of
//! `splat/shadow.rs`): the default light direction, and a small square over a plane whose
//! shadow must land where the light's direction puts it, with no shadow anywhere else.

use glam::{DVec3, Vec3};

use super::*;
use crate::camera::{OrbitCamera, Projection};
use crate::chaos_game::{PointBatch, PointSink};
use crate::resolve::{ResolveStyle, resolve_linear};
use crate::scene::spec::SplatMode;
use crate::splat::{Framebuffer, SplatView};

/// The default yaw and pitch give the solid look's key light to the bit, and the formula gives
/// it within f32 rounding (so the defaults are the direction, not just a switch).
#[test]
fn default_angles_are_the_key_light() {
    assert_eq!(key_light(KEY_LIGHT_YAW_DEG, KEY_LIGHT_PITCH_DEG), KEY_LIGHT);
    let (yaw, pitch) = (KEY_LIGHT_YAW_DEG.to_radians(), KEY_LIGHT_PITCH_DEG.to_radians());
    let formula = Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos());
    assert!((formula - Vec3::from_array(KEY_LIGHT)).abs().max_element() < 1e-6, "{formula}");
    // Off the defaults the formula holds: straight at the viewer, and straight up.
    assert!((Vec3::from_array(key_light(0.0, 0.0)) - Vec3::Z).length() < 1e-6);
    assert!((Vec3::from_array(key_light(10.0, 90.0)) - Vec3::Y).length() < 1e-6);
}

/// Splats `points` into `fb` in batches.
fn splat_points(fb: &mut Framebuffer, points: &[Vec3]) {
    for chunk in points.chunks(4096) {
        let x: Vec<f32> = chunk.iter().map(|p| p.x).collect();
        let y: Vec<f32> = chunk.iter().map(|p| p.y).collect();
        let z: Vec<f32> = chunk.iter().map(|p| p.z).collect();
        let functions = vec![0u8; chunk.len()];
        fb.consume(PointBatch { x: &x, y: &y, z: &z, functions: &functions });
    }
}

/// A dense horizontal plane (y = 0, x and z in [-1, 1]) and a small square (side 0.2) at height
/// h = 0.6 above its centre, seen from above in parallel projection, lit by a key light turned
/// to the side. The shadow's darkening (shadows 1 against shadows 0, the same accumulation) has
/// its centroid where the square's centre, moved along the light's direction onto the plane,
/// lands in the image. Tolerance: 1.5 texels (the square's coverage of the map is quantized to
/// whole texels at each edge, ≤ 1 texel of centroid, and the 3×3 PCF taps are centred on the
/// receiver's texel, not on its position in it, ≤ ½ texel) in image pixels, plus 1 pixel for the
/// image's own sampling. Away from the shadow (beyond its analytic outline grown by that
/// tolerance and the PCF's reach) nothing may darken at all: no acne on the lit plane or square.
#[test]
fn square_shadow_lands_where_the_light_puts_it() {
    let (size_px, h, half_side) = (200u32, 0.6f32, 0.1f32);
    let camera = OrbitCamera {
        target: Vec3::ZERO,
        yaw_deg: 20.0,
        pitch_deg: 55.0,
        distance: 5.0,
        fov_y_deg: 40.0,
        projection: Projection::Parallel,
    };
    let bounds = (DVec3::new(-1.0, 0.0, -1.0), DVec3::new(1.0, h as f64, 1.0));
    for (case, (yaw_deg, pitch_deg)) in [(55.0f32, 10.0f32), (-40.0, 25.0), (20.0, -15.0)].into_iter().enumerate() {
        let style = ResolveStyle {
            occlusion: 0.0,
            shadows: 1.0,
            light_yaw_deg: yaw_deg,
            light_pitch_deg: pitch_deg,
            ..ResolveStyle::SOLID
        };
        let view = SplatView::new(&camera, size_px, size_px, bounds, SplatMode::Closest, 0.0, [0.0; 3]);
        let view = view.with_shadow(&camera, bounds, style.key_light());
        let shadow_view = view.shadow.expect("closest mode has a shadow map");
        let mut fb = Framebuffer::new(view, vec![[1.0; 3]]);
        let step = 0.002;
        let n = (2.0 / step) as i32;
        let mut points: Vec<Vec3> = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| Vec3::new(-1.0 + i as f32 * step, 0.0, -1.0 + j as f32 * step)))
            .collect();
        let m = (2.0 * half_side / step) as i32;
        points.extend((0..=m).flat_map(|i| {
            (0..=m).map(move |j| Vec3::new(-half_side + i as f32 * step, h, -half_side + j as f32 * step))
        }));
        splat_points(&mut fb, &points);
        let lit = resolve_linear(&fb, &camera, &style);
        let unshadowed = resolve_linear(&fb, &camera, &ResolveStyle { shadows: 0.0, ..style });

        // The analytic shadow: the square moved along −L (world) down to the plane.
        let world_from_view = camera.view_from_world().inverse();
        let to_light = world_from_view.transform_vector3(style.key_light()).normalize();
        assert!(to_light.y > 0.2, "case {case}: the light must shine down onto the plane: {to_light}");
        let onto_plane = |p: Vec3| p - to_light * (p.y / to_light.y);
        let pixel_of = |p: Vec3| {
            let q = view.pixel_from_world * p.extend(1.0);
            (q.x / q.w, q.y / q.w)
        };
        let expected = pixel_of(onto_plane(Vec3::new(0.0, h, 0.0)));
        // Pixel world size (parallel projection) and the tolerance of the doc comment.
        let pixel_world = 2.0 * camera.half_height_at_target() / size_px as f32;
        let texel_px = shadow_view.texel_world / pixel_world;
        let tolerance_px = 1.5 * texel_px + 1.0;
        // The shadow's outline in the image: its corners' bounding box, grown by the tolerance
        // and the PCF's reach (its radius in texels, plus one for the map's quantization).
        let corners: Vec<(f32, f32)> = [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .iter()
            .map(|&(a, b)| pixel_of(onto_plane(Vec3::new(a * half_side, h, b * half_side))))
            .collect();
        let grow = tolerance_px + (SHADOW_PCF_RADIUS as f32 + 1.0) * texel_px;
        let (x0, x1) = (
            corners.iter().map(|c| c.0).fold(f32::MAX, f32::min),
            corners.iter().map(|c| c.0).fold(f32::MIN, f32::max),
        );
        let (y0, y1) = (
            corners.iter().map(|c| c.1).fold(f32::MAX, f32::min),
            corners.iter().map(|c| c.1).fold(f32::MIN, f32::max),
        );
        // The square's own image must not cover its shadow (else the centroid is cut).
        let square: Vec<(f32, f32)> = [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .iter()
            .map(|&(a, b)| pixel_of(Vec3::new(a * half_side, h, b * half_side)))
            .collect();
        let apart = square.iter().all(|s| s.0 < x0 - grow)
            || square.iter().all(|s| s.0 > x1 + grow)
            || square.iter().all(|s| s.1 < y0 - grow)
            || square.iter().all(|s| s.1 > y1 + grow);
        assert!(apart, "case {case}: the square {square:?} hides its shadow {corners:?}");

        let (mut sum, mut sx, mut sy, mut stray) = (0.0f64, 0.0f64, 0.0f64, 0);
        for y in 0..size_px {
            for x in 0..size_px {
                let i = (y * size_px + x) as usize;
                let darkening = unshadowed.rgb[i][0] - lit.rgb[i][0];
                assert!(darkening >= 0.0, "case {case}: a shadow brightened ({x}, {y}) by {darkening}");
                if darkening > 0.0 {
                    let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                    if px < x0 - grow || px > x1 + grow || py < y0 - grow || py > y1 + grow {
                        stray += 1;
                    }
                    sum += darkening as f64;
                    sx += darkening as f64 * px as f64;
                    sy += darkening as f64 * py as f64;
                }
            }
        }
        assert_eq!(stray, 0, "case {case}: pixels darkened outside the shadow (acne)");
        assert!(sum > 0.0, "case {case}: no shadow at all");
        let centroid = ((sx / sum) as f32, (sy / sum) as f32);
        let error = ((centroid.0 - expected.0).powi(2) + (centroid.1 - expected.1).powi(2)).sqrt();
        eprintln!(
            "case {case}: shadow centroid {centroid:?}, expected {expected:?}: {error:.2} px off \
             (tolerance {tolerance_px:.2} px, texel {texel_px:.2} px)"
        );
        assert!(error <= tolerance_px, "case {case}: centroid {centroid:?} is {error} px from {expected:?}");
    }
}
