//! Ray tracer against its oracles: hierarchy traversal against brute force over every leaf on
//! seeded rays for each paper scene; the Lipschitz spheres against mapped samples (the
//! superset property); a small golden image from the deterministic CPU tracer; bad glTF.

mod common;

use std::sync::atomic::AtomicBool;

use common::load_scene as scene;
use glam::{DVec3, Vec3};
use nlifs::raytrace::geometry::{NodeKind, Ray};
use nlifs::raytrace::hierarchy::{Hierarchy, InitialObject, Stop};
use nlifs::raytrace::mesh::Mesh;
use nlifs::raytrace::search::Scratch;
use nlifs::raytrace::wide::Simd;
use nlifs::raytrace::{self, Initial, RaytraceError, RaytraceSettings};
use nlifs::rng::Pcg32;

const SCENES: [&str; 5] = ["tapering", "twisting", "fantasy", "plant1", "plant2"];

fn unit_vector(rng: &mut Pcg32) -> Vec3 {
    loop {
        let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// Rays from a sphere around the geometry towards random points of its box (most hit
/// something, many graze), plus rays starting inside the box in random directions.
fn seeded_rays(h: &Hierarchy, seed: u32, count: u32) -> Vec<Ray> {
    let (lo, hi) = h.bounds;
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    (0..count)
        .map(|i| {
            let mut rng = Pcg32::for_stream(seed, 0, i);
            let target = lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            if i % 4 == 3 {
                Ray { origin: target, dir: unit_vector(&mut rng) }
            } else {
                let origin = centre + 2.0 * radius * unit_vector(&mut rng);
                Ray { origin, dir: (target - origin).normalize() }
            }
        })
        .collect()
}

/// The hierarchy's closest hit must be brute force's: the same t exactly (the same
/// intersection routine runs on the same leaf) and the same leaf unless two leaves tie.
fn check_against_brute_force(h: &Hierarchy, what: &str, seed: u32) -> usize {
    let mut hits = 0;
    let rays = seeded_rays(h, seed, 10_000);
    // The packet searches (16 rays at a time, what the tracer runs): the same nearest t and
    // the same occlusion, with a leaf as the shadow cache's guess.
    let packets = h.intersect_packets(&rays, 0.0, f32::INFINITY, &mut Scratch::default());
    let hint = (0..h.nodes.len() as u32).find(|&k| h.nodes[k as usize].kind != NodeKind::Inner).unwrap_or(u32::MAX);
    let blocked = h.occluded_packets(&rays, 0.0, f32::INFINITY, hint, &mut Scratch::default());
    for (i, ray) in rays.iter().enumerate() {
        let slow = h.intersect_brute_force(ray, 0.0, f32::INFINITY);
        assert_eq!(packets[i].map(|x| x.t), slow.map(|x| x.t), "{what}: ray {i} (seed {seed}): packet search");
        assert_eq!(blocked[i], slow.is_some(), "{what}: ray {i} (seed {seed}): packet occlusion");
    }
    for (i, ray) in rays.iter().enumerate() {
        let fast = h.intersect(ray, 0.0, f32::INFINITY);
        let slow = h.intersect_brute_force(ray, 0.0, f32::INFINITY);
        match (fast, slow) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert_eq!(a.t, b.t, "{what}: ray {i} (seed {seed}): t {} vs brute force {}", a.t, b.t);
                hits += 1;
            }
            _ => panic!("{what}: ray {i} (seed {seed}): hierarchy {fast:?} vs brute force {slow:?}"),
        }
        // With any leaf as hint (the tracer passes the previous sample's), the same nearest t.
        let leaves: Vec<u32> =
            (0..h.nodes.len() as u32).filter(|&k| h.nodes[k as usize].kind != NodeKind::Inner).collect();
        let hint = leaves[(i * 7919) % leaves.len()];
        let hinted = h.intersect_hinted(ray, 0.0, f32::INFINITY, hint, &mut Scratch::default());
        assert_eq!(hinted.map(|x| x.t), slow.map(|x| x.t), "{what}: ray {i} (seed {seed}): hinted with leaf {hint}");
        assert_eq!(h.occluded(ray, 0.0, f32::INFINITY), slow.is_some(), "{what}: ray {i} (seed {seed}): occlusion");
        // With any leaf as the shadow cache's guess, the same answer.
        let cached = h.occluder_hinted(ray, 0.0, f32::INFINITY, hint, &mut Scratch::default());
        assert_eq!(
            cached.is_some(),
            slow.is_some(),
            "{what}: ray {i} (seed {seed}): occlusion with cached leaf {hint}"
        );
        if let Some(b) = slow {
            // A segment ending before the first hit is not occluded.
            assert!(!h.occluded(ray, 0.0, b.t * 0.999), "{what}: ray {i}: occluded before the first hit");
        }
    }
    hits
}

/// Every compiled form of the traversal this CPU runs (the baseline one always; AVX2 and
/// AVX-512 where present), so that each is checked against brute force.
fn simd_forms(h: &Hierarchy) -> Vec<Hierarchy> {
    let mut forms: Vec<Hierarchy> = Vec::new();
    for simd in [Simd::Baseline, Simd::Avx2, Simd::Avx512] {
        let mut form = h.clone();
        form.set_simd(simd);
        if forms.iter().all(|f| f.simd() != form.simd()) {
            forms.push(form);
        }
    }
    eprintln!("traversal forms checked: {:?}", forms.iter().map(Hierarchy::simd).collect::<Vec<_>>());
    forms
}

#[test]
fn sphere_hierarchy_matches_brute_force_on_paper_scenes() {
    for (k, name) in SCENES.iter().enumerate() {
        let ifs = scene(name).at(0.0);
        let h = raytrace::build_fixed(&ifs, &Initial::Sphere, 4).unwrap();
        for form in simd_forms(&h) {
            let hits = check_against_brute_force(&form, &format!("{name} ({:?})", form.simd()), k as u32);
            // A test that cannot fail is no test: most rays must hit.
            assert!(hits > 3000, "{name}: only {hits} of 10000 rays hit");
        }
    }
}

/// Shadow rays of a parallel light (one direction, what the tracer's packets carry and what
/// the beam cull serves): from the surfaces the camera rays hit, offset as the tracer does, and
/// rays that graze leaf spheres within rounding of their silhouettes. Each packet answer must
/// be brute force's.
fn check_parallel_shadows(h: &Hierarchy, what: &str, seed: u32) -> (usize, usize) {
    let (lo, hi) = h.bounds;
    let eps = 1e-4 * 0.5 * (hi - lo).length();
    let mut rng = Pcg32::for_stream(seed, 1, 0);
    let light = unit_vector(&mut rng);
    let mut rays = Vec::new();
    for ray in seeded_rays(h, seed, 4000) {
        if let Some(hit) = h.intersect(&ray, 0.0, f32::INFINITY) {
            let (p, n) = h.surface(&ray, &hit);
            rays.push(Ray { origin: p + eps * n, dir: light });
        }
    }
    // Grazing: from a point on a leaf's silhouette circle (seen along the light), back along
    // the light, so the ray touches that sphere within rounding.
    let leaves: Vec<_> = h.leaf_spheres().copied().collect();
    let (u, v) = light.any_orthonormal_pair();
    for k in 0..2000 {
        let leaf = leaves[(k * 7919) % leaves.len()];
        let angle = std::f32::consts::TAU * rng.next_f32();
        let rim = leaf.centre + leaf.radius * (angle.cos() * u + angle.sin() * v);
        let back = (hi - lo).length() * (0.2 + rng.next_f32());
        rays.push(Ray { origin: rim - back * light, dir: light });
    }
    let rays: Vec<Ray> = rays.into_iter().filter(|r| h.root_entry(r, 0.0, f32::INFINITY) != f32::INFINITY).collect();
    let blocked = h.occluded_packets(&rays, 0.0, f32::INFINITY, u32::MAX, &mut Scratch::default());
    let mut count = 0;
    for (i, ray) in rays.iter().enumerate() {
        let slow = h.intersect_brute_force(ray, 0.0, f32::INFINITY).is_some();
        assert_eq!(blocked[i], slow, "{what}: parallel shadow ray {i} (seed {seed}) {ray:?}");
        count += slow as usize;
    }
    (count, rays.len())
}

#[test]
fn parallel_shadow_packets_match_brute_force() {
    for (k, name) in SCENES.iter().enumerate() {
        let ifs = scene(name).at(0.0);
        let h = raytrace::build_fixed(&ifs, &Initial::Sphere, 4).unwrap();
        for form in simd_forms(&h) {
            let what = format!("{name} ({:?})", form.simd());
            let (blocked, total) = check_parallel_shadows(&form, &what, 300 + k as u32);
            // Both answers must occur often, or the comparison proves little.
            assert!(blocked > total / 10 && blocked < total * 9 / 10, "{what}: {blocked} of {total} rays blocked");
        }
    }
}

/// The adaptive stop gives leaves at mixed depths; the traversal must still agree.
#[test]
fn adaptive_hierarchy_matches_brute_force() {
    use nlifs::raytrace::hierarchy::PixelFootprint;
    for (k, name) in ["plant2", "fantasy"].iter().enumerate() {
        let ifs = scene(name).at(0.0);
        let (lo, hi) = (ifs.domain.min().as_vec3(), ifs.domain.max().as_vec3());
        let eye = 0.5 * (lo + hi) + Vec3::new(1.0, 0.6, 1.5) * (hi - lo).length();
        let pixel = PixelFootprint { eye, perspective: true, per_pixel: 0.1 };
        let h = Hierarchy::build(&ifs, &InitialObject::Sphere, Stop { max_depth: 6, pixel: Some(pixel) }).unwrap();
        let depths: std::collections::BTreeSet<u8> = h.leaf_spheres().map(|n| n.depth).collect();
        assert!(depths.len() >= 2, "{name}: the adaptive stop should give mixed depths, got {depths:?}");
        let hits = check_against_brute_force(&h, &format!("{name} adaptive"), 200 + k as u32);
        assert!(hits > 3000, "{name}: only {hits} of 10000 rays hit");
    }
}

#[test]
fn mesh_hierarchy_matches_brute_force_on_paper_scenes() {
    for (k, name) in SCENES.iter().enumerate() {
        let ifs = scene(name).at(0.0);
        let mesh = Mesh::box_surface(ifs.domain.min(), ifs.domain.max(), 3);
        let h = Hierarchy::build(&ifs, &InitialObject::Mesh(mesh), Stop { max_depth: 2, pixel: None }).unwrap();
        for form in simd_forms(&h) {
            let hits =
                check_against_brute_force(&form, &format!("{name} grid surface ({:?})", form.simd()), 100 + k as u32);
            assert!(hits > 1000, "{name}: only {hits} of 10000 rays hit");
        }
    }
}

/// S(i1 i2…ik) must contain w_i1 of every point of S(i2…ik): sample points uniformly in the
/// depth-(k−1) leaf spheres, map them, and look them up in the depth-k leaf spheres (leaves are
/// in path order, outermost function most significant). Tolerance: the f32 rounding slack that
/// the build adds, 1e-6 of the coordinates' magnitude.
#[test]
fn lipschitz_spheres_contain_mapped_samples() {
    for (k, name) in SCENES.iter().enumerate() {
        let ifs = scene(name).at(0.0);
        let active = ifs.active();
        let m = active.len();
        let depth = 3;
        let inner = raytrace::build_fixed(&ifs, &Initial::Sphere, depth - 1).unwrap();
        let outer = raytrace::build_fixed(&ifs, &Initial::Sphere, depth).unwrap();
        let inner: Vec<_> = inner.leaf_spheres().copied().collect();
        let outer: Vec<_> = outer.leaf_spheres().copied().collect();
        assert_eq!(outer.len(), inner.len() * m);
        let mut rng = Pcg32::for_stream(7, k as u32, 0);
        for sample in 0..20_000 {
            let f = sample % m;
            let p = (rng.next_u32() as usize) % inner.len();
            let s = inner[p];
            let x =
                s.centre.as_dvec3() + s.radius as f64 * rng.next_f32().cbrt() as f64 * unit_vector(&mut rng).as_dvec3();
            let y = ifs.functions[active[f]].map.eval(x);
            let t = outer[f * inner.len() + p];
            let d = (y - t.centre.as_dvec3()).length();
            let slack = 1e-6 * t.centre.abs().max_element() as f64 + 1e-9;
            assert!(
                d <= t.radius as f64 + slack,
                "{name}: sample {sample}: w_{f}(x) at distance {d} from a sphere of radius {}",
                t.radius
            );
        }
    }
}

/// Points of A mapped through a leaf's whole composition lie inside the bound of every node on
/// the way down (what makes culling by the hierarchy correct).
#[test]
fn mapped_points_stay_inside_their_ancestors() {
    for (k, name) in SCENES.iter().enumerate() {
        let ifs = scene(name).at(0.0);
        let active = ifs.active();
        let h = raytrace::build_fixed(&ifs, &Initial::Sphere, 4).unwrap();
        let (lo, hi) = (ifs.domain.min(), ifs.domain.max());
        let mut rng = Pcg32::for_stream(11, k as u32, 0);
        for sample in 0..2000 {
            let mut x =
                lo + (hi - lo) * DVec3::new(rng.next_f32() as f64, rng.next_f32() as f64, rng.next_f32() as f64);
            let path: Vec<usize> = (0..4).map(|_| rng.next_u32() as usize % active.len()).collect();
            for &f in path.iter().rev() {
                x = ifs.functions[active[f]].map.eval(x);
            }
            let mut node = 0usize;
            for &f in &path {
                let n = h.nodes[node];
                let d = (x - n.centre.as_dvec3()).length();
                assert!(d <= n.radius as f64 * (1.0 + 1e-6), "{name}: sample {sample} outside node {node}");
                node = n.first as usize + f;
            }
        }
    }
}

/// A 128×96 still of tapering W^3(sphere) at 2 spp. Tolerance: the image is a deterministic
/// function of the inputs on one build, but libm's sqrt/pow and FMA contraction may differ
/// across platforms by a few ulps, which moves silhouette and shadow-edge samples. So: mean
/// absolute channel difference ≤ 0.5 levels and at most 1% of pixels off by more than 16 levels.
#[test]
fn golden_image_tapering_spheres() {
    let scene = scene("tapering");
    let settings = RaytraceSettings { width: 128, height: 96, spp: 2, depth: 3, ..Default::default() };
    let traced = raytrace::render(&scene, 0.0, None, &settings, &|_, _| {}, &AtomicBool::new(false)).unwrap();
    let actual = traced.image;
    let name = "tapering_n3_spheres";
    let Some(expected) = common::golden_or_replace(name, &actual) else { return };
    let diff = common::Difference::of(&actual, &expected);
    let (mean, bad) = (diff.mean_levels(), diff.pixels_over(16));
    let pixels = (actual.width() * actual.height()) as usize;
    if mean > 0.5 || bad * 100 > pixels {
        panic!(
            "golden image differs: mean {mean:.3} levels, {bad} pixels > 16 levels; {}",
            diff.write_failure_images(name, &actual)
        );
    }
}

#[test]
fn bad_gltf_is_an_error_not_a_panic() {
    let dir = common::temp_dir("raytrace");
    let ifs = scene("tapering").at(0.0);
    let cases: [(&str, &[u8]); 3] = [
        ("garbage.glb", b"this is not a glTF file"),
        ("truncated.glb", b"glTF\x02\x00\x00\x00\xff\x00\x00\x00"),
        ("empty.gltf", br#"{"asset":{"version":"2.0"}}"#),
    ];
    for (name, bytes) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        match raytrace::build_fixed(&ifs, &Initial::Gltf(path.clone()), 1) {
            Err(RaytraceError::Gltf { .. }) => {}
            other => panic!("{name}: expected a glTF error, got {:?}", other.map(|h| h.leaf_count)),
        }
    }
    let missing = raytrace::build_fixed(&ifs, &Initial::Gltf(dir.join("missing.glb")), 1);
    assert!(matches!(missing, Err(RaytraceError::Gltf { .. })));
}

/// `export mesh` output read back by the gltf crate as an initial object: W^1(sphere) of
/// tapering is 4 icospheres of 80 triangles, so W^1 of plant2 with it as A has 5 · 320.
#[test]
fn exported_mesh_round_trips_as_initial_object() {
    let dir = common::temp_dir("raytrace-rt");
    let tapering = scene("tapering").at(0.0);
    let h = raytrace::build_fixed(&tapering, &Initial::Sphere, 1).unwrap();
    let colors: Vec<[f32; 3]> = tapering.functions.iter().map(|f| f.color).collect();
    let names: Vec<String> = tapering.functions.iter().map(|f| f.name.clone()).collect();
    let path = dir.join("tapering_w1.glb");
    nlifs::io::write_atomic(&path, |w| raytrace::export::write_glb_mesh(w, &h, &colors, &names)).unwrap();
    let plant = scene("plant2").at(0.0);
    let g = raytrace::build_fixed(&plant, &Initial::Gltf(path), 1).unwrap();
    assert_eq!(g.leaf_count, 5);
    assert_eq!(g.triangles.len(), 5 * 4 * 80);
    // The fitted mesh lies in the grid's box, so its images lie in the plant's W^1 box.
    let (lo, hi) = (plant.domain.min().as_vec3(), plant.domain.max().as_vec3());
    let pad = 1e-3 * (hi - lo).length();
    assert!(g.bounds.0.cmpge(lo - pad).all() && g.bounds.1.cmple(hi + pad).all(), "{:?} outside {lo} {hi}", g.bounds);
}

/// A raised cancel flag stops the render with `Cancelled` (the viewer's background thread).
#[test]
fn cancel_stops_the_render() {
    let settings = RaytraceSettings { width: 32, height: 24, spp: 1, depth: 2, ..Default::default() };
    let r = raytrace::render(&scene("plant2"), 0.0, None, &settings, &|_, _| {}, &AtomicBool::new(true));
    assert!(matches!(r, Err(RaytraceError::Cancelled)), "expected Cancelled");
}

/// Pixels of `image` that differ from `background` (sRGB bytes) by more than `levels` in some
/// channel, grown by `grow` pixels (the traced silhouette's edges are antialiased).
fn covered(image: &image::RgbImage, background: [u8; 3], levels: u8, grow: i64) -> Vec<bool> {
    let (w, h) = (image.width() as i64, image.height() as i64);
    let hit = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && x < w
            && y < h
            && image.get_pixel(x as u32, y as u32).0.iter().zip(background).any(|(&a, b)| a.abs_diff(b) > levels)
    };
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            out.push((-grow..=grow).any(|dy| (-grow..=grow).any(|dx| hit(x + dx, y + dy))));
        }
    }
    out
}

/// `snapshot --framing points` takes the camera `render` takes: W^n(grid box) contains the
/// attractor (each function maps the box into itself), so every pixel the point render covers
/// is covered by the traced surface of the same camera, to within the traced edge's
/// antialiasing (one pixel) — at least 99.5 % of them. The default framing (on the traced
/// geometry) is a different camera, and the same check fails for it: the test can tell.
#[test]
fn snapshot_framed_on_points_lines_up_with_render() {
    let dir = common::temp_dir("snapshot-framing");
    let points = dir.join("points.png");
    let size = ["--width", "200", "--height", "150"];
    let out = common::run_nlifs(
        &[
            &["render", common::scene_path("tapering").to_str().unwrap()][..],
            &size,
            &["--look", "paper", "-o"],
            &[points.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let scene = scene("tapering");
    let background = scene.render.background.map(|c| (nlifs::color::linear_to_srgb(c) * 255.0).round() as u8);
    let hex = format!("#{:02x}{:02x}{:02x}", background[0], background[1], background[2]);
    let inside = |framing: &str| {
        let traced = dir.join(format!("traced-{framing}.png"));
        let out = common::run_nlifs(
            &[
                &["snapshot", common::scene_path("tapering").to_str().unwrap()][..],
                &size,
                &["--framing", framing, "--initial", "grid", "--depth", "4", "--no-ground", "--background", &hex],
                &["--spp", "1", "-o", traced.to_str().unwrap()],
            ]
            .concat(),
        );
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let point_mask = covered(&image::open(&points).unwrap().to_rgb8(), background, 2, 0);
        let traced_mask = covered(&image::open(&traced).unwrap().to_rgb8(), background, 2, 1);
        let drawn = point_mask.iter().filter(|&&c| c).count();
        let contained = point_mask.iter().zip(&traced_mask).filter(|&(&p, &t)| p && t).count();
        assert!(drawn > 2000, "the point render covers {drawn} pixels");
        contained as f64 / drawn as f64
    };
    let lined_up = inside("points");
    assert!(lined_up >= 0.995, "{:.2} % of the point render's pixels inside the traced surface", 100.0 * lined_up);
    let other = inside("geometry");
    eprintln!("inside the traced surface: framing points {:.3} %, geometry {:.3} %", 100.0 * lined_up, 100.0 * other);
    assert!(other < 0.98, "the geometry framing too puts {:.2} % inside: the check cannot tell", 100.0 * other);
    let _ = std::fs::remove_dir_all(&dir);
}
