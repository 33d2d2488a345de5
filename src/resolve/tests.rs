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
        tone: style.tone,
        shadows: style.shadows,
        key_light: style.key_light().to_array(),
        shadow: None,
        normal_radius_px: NORMAL_RADIUS_PX,
        pixel_area: 1e-4,
        points_drawn: 0,
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
        let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0, shadow: &[] };
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
            let p =
                params(size, ResolveStyle { shading: 1.0, occlusion: 1.0, point_radius_px: 0, ..ResolveStyle::PAPER });
            let footprint = p.pixel_size;
            let accum = field(size, &p, |x, y| {
                let hole = holes && (x as u32 * 7 + y as u32 * 3).is_multiple_of(5);
                (!hole).then_some(2.0 + (slope_x * (x - 10.0) + slope_y * (y - 10.0)) * footprint)
            });
            let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0, shadow: &[] };
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
    let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0, shadow: &[] };
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
    let p = params(size, ResolveStyle { shading: 0.0, occlusion: 1.0, point_radius_px: 0, ..ResolveStyle::PAPER });
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
    let style = ResolveStyle { shading: 0.5, occlusion: 0.25, point_radius_px: 20, ..ResolveStyle::PAPER };
    let args = ResolveArgs::new(&view, &camera, &style);
    let closest = args.params(4, 4, true);
    assert_eq!((closest.shading, closest.occlusion, closest.point_radius_px), (0.5, 0.25, MAX_POINT_RADIUS_PX));
    for mode in [SplatMode::Average, SplatMode::Density] {
        let p = ResolveArgs { mode, ..args }.params(4, 4, true);
        assert_eq!((p.mode, p.shading, p.occlusion, p.point_radius_px), (mode.index(), 0.0, 0.0, 0));
    }
}

/// Linear density-mode parameters of a `width`×1 accumulation over a black background with
/// `tone`.
fn tone_params(mode: SplatMode, width: u32, tone: Tone) -> ResolveParams {
    let bounds = (glam::DVec3::ZERO, glam::DVec3::ONE);
    let camera = OrbitCamera::framing(bounds, 2);
    let view = SplatView::new(&camera, width, 1, bounds, mode, 0.0, [0.0; 3]);
    let style = ResolveStyle { tone, ..ResolveStyle::PAPER };
    ResolveArgs::new(&view, &camera, &style).params(width, 1, false)
}

/// A sum accumulation: per pixel, `count` points of the average colour `avg`.
fn sums(pixels: &[(u32, [f32; 3])]) -> Vec<u32> {
    pixels
        .iter()
        .flat_map(|&(count, avg)| {
            let s = avg.map(|c| (c * COLOR_SCALE * count as f32).round() as u32);
            [s[0], s[1], s[2], count]
        })
        .collect()
}

/// The linear colours of the pixels of `accum` resolved with `p`.
fn toned_row(p: &ResolveParams, accum: &[u32]) -> Vec<[f32; 3]> {
    let inputs =
        ResolveInputs { accum, colors: &[[1.0; 3]], max_count: max_count(accum, p.width as usize), shadow: &[] };
    (0..p.width).map(|x| resolve_fragment(p, &inputs, x, 0)).collect()
}

/// The neutral tone is the default everywhere, and a scene's tone reaches the style.
#[test]
fn neutral_tone_is_the_default() {
    assert_eq!(Tone::default(), Tone::NEUTRAL);
    assert_eq!(Tone::of(&RenderSettings::default()), Tone::NEUTRAL);
    assert_eq!(ResolveStyle::of(&RenderSettings::default(), 2).tone, Tone::NEUTRAL);
    let settings = RenderSettings { exposure: 1.5, gamma: 2.0, ..RenderSettings::default() };
    assert_eq!(ResolveStyle::of(&settings, 3).tone, Tone { exposure: 1.5, gamma: 2.0, ..Tone::NEUTRAL });
}

/// Exposure +1 doubles the linear colour of every pixel below saturation (bg black, gamma 1:
/// the colour is avg · 2^exposure · log density; tolerance 1e-6 relative, the doubling being
/// exact in floating point).
#[test]
fn exposure_one_doubles_linear_brightness() {
    let accum = sums(&[(1, [0.4, 0.2, 0.1]), (5, [0.3, 0.3, 0.3]), (40, [0.1, 0.2, 0.4]), (400, [0.2, 0.1, 0.3])]);
    let base = toned_row(&tone_params(SplatMode::Density, 4, Tone::NEUTRAL), &accum);
    let brighter = toned_row(&tone_params(SplatMode::Density, 4, Tone { exposure: 1.0, ..Tone::NEUTRAL }), &accum);
    for (b, e) in base.iter().zip(&brighter) {
        for c in 0..3 {
            assert!(2.0 * b[c] < 1.0, "below saturation");
            assert!((e[c] - 2.0 * b[c]).abs() <= 1e-6 * e[c], "{e:?} vs 2 × {b:?}");
        }
    }
    // Average mode: the colour itself doubles.
    let average = toned_row(&tone_params(SplatMode::Average, 4, Tone { exposure: 1.0, ..Tone::NEUTRAL }), &accum);
    let plain = toned_row(&tone_params(SplatMode::Average, 4, Tone::NEUTRAL), &accum);
    for (e, b) in average.iter().zip(&plain) {
        for c in 0..3 {
            assert!((e[c] - 2.0 * b[c]).abs() <= 1e-6 * e[c], "{e:?} vs 2 × {b:?}");
        }
    }
}

/// Gamma 2 on a known count gives avg · √(ln(1 + n) / ln(1 + max)) above the threshold, and
/// flam3's linear blend below it (closed form in f64; tolerance 1e-6 absolute, f32 rounding).
#[test]
fn gamma_two_gives_the_closed_form() {
    let avg = [0.6f32, 0.3, 0.15];
    let (n, max) = (7u32, 300u32);
    let accum = sums(&[(n, avg), (max, avg), (1, avg)]);
    for tau in [0.01f64, 0.5] {
        let p = tone_params(SplatMode::Density, 3, Tone { gamma: 2.0, gamma_threshold: tau as f32, ..Tone::NEUTRAL });
        let row = toned_row(&p, &accum);
        for (x, count) in [(0usize, n), (2, 1)] {
            let a = (1.0 + count as f64).ln() / (1.0 + max as f64).ln();
            let alpha = if a >= tau {
                a.sqrt()
            } else {
                let frac = a / tau;
                (1.0 - frac) * a * (tau.sqrt() / tau) + frac * a.sqrt()
            };
            for c in 0..3 {
                // The stored average: the sums are whole numbers.
                let stored = accum[4 * x + c] as f64 / (count as f64 * COLOR_SCALE as f64);
                let expected = stored * alpha;
                assert!(
                    (row[x][c] as f64 - expected).abs() < 1e-6,
                    "τ {tau}, count {count}: {:?} vs {expected}",
                    row[x]
                );
            }
        }
    }
}

/// On a pixel of two colours (red and blue points, average (½, 0, ½)) with gamma 2 over black,
/// vibrancy 1 applies the gamma to the alpha: avg · √a (the hue kept); vibrancy 0 per channel:
/// √(avg · a), √2 times brighter in red and blue; ½ is their mean (tolerance 1e-6).
#[test]
fn vibrancy_mixes_alpha_and_channel_gamma() {
    let avg = [0.5f32, 0.0, 0.5];
    let accum = sums(&[(20, avg), (1000, [1.0, 1.0, 1.0])]);
    let a = 21f64.ln() / 1001f64.ln();
    let row = |v: f32| {
        toned_row(&tone_params(SplatMode::Density, 2, Tone { gamma: 2.0, vibrancy: v, ..Tone::NEUTRAL }), &accum)[0]
    };
    let (vivid, per_channel, half) = (row(1.0), row(0.0), row(0.5));
    for c in [0, 2] {
        let alpha_gamma = 0.5 * a.sqrt();
        let channel_gamma = (0.5 * a).sqrt();
        assert!((vivid[c] as f64 - alpha_gamma).abs() < 1e-6, "{vivid:?}");
        assert!((per_channel[c] as f64 - channel_gamma).abs() < 1e-6, "{per_channel:?}");
        assert!((half[c] as f64 - 0.5 * (alpha_gamma + channel_gamma)).abs() < 1e-6, "{half:?}");
        assert!((per_channel[c] / vivid[c] - std::f32::consts::SQRT_2).abs() < 1e-5);
    }
    assert_eq!((vivid[1], per_channel[1]), (0.0, 0.0), "green stays black");
}

/// Highlights past white (average mode, exposure 2 on (0.5, 0.25, 0.1): 4× is (2, 1, 0.4)):
/// power −1 clips per channel, 0 keeps the hue at full value, 16 fades nearly to white
/// (saturation times 2^-16); tolerance 1e-6.
#[test]
fn highlight_power_desaturates_to_white() {
    let accum = sums(&[(4, [0.5, 0.25, 0.1])]);
    let avg = toned_row(&tone_params(SplatMode::Average, 1, Tone::NEUTRAL), &accum)[0];
    let row = |h: f32| {
        toned_row(
            &tone_params(SplatMode::Average, 1, Tone { exposure: 2.0, highlight_power: h, ..Tone::NEUTRAL }),
            &accum,
        )[0]
    };
    let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|c| (a[c] - b[c]).abs() < 1e-6);
    assert!(close(row(-1.0), [1.0, 1.0, (4.0 * avg[2]).min(1.0)]), "{:?}", row(-1.0));
    assert!(close(row(0.0), avg.map(|c| c / avg[0])), "{:?}", row(0.0));
    let r = 0.5f32.powi(16);
    assert!(close(row(16.0), avg.map(|c| 1.0 - (1.0 - c / avg[0]) * r)), "{:?}", row(16.0));
}

/// The tone fields parse, write back, animate between keys and reject values out of range with
/// an error naming the field.
#[test]
fn scene_tone_fields() {
    let path = format!("{}/scenes/plant2.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |keys: &str| text.replace("[render]\n", &format!("[render]\n{keys}\n"));
    let plain = crate::scene::Scene::parse(&text, &path).unwrap();
    assert!(!plain.to_toml().contains("gamma"), "a scene without tone fields writes none");
    let toml = "exposure = 1.5\ngamma = 2.2\ngamma_threshold = 0.05\nvibrancy = 0.5\nhighlight_power = 2.0";
    let scene = crate::scene::Scene::parse(&with(toml), &path).unwrap();
    assert_eq!(scene.render.tone(), [1.5, 2.2, 0.05, 0.5, 2.0]);
    let again = crate::scene::Scene::parse(&scene.to_toml(), &path).unwrap();
    assert_eq!(again.render, scene.render);
    for (keys, field) in [
        ("exposure = 11.0", "render.exposure"),
        ("gamma = 0.0", "render.gamma"),
        ("gamma_threshold = 1.5", "render.gamma_threshold"),
        ("vibrancy = -0.5", "render.vibrancy"),
        ("highlight_power = 100.0", "render.highlight_power"),
    ] {
        let e = crate::scene::Scene::parse(&with(keys), &path).unwrap_err();
        assert_eq!(e.field.as_deref(), Some(field), "{keys}: {e}");
    }
    let keyed = format!(
        "{text}\n[timeline]\nduration_secs = 2.0\n\n[[key]]\nt_secs = 0.0\ninterpolation = \"linear\"\n[key.render]\nexposure = 0.0\n\n[[key]]\nt_secs = 2.0\n[key.render]\nexposure = 2.0\n"
    );
    let scene = crate::scene::Scene::parse(&keyed, &path).unwrap();
    assert!((scene.render_at(1.0).exposure - 1.0).abs() < 1e-6, "{}", scene.render_at(1.0).exposure);
    let again = crate::scene::Scene::parse(&scene.to_toml(), &path).unwrap();
    assert_eq!(again.render_at(1.0).exposure, scene.render_at(1.0).exposure);
}
