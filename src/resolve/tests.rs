//! Unit tests of the CPU resolve: the solid look's terms (planes, a sphere, a corner and a
//! ridge, with their tolerances stated), the look presets and the scene's keys.

use super::*;

/// Parameters of a closest-mode resolve of `size`×`size` pixels in parallel projection,
/// no depth cue, linear output: with white functions a fragment's value is its light factor.
fn params(size: u32, style: ResolveStyle) -> ResolveParams {
    let args = ResolveArgs {
        mode: SplatMode::Closest,
        background: [0.0; 3],
        depth_cue: 0.0,
        shading: style.shading,
        occlusion: style.occlusion,
        point_radius_px: style.point_radius_px,
        near: 1.0,
        far: 3.0,
        pixel_size: 0.01,
        perspective: false,
        origin_px: [0, 0],
    };
    args.params(size, size, false)
}

fn key(depth_view: f32, p: &ResolveParams) -> u32 {
    let t = (depth_view - p.near) / (p.far - p.near);
    ((t * DEPTH_SCALE) as u32) << 8
}

/// The accumulation of a `size`×`size` field with view depth `depth(x, y)` (None: empty).
fn field(size: u32, p: &ResolveParams, depth: impl Fn(f32, f32) -> Option<f32>) -> Vec<u32> {
    (0..size * size).map(|i| depth((i % size) as f32, (i / size) as f32).map_or(EMPTY, |d| key(d, p))).collect()
}

/// A key alone in an empty accumulation covers the pixels within the point radius: the
/// lattice points of a disc, 1, 5 and 13 of them for radius 0, 1 and 2.
#[test]
fn radius_fills_a_disc() {
    for (radius, covered) in [(0, 1), (1, 5), (2, 13), (3, 29)] {
        let p = params(9, ResolveStyle { point_radius_px: radius, ..ResolveStyle::PAPER });
        let mut accum = vec![EMPTY; 81];
        accum[4 * 9 + 4] = key(2.0, &p);
        let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0 };
        let lit: Vec<[f32; 3]> =
            (0..81).map(|i| resolve_fragment(&p, &inputs, i % 9, i / 9)).filter(|c| c[0] > 0.0).collect();
        assert_eq!(lit.len(), covered, "radius {radius}");
        assert!(lit.iter().all(|&c| c == [1.0; 3]), "radius {radius}: {lit:?}");
    }
}

/// A plane, dense or with holes, tilted or facing the camera, is lit evenly and exactly as
/// its normal says (parallel projection: the same light everywhere), and a plane is not
/// occluded: occlusion 1 leaves its colour. Also a lone key faces the viewer.
#[test]
fn planes_are_lit_evenly_and_not_occluded() {
    let size = 21;
    for (slope_x, slope_y) in [(0.0f32, 0.0f32), (0.5, 0.0), (-1.0, 0.7), (1.7, 1.2)] {
        for holes in [false, true] {
            let p = params(size, ResolveStyle { shading: 1.0, occlusion: 1.0, point_radius_px: 0 });
            let footprint = p.pixel_size;
            let accum = field(size, &p, |x, y| {
                let hole = holes && (x as u32 * 7 + y as u32 * 3).is_multiple_of(5);
                (!hole).then_some(2.0 + (slope_x * (x - 10.0) + slope_y * (y - 10.0)) * footprint)
            });
            let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0 };
            // The plane's normal: tangents (1, 0, −slope_x) and (0, −1, −slope_y) (image y down).
            let normal = Vec3::new(0.0, -1.0, -slope_y).cross(Vec3::new(1.0, 0.0, -slope_x)).normalize();
            let (diffuse, specular) = lit(normal, Vec3::Z);
            let expected = diffuse + specular;
            // The fit's ridge flattens the slope by RIDGE / (c + RIDGE), c the weighted
            // variance of the offsets: ≥ 40 · 0.48 with a fifth of the window in holes and
            // weights ≥ 1 / (1 + |slope|² / 4) ≥ 0.48 for |slope| ≤ 2.1, so by ≤ 1 / 20. That
            // turns the normal by ≤ 0.05 · |slope| / (1 + |slope|²) ≤ 0.025 rad, and the light
            // by ≤ 0.025 · (KEY + FILL) plus the highlight's 32 · SPECULAR · s^31 · 0.025,
            // s = n · h within 0.025 of the exact normal's. Depth quantization (2^-24 of the
            // depth range over a footprint) adds < 1e-4.
            let tilt = 0.025f32;
            let half = (Vec3::from_array(KEY_LIGHT) + Vec3::Z).normalize();
            let s_max = (normal.dot(half) + tilt).min(1.0);
            let tolerance = tilt * (KEY + FILL) + 32.0 * SPECULAR * s_max.powi(31) * tilt + 1e-4;
            let (mut lowest, mut highest) = (f32::MAX, f32::MIN);
            for y in 5..16 {
                for x in 5..16 {
                    if accum[(y * size + x) as usize] == EMPTY {
                        continue;
                    }
                    let c = resolve_fragment(&p, &inputs, x, y)[0];
                    (lowest, highest) = (lowest.min(c), highest.max(c));
                    assert!(
                        (c - expected).abs() < tolerance,
                        "slopes ({slope_x}, {slope_y}), holes {holes}, pixel ({x}, {y}): {c} vs {expected} \
                         (tolerance {tolerance})"
                    );
                }
            }
            // Densely splatted, every window is the same plane: the same light up to the depth
            // keys' quantization (2^-24 of the depth range, ≪ 1e-3 of a footprint's slope).
            if !holes {
                assert!(highest - lowest < 1e-3, "slopes ({slope_x}, {slope_y}): light {lowest}..{highest}");
            }
        }
    }
    let p = params(5, ResolveStyle::SOLID);
    let mut accum = vec![EMPTY; 25];
    accum[12] = key(2.0, &p);
    let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0 };
    let (diffuse, specular) = lit(Vec3::Z, Vec3::Z);
    assert!((resolve_fragment(&p, &inputs, 2, 2)[0] - (diffuse + specular)).abs() < 1e-6);
}

/// The fitted normals of a sphere's depth field (parallel projection, every pixel covered)
/// follow the sphere's within 5° where the sphere is no steeper than 63° (slope 2; the
/// ridge flattens the fitted slope by a few percent, the window's curvature by less), so
/// Lambert's cosine under any light is within sin 5° ≈ 0.09 of the exact one.
#[test]
fn sphere_normals_follow_the_sphere() {
    let size = 81;
    let p = params(size, ResolveStyle::SOLID);
    let radius_px = 36.0;
    let centre = 40.5;
    let footprint = p.pixel_size;
    let accum = field(size, &p, |x, y| {
        let (u, v) = (x + 0.5 - centre, y + 0.5 - centre);
        let h2 = radius_px * radius_px - u * u - v * v;
        (h2 > 0.0).then(|| 2.0 - h2.sqrt() * footprint)
    });
    let mut worst_deg = 0.0f32;
    for y in 0..size as i32 {
        for x in 0..size as i32 {
            let (u, v) = (x as f32 + 0.5 - centre, y as f32 + 0.5 - centre);
            let r = (u * u + v * v).sqrt();
            // Slope 2 at r = R · 2 / √5.
            if r > radius_px * 2.0 / 5f32.sqrt() {
                continue;
            }
            let k = accum[(y * size as i32 + x) as usize];
            let slopes = fitted_slopes(&p, &accum, x, y, k);
            let (normal, _) = normal_and_eye(&p, x, y, slopes);
            let exact = Vec3::new(u, -v, (radius_px * radius_px - r * r).sqrt()) / radius_px;
            let deg = normal.dot(exact).clamp(-1.0, 1.0).acos().to_degrees();
            worst_deg = worst_deg.max(deg);
        }
    }
    assert!(worst_deg < 5.0, "worst normal error {worst_deg}°");
}

/// Occlusion: none on a plane (above) or on a convex ridge; some, below 1, in the inside of
/// a corner (a valley of two planes at right angles, seen edge-on to the crease), most at
/// its crease.
#[test]
fn a_corner_is_occluded_a_ridge_is_not() {
    let size = 41;
    let p = params(size, ResolveStyle { shading: 0.0, occlusion: 1.0, point_radius_px: 0 });
    let footprint = p.pixel_size;
    // Depth grows away from the ridge's crest (nearest the viewer) and towards the valley's.
    let ridge = field(size, &p, |x, _| Some(2.0 + (x - 20.0).abs() * footprint));
    let valley = field(size, &p, |x, _| Some(2.0 - (x - 20.0).abs() * footprint));
    let occlusion_at = |accum: &[u32], x: i32| {
        let k = accum[(20 * size as i32 + x) as usize];
        occlusion(&p, accum, x, 20, k, fitted_slopes(&p, accum, x, 20, k))
    };
    for x in 5..36 {
        assert_eq!(occlusion_at(&ridge, x), 0.0, "ridge at x = {x}");
    }
    let crease = occlusion_at(&valley, 20);
    assert!(crease > 0.3 && crease < 1.0, "valley's crease: {crease}");
    for x in 5..36 {
        let o = occlusion_at(&valley, x);
        assert!(o <= crease && o < 1.0, "valley at x = {x}: {o} (crease {crease})");
    }
    assert_eq!(occlusion_at(&valley, 5), 0.0, "the valley's walls far from the crease");
}

/// The paper look draws today's flat colour; a scene's look, shading and occlusion choose the
/// style, and 2D scenes stay paper.
#[test]
fn looks_and_scene_settings() {
    assert_eq!(ResolveStyle::default(), ResolveStyle::PAPER);
    let mut settings = RenderSettings::default();
    assert_eq!(ResolveStyle::of(&settings, 3), ResolveStyle::of_look(DEFAULT_LOOK_3D));
    settings.look = Some(Look::Solid);
    assert_eq!(ResolveStyle::of(&settings, 3), ResolveStyle::SOLID);
    settings.occlusion = Some(0.25);
    assert_eq!(ResolveStyle::of(&settings, 3), ResolveStyle { occlusion: 0.25, ..ResolveStyle::SOLID });
    settings.look = None;
    assert_eq!(ResolveStyle::of(&settings, 2), ResolveStyle { occlusion: 0.25, ..ResolveStyle::PAPER });
}

/// `[render] look`, `shading` and `occlusion` parse, write back and reach the style; bad
/// values are errors naming the field, and a scene without them writes none of them.
#[test]
fn scene_render_keys() {
    let path = format!("{}/scenes/plant2.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |keys: &str| text.replace("[render]\n", &format!("[render]\n{keys}\n"));
    let plain = crate::scene::Scene::parse(&text, &path).unwrap();
    assert_eq!((plain.render.look, plain.render.shading, plain.render.occlusion), (None, None, None));
    assert!(!plain.to_toml().contains("look ="), "a scene without a look writes none");
    let scene = crate::scene::Scene::parse(&with("look = \"solid\"\nocclusion = 0.3"), &path).unwrap();
    assert_eq!(ResolveStyle::of(&scene.render, 3), ResolveStyle { occlusion: 0.3, ..ResolveStyle::SOLID });
    let again = crate::scene::Scene::parse(&scene.to_toml(), &path).unwrap();
    assert_eq!(again.render, scene.render);
    for (keys, field) in [
        ("look = \"glossy\"", "render.look"),
        ("shading = 1.5", "render.shading"),
        ("occlusion = -0.1", "render.occlusion"),
    ] {
        let e = crate::scene::Scene::parse(&with(keys), &path).unwrap_err();
        assert_eq!(e.field.as_deref(), Some(field), "{keys}: {e}");
    }
}

/// Shading, occlusion and point radius apply to closest mode only; the radius is clamped.
#[test]
fn params_gate_the_closest_only_settings() {
    let bounds = (glam::DVec3::ZERO, glam::DVec3::ONE);
    let camera = OrbitCamera::framing(bounds, 3);
    let view = SplatView::new(&camera, 4, 4, bounds, SplatMode::Closest, 0.5, [0.0; 3]);
    let style = ResolveStyle { shading: 0.5, occlusion: 0.25, point_radius_px: 20 };
    let args = ResolveArgs::new(&view, &camera, &style);
    let closest = args.params(4, 4, true);
    assert_eq!((closest.shading, closest.occlusion, closest.point_radius_px), (0.5, 0.25, MAX_POINT_RADIUS_PX));
    for mode in [SplatMode::Average, SplatMode::Density] {
        let p = ResolveArgs { mode, ..args }.params(4, 4, true);
        assert_eq!((p.mode, p.shading, p.occlusion, p.point_radius_px), (mode.index(), 0.0, 0.0, 0));
    }
}
