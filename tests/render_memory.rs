//! Renders in bounded memory: the shared framebuffer gives the integers of the per-thread
//! framebuffers merged, whatever the thread count; a render that cannot fit stops before it
//! allocates, with the size it needs; the streamed PNG and the streamed point export write the
//! bytes of the one-shot writers; the EXR's normal layer and the layer checks.

mod common;

use std::path::Path;

use glam::Vec3;
use nlifs::chaos_game::{self, CollectSink};
use nlifs::scene::spec::{RenderSettings, SplatMode};
use nlifs::shot::{Accumulation, Framing, Shot};
use nlifs::splat::Framebuffer;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs nlifs; panics with its stderr unless it exits with `code`.
fn nlifs(args: &[&str], code: i32) -> String {
    let out = common::run_nlifs(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "nlifs {}: {stderr}", args.join(" "));
    stderr
}

fn shot(scene: &str, mode: SplatMode, width: u32, height: u32, points: u64) -> Shot {
    let scene = common::load_scene(scene);
    let settings = RenderSettings { width, height, points, mode, seed: 5, ..scene.render.clone() };
    Shot::prepare(&scene, 0.0, &settings, Framing::Fit, None).unwrap()
}

fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

/// The oracle: the framebuffer one thread fills chunk by chunk, in order.
fn sequential(shot: &Shot) -> Framebuffer {
    let mut fb = Framebuffer::new(shot.view, shot.compiled.colors.clone());
    for c in 0..shot.plan.chunks() {
        chaos_game::run_chunk(&shot.compiled, shot.settings.seed, shot.stream, c, shot.plan.steps(c), &mut fb);
    }
    fb
}

/// Every mode, a 2D and a 3D scene, 1 to 8 threads: the shared framebuffer and the merged
/// per-thread framebuffers hold exactly the integers of one thread's sequential run (tolerance 0:
/// the updates are min and saturating sums, order-independent).
#[test]
fn shared_framebuffer_equals_the_merged_per_thread_ones() {
    for (scene, size) in [("plant2", (173, 131)), ("julia", (160, 97))] {
        for mode in SplatMode::ALL {
            // Five chunks and a short one: more chunks than some pools have threads.
            let shot = shot(scene, mode, size.0, size.1, 5 * 262_144 + 1000);
            let expected = sequential(&shot);
            assert!(expected.covered_pixels() > 500, "{scene} {mode:?}: {}", expected.covered_pixels());
            for threads in [1, 2, 3, 8] {
                for way in [Accumulation::PerThread, Accumulation::Shared] {
                    let fb = on_threads(threads, || shot.splat_chunks(0..shot.plan.chunks(), way, || {}));
                    assert!(
                        fb.closest == expected.closest && fb.accum == expected.accum,
                        "{scene} {mode:?} {threads} threads {way:?}"
                    );
                }
            }
        }
    }
}

/// Large views take the shared framebuffer, small ones per-thread copies; and the render's
/// choice follows the pool it runs on.
#[test]
fn large_views_share_one_framebuffer() {
    let small = shot("plant2", SplatMode::Closest, 320, 240, 1000).view;
    let large = shot("plant2", SplatMode::Density, 4096, 4096, 1000).view;
    assert_eq!(on_threads(2, || Accumulation::for_view(&small)), Accumulation::PerThread);
    assert_eq!(on_threads(2, || Accumulation::for_view(&large)), Accumulation::Shared);
    // 1920×1080 in density mode is 33 MB: two copies fit the budget, sixteen do not.
    let hd = shot("plant2", SplatMode::Density, 1920, 1080, 1000).view;
    assert_eq!(on_threads(1, || Accumulation::for_view(&hd)), Accumulation::PerThread);
    assert_eq!(on_threads(16, || Accumulation::for_view(&hd)), Accumulation::Shared);
}

/// A render that cannot fit in the memory available stops before it allocates: exit 2, the
/// size it needs and what is available in the message, no file.
#[test]
fn a_render_too_large_for_memory_is_refused() {
    let dir = common::temp_dir("render-memory-too-large");
    let out = dir.join("huge.png");
    let scene = common::scene_path("plant2");
    let output = common::nlifs_command()
        .args(["render", s(&scene), "--width", "16384", "--height", "16384", "--mode", "density", "-o", s(&out)])
        .env("NLIFS_MEMORY_LIMIT", "1G")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    // 16384² pixels of 16 bytes: 4 GiB for the framebuffer alone.
    assert!(
        stderr.contains("16384×16384 density render needs about 4.") && stderr.contains("1.00 GiB is available"),
        "{stderr}"
    );
    assert!(!out.exists(), "a refused render wrote {}", out.display());
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing written");
}

/// The render's streamed PNG is the bytes the one-shot path writes: `resolve_image` of the
/// framebuffer encoded by `save_rgb8` with the same scene chunks; in the paper and the solid look.
#[test]
fn streamed_render_png_equals_the_one_shot_png() {
    let dir = common::temp_dir("render-memory-png");
    for (scene, extra) in
        [("plant2", vec!["--look", "solid", "--point-radius", "1"]), ("julia", vec!["--mode", "average"])]
    {
        let out = dir.join(format!("{scene}.png"));
        let path = common::scene_path(scene);
        let mut args =
            vec!["render", s(&path), "--width", "150", "--height", "110", "--points", "400000", "--seed", "9"];
        args.extend(extra.iter().copied());
        args.extend(["-o", s(&out)]);
        nlifs(&args, 0);
        // The same still through the library's one-shot path.
        let scene_data = common::load_scene(scene);
        let mut settings = scene_data.render.clone();
        (settings.width, settings.height, settings.points, settings.seed) = (150, 110, 400_000, 9);
        if scene == "julia" {
            settings.mode = SplatMode::Average;
        }
        if scene == "plant2" {
            settings.look = Some(nlifs::scene::spec::Look::Solid);
        }
        // The PNG's scene names the look the command line set (so that parts merge in it).
        let provenance = nlifs::output::Provenance::for_render(&scene_data, 0.0, &settings);
        let shot = Shot::prepare(&scene_data, 0.0, &settings, Framing::Fit, None).unwrap();
        let radius = if scene == "plant2" { 1 } else { 0 };
        let shot = shot.clone().with_style(nlifs::resolve::ResolveStyle { point_radius_px: radius, ..shot.style });
        let r = nlifs::render::render_cpu(&shot, &|_, _| {});
        let expected = dir.join(format!("{scene}-expected.png"));
        nlifs::output::png::save_rgb8(&expected, &r.image, Some(&provenance)).unwrap();
        assert!(std::fs::read(&out).unwrap() == std::fs::read(&expected).unwrap(), "{scene}: streamed PNG differs");
    }
}

/// `export points` streams: its PLY and GLB are the bytes of the in-memory writers (the GLB's
/// reference below is the writer as it was before streaming) on the points collected at once.
#[test]
fn streamed_point_export_equals_the_in_memory_bytes() {
    let dir = common::temp_dir("render-memory-export");
    let scene = common::scene_path("plant2");
    let points = 3 * 262_144 + 777;
    let (ply, glb) = (dir.join("p.ply"), dir.join("p.glb"));
    for out in [&ply, &glb] {
        nlifs(&["export", "points", s(&scene), "-o", s(out), "--points", &points.to_string(), "--seed", "4"], 0);
    }
    let scene_data = common::load_scene("plant2");
    let settings = RenderSettings { points, seed: 4, ..scene_data.render_at(0.0) };
    let shot = Shot::prepare(&scene_data, 0.0, &settings, Framing::Scene, None).unwrap();
    let mut all = CollectSink::default();
    for c in 0..shot.plan.chunks() {
        chaos_game::run_chunk(&shot.compiled, 4, shot.stream, c, shot.plan.steps(c), &mut all);
    }
    let pts = &all.points[..points as usize];
    let colors: Vec<[f32; 3]> =
        all.functions[..points as usize].iter().map(|&f| shot.compiled.colors[f as usize]).collect();
    let mut expected = Vec::new();
    nlifs::export::write_ply(&mut expected, pts, &colors).unwrap();
    assert!(std::fs::read(&ply).unwrap() == expected, "PLY differs");
    let mut expected = Vec::new();
    glb_points_before_streaming(&mut expected, pts, &colors).unwrap();
    assert!(std::fs::read(&glb).unwrap() == expected, "GLB differs");
}

/// `nlifs::export::write_glb_points` as it was when it held all points (the reference).
fn glb_points_before_streaming(w: &mut Vec<u8>, points: &[Vec3], colors: &[[f32; 3]]) -> std::io::Result<()> {
    let n = points.len();
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut bin = Vec::with_capacity(n * 16);
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
        for v in p.to_array() {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    if n == 0 {
        lo = Vec3::ZERO;
        hi = Vec3::ZERO;
    }
    let color_offset = bin.len();
    for c in colors {
        for v in c {
            bin.push(nlifs::color::linear_to_unorm8(*v));
        }
        bin.push(255);
    }
    let json = serde_json::json!({
        "asset": { "version": "2.0", "generator": "nlifs" },
        "scene": 0,
        "scenes": [ { "nodes": [0] } ],
        "nodes": [ { "mesh": 0, "name": "attractor" } ],
        "meshes": [ { "name": "attractor", "primitives": [ {
            "attributes": { "POSITION": 0, "COLOR_0": 1 },
            "mode": 0
        } ] } ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
              "min": lo.to_array(), "max": hi.to_array() },
            { "bufferView": 1, "componentType": 5121, "normalized": true, "count": n, "type": "VEC4" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": color_offset, "target": 34962 },
            { "buffer": 0, "byteOffset": color_offset, "byteLength": bin.len() - color_offset, "target": 34962 }
        ],
        "buffers": [ { "byteLength": bin.len() } ]
    });
    let mut json_bytes = serde_json::to_vec(&json)?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let bin_padded = bin.len().div_ceil(4) * 4;
    let total = (12 + 8 + json_bytes.len() + 8 + bin_padded) as u32;
    w.extend_from_slice(b"glTF");
    w.extend_from_slice(&2u32.to_le_bytes());
    w.extend_from_slice(&total.to_le_bytes());
    w.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    w.extend_from_slice(b"JSON");
    w.extend_from_slice(&json_bytes);
    w.extend_from_slice(&(bin_padded as u32).to_le_bytes());
    w.extend_from_slice(b"BIN\0");
    w.extend_from_slice(&bin);
    w.extend_from_slice(&vec![0u8; bin_padded - bin.len()]);
    Ok(())
}

/// The solid look's EXR has the shading normal as `N.x N.y N.z`: unit vectors facing the
/// viewer (z > 0) where a point lies, 0 where none does; `--layers` picks layers, and a layer
/// the mode lacks is refused before anything is written.
#[test]
fn exr_normal_layer_and_layer_choice() {
    let dir = common::temp_dir("render-memory-exr");
    let scene = common::scene_path("plant2");
    let base = ["render", s(&scene), "--width", "96", "--height", "72", "--points", "300000"];
    let solid = dir.join("solid.exr");
    nlifs(&[&base[..], &["--look", "solid", "-o", s(&solid)]].concat(), 0);
    let (names, _) = nlifs::output::exr::channels(&solid).unwrap();
    assert_eq!(names, ["A", "B", "G", "N.x", "N.y", "N.z", "R", "Z", "id"]);
    let image = exr::prelude::read_all_flat_layers_from_file(&solid).unwrap();
    let layer = &image.layer_data[0];
    let channel = |name: &str| -> Vec<f32> {
        let c = layer.channel_data.list.iter().find(|c| c.name.to_string() == name).unwrap();
        c.sample_data.values_as_f32().collect()
    };
    let (nx, ny, nz, z) = (channel("N.x"), channel("N.y"), channel("N.z"), channel("Z"));
    let mut lit = 0;
    for i in 0..z.len() {
        let length = (nx[i] * nx[i] + ny[i] * ny[i] + nz[i] * nz[i]).sqrt();
        if z[i].is_finite() {
            assert!((length - 1.0).abs() < 1e-4 && nz[i] > 0.0, "pixel {i}: ({}, {}, {})", nx[i], ny[i], nz[i]);
            lit += 1;
        } else {
            assert_eq!(length, 0.0, "empty pixel {i}");
        }
    }
    assert!(lit > 500, "{lit} pixels with a point");

    let picked = dir.join("picked.exr");
    nlifs(&[&base[..], &["--look", "solid", "--layers", "N", "-o", s(&picked)]].concat(), 0);
    assert_eq!(nlifs::output::exr::channels(&picked).unwrap().0, ["A", "B", "G", "N.x", "N.y", "N.z", "R"]);

    // Layers the mode does not have, an unknown layer, --layers on a PNG: exit 2, no file.
    let bad = dir.join("bad.exr");
    for (extra, says) in [
        (vec!["--layers", "count"], "closest mode with this look has no `count` layer"),
        (vec!["--look", "paper", "--layers", "Z,N"], "no `N` layer"),
        (vec!["--mode", "density", "--layers", "Z"], "density mode has no `Z` layer"),
        (vec!["--layers", "depth"], "`depth` is not a layer"),
    ] {
        let stderr = nlifs(&[&base[..], &extra[..], &["-o", s(&bad)]].concat(), 2);
        assert!(stderr.contains(says), "{extra:?}: {stderr}");
    }
    let png = dir.join("bad.png");
    let stderr = nlifs(&[&base[..], &["--layers", "Z", "-o", s(&png)]].concat(), 2);
    assert!(stderr.contains("--layers applies to exr"), "{stderr}");
    assert!(!bad.exists() && !png.exists(), "a refused render wrote a file");
}
