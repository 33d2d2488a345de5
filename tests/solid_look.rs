//! The solid look on splatted points, end to end through the real splat and the CPU resolve
//! (`src/resolve.rs`), against closed forms: a densely splatted plane facing the camera is lit
//! evenly; a sphere's points are lit by Lambert's cosine (plus the key light's highlight) of
//! the sphere's exact normal, within the error the depth-fitted normals allow.

use glam::{DVec3, Vec3};
use nlifs::camera::{OrbitCamera, Projection};
use nlifs::chaos_game::{PointBatch, PointSink};
use nlifs::resolve::{self, LinearImage, ResolveStyle};
use nlifs::rng::Pcg32;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::{Framebuffer, SplatView};

const SIZE_PX: u32 = 200;

/// The shading alone: lit, no occlusion, flat everything else (shadows off where the look has
/// them; the sphere is convex and the plane faces the light, so they would only add bias).
fn shading_only() -> ResolveStyle {
    ResolveStyle { occlusion: 0.0, ..ResolveStyle::SOLID }
}

/// A perspective camera looking at the origin from +z (yaw and pitch 0), framing [-1, 1]³.
fn camera() -> OrbitCamera {
    let bounds = (DVec3::splat(-1.0), DVec3::splat(1.0));
    let mut camera = OrbitCamera::framing(bounds, 3);
    camera.yaw_deg = 0.0;
    camera.pitch_deg = 0.0;
    camera.projection = Projection::Perspective;
    camera
}

/// Splats `points` (white, one function) seen by `camera`, without depth cue, and resolves
/// them with `style` in linear light.
fn splat_and_resolve(points: &[Vec3], camera: &OrbitCamera, style: &ResolveStyle) -> LinearImage {
    let bounds = (DVec3::splat(-1.0), DVec3::splat(1.0));
    let view = SplatView::new(camera, SIZE_PX, SIZE_PX, bounds, SplatMode::Closest, 0.0, [0.0; 3]);
    let mut framebuffer = Framebuffer::new(view, vec![[1.0; 3]]);
    for chunk in points.chunks(1 << 16) {
        let x: Vec<f32> = chunk.iter().map(|p| p.x).collect();
        let y: Vec<f32> = chunk.iter().map(|p| p.y).collect();
        let z: Vec<f32> = chunk.iter().map(|p| p.z).collect();
        let functions = vec![0u8; chunk.len()];
        framebuffer.consume(PointBatch { x: &x, y: &y, z: &z, functions: &functions });
    }
    resolve::resolve_linear(&framebuffer, camera, style)
}

/// The view-space ray through the centre of pixel (x, y) (unnormalized, z = −1).
fn ray(camera: &OrbitCamera, x: u32, y: u32) -> Vec3 {
    let (pixel_size, _) = resolve::pixel_footprint(camera, SIZE_PX);
    let half = 0.5 * SIZE_PX as f32;
    Vec3::new((x as f32 + 0.5 - half) * pixel_size, (half - (y as f32 + 0.5)) * pixel_size, -1.0)
}

/// A densely splatted square of the plane z = 0 facing the camera: every pixel away from its
/// edges is lit as the plane's exact normal is (the diffuse light is the same everywhere; only
/// the highlight's half-vector turns with the view ray), within 0.01 of linear light.
#[test]
fn a_dense_plane_is_lit_evenly() {
    let camera = camera();
    let mut rng = Pcg32::for_stream(3, 0, 0);
    let points: Vec<Vec3> =
        (0..2_000_000).map(|_| Vec3::new(rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0 - 1.0, 0.0)).collect();
    let image = splat_and_resolve(&points, &camera, &shading_only());
    let (mut worst, mut covered) = (0.0f32, 0);
    let (mut lowest_diffuse, mut highest_diffuse) = (f32::INFINITY, 0.0f32);
    let inner = SIZE_PX / 4..3 * SIZE_PX / 4;
    for y in inner.clone() {
        for x in inner.clone() {
            let i = (y * SIZE_PX + x) as usize;
            if image.alpha[i] > 0.0 {
                covered += 1;
                let (diffuse, specular) = resolve::lit(Vec3::Z, -ray(&camera, x, y).normalize());
                worst = worst.max((image.rgb[i][0] - (diffuse + specular)).abs());
                lowest_diffuse = lowest_diffuse.min(image.rgb[i][0] - specular);
                highest_diffuse = highest_diffuse.max(image.rgb[i][0] - specular);
            }
        }
    }
    assert!(covered > 9_000, "{covered} covered pixels");
    assert!(worst < 0.01, "worst error {worst}");
    assert!(highest_diffuse - lowest_diffuse < 0.01, "diffuse light on the plane {lowest_diffuse}..{highest_diffuse}");
}

/// A sphere's points: each pixel where the sphere is no steeper than 63° is lit as its exact
/// normal is (diffuse by Lambert's cosine of the key and fill lights, and the key's highlight).
/// The unit test `sphere_normals_follow_the_sphere` bounds the fitted normal's error by 5° on a
/// full depth field; the splatted field is sparser and quantized within each pixel, so allow a
/// mean error of 0.02 and at most 0.1 (≈ (KEY + FILL) · sin 5° plus the highlight's change)
/// at the 99th percentile.
#[test]
fn a_sphere_of_points_follows_lamberts_cosine() {
    let camera = camera();
    let mut rng = Pcg32::for_stream(5, 0, 0);
    let points: Vec<Vec3> = (0..4_000_000)
        .map(|_| {
            let z = rng.next_f32() * 2.0 - 1.0;
            let phi = rng.next_f32() * std::f32::consts::TAU;
            let s = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect();
    let image = splat_and_resolve(&points, &camera, &shading_only());
    let centre_view = camera.view_from_world().transform_point3(Vec3::ZERO);
    let mut errors = Vec::new();
    for y in 0..SIZE_PX {
        for x in 0..SIZE_PX {
            let i = (y * SIZE_PX + x) as usize;
            let d = ray(&camera, x, y).normalize();
            // The ray's nearest hit of the unit sphere.
            let b = d.dot(centre_view);
            let disc = b * b - (centre_view.length_squared() - 1.0);
            if disc <= 0.0 {
                continue;
            }
            let hit = d * (b - disc.sqrt());
            let normal = (hit - centre_view).normalize();
            // No steeper than slope 2 towards the viewer: cos θ ≥ 1/√5.
            if normal.dot(-d) < 1.0 / 5f32.sqrt() {
                continue;
            }
            assert!(image.alpha[i] > 0.0, "pixel ({x}, {y}) on the sphere is empty");
            let (diffuse, specular) = resolve::lit(normal, -d);
            errors.push((image.rgb[i][0] - (diffuse + specular)).abs());
        }
    }
    assert!(errors.len() > 5_000, "{} pixels compared", errors.len());
    errors.sort_by(f32::total_cmp);
    let mean = errors.iter().sum::<f32>() / errors.len() as f32;
    let p99 = errors[errors.len() * 99 / 100];
    eprintln!("sphere: {} pixels, mean error {mean:.4}, 99th percentile {p99:.4}", errors.len());
    assert!(mean < 0.02, "mean error {mean}");
    assert!(p99 < 0.1, "99th percentile error {p99}");
}
