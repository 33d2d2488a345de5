//! Xaos in scenes (`[[function]] xaos = [...]`, flam3's `chaos` rows): the next function is
//! drawn with the probabilities multiplied by the previous function's row.
//!
//! The IFS is Sierpiński's triangle (w1 at the origin, w2 right, w3 on top, equal
//! probabilities) with w1's row [0, 1, 1]: w1 never follows w1. Then no point of the attractor
//! lies in w1(w1(T)), the square [0, ¼)² (any point there has the address w1 w1 …), and the
//! chain of functions is a Markov chain whose stationary share of w1 is ¼ (π₁ = (π₂ + π₃) / 3).
//! On the CPU (`chaos_game/run.rs`, `SelectionTable::row_of`) and on the GPU
//! (`shaders/chaos_game.wgsl`, `XAOS`, the row kept in the stored point between dispatches),
//! in function and palette colour; the deterministic sets W^n (nesting view, ray tracer); the
//! scene's checks and its round trip.

mod common;

use common::{assert_gpu_density_matches_cpu, gpu};
use nlifs::chaos_game::{self, CollectSink, CompiledIfs, ORBITS_PER_CHUNK};
use nlifs::gpu::chaos_game::GpuChaosGame;
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::SplatView;

/// Sierpiński's triangle with `extra` after each function's lines (by index) and `head` in
/// the scene's first lines.
fn sierpinski(head: &str, extra: [&str; 3]) -> String {
    let mut text = format!("version = 1\n{head}\n[grid]\nx = [0, 1]\ny = [0, 1]\n");
    for ((ox, oy), extra) in [(0.0, 0.0), (0.5, 0.0), (0.25, 0.5)].into_iter().zip(extra) {
        text += &format!(
            "\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [{ox}, {oy}]\n{extra}\n"
        );
    }
    text
}

const NO_W1_AFTER_W1: [&str; 3] = ["xaos = [0, 1, 1]", "", ""];

fn compiled(text: &str) -> (Scene, CompiledIfs) {
    let scene = Scene::parse(text, "xaos.toml").unwrap_or_else(|e| panic!("{text}\n{e}"));
    let compiled = CompiledIfs::new(&scene.at(0.0)).expect("compiled");
    (scene, compiled)
}

/// In w1(w1(T)) = [0, ¼)², with a margin for the edges the square shares with w1 w2 and w1 w3.
fn in_forbidden_square(x: f32, y: f32) -> bool {
    x < 0.249 && y < 0.249
}

#[test]
fn the_cpu_never_draws_a_next_function_of_multiplier_zero() {
    for (extra, forbidden) in [(NO_W1_AFTER_W1, true), (["", "", ""], false)] {
        let (_, compiled) = compiled(&sierpinski("", extra));
        assert_eq!(compiled.selection.xaos, forbidden);
        let mut sink = CollectSink::default();
        let (chunks, steps) = (8u32, 4096usize);
        for chunk in 0..chunks {
            chaos_game::run_chunk(&compiled, 5, 0, chunk, steps, &mut sink);
        }
        // The points of a chunk are step by step, each step all its orbits.
        let per_chunk = ORBITS_PER_CHUNK * steps;
        let mut repeats = 0;
        for c in 0..chunks as usize {
            let f = &sink.functions[c * per_chunk..][..per_chunk];
            repeats += (ORBITS_PER_CHUNK..per_chunk).filter(|&i| f[i] == 0 && f[i - ORBITS_PER_CHUNK] == 0).count();
        }
        let share = sink.functions.iter().filter(|&&f| f == 0).count() as f64 / sink.functions.len() as f64;
        let inside = sink.points.iter().filter(|p| in_forbidden_square(p.x, p.y)).count();
        eprintln!("xaos {forbidden}: w1 after w1 {repeats} times, w1's share {share:.4}, {inside} points in [0, ¼)²");
        if forbidden {
            assert_eq!(repeats, 0, "w1 followed w1");
            assert_eq!(inside, 0, "points in w1(w1(T))");
            // 2.1 M steps of a chain that forgets in a few steps: σ ≈ 0.0005.
            assert!((share - 0.25).abs() < 0.005, "w1's share {share}, not ¼");
        } else {
            assert!(repeats > 100_000 && inside > 100_000, "without xaos w1 follows w1 a ninth of the time");
            assert!((share - 1.0 / 3.0).abs() < 0.005, "w1's share {share}, not ⅓");
        }
    }
}

/// A row whose multipliers leave nothing to go to is drawn as without xaos (flam3 refuses
/// such a flame; nlifs draws it by the probabilities alone), and disabled functions are
/// left out of the rows.
#[test]
fn a_row_of_zeros_draws_by_the_probabilities_and_disabled_functions_are_left_out() {
    let (_, zeros) = compiled(&sierpinski("", ["xaos = [0, 0, 0]", "xaos = [0, 1, 1]", ""]));
    let n = 3;
    let row = |t: &CompiledIfs, r: usize| t.selection.thresholds[r * n..r * n + n].to_vec();
    assert_eq!(row(&zeros, 1), row(&zeros, 0), "after w1: the probabilities alone");
    assert_eq!(row(&zeros, 2), vec![0, 1 << 23, 1 << 24], "after w2: w2 or w3, half each");
    let (_, disabled) = compiled(&sierpinski("", ["xaos = [0, 1, 1]", "enabled = false", ""]));
    assert_eq!(disabled.selection.function_count, 2);
    // Compiled functions w1 and w3: after w1 only w3.
    assert_eq!(disabled.selection.thresholds[2..4], [0, 1 << 24]);
}

#[test]
fn bad_xaos_is_named_with_its_function() {
    let cases = [
        (sierpinski("", ["xaos = [1, 1, 1, 1]", "", ""]), "function[0].xaos", "has 4 entries; the scene has 3"),
        (sierpinski("", ["", "xaos = [1, -1]", ""]), "function[1].xaos", "-1 is not a number ≥ 0"),
        (sierpinski("", ["", "", "xaos = [1, nan]"]), "function[2].xaos", "NaN is not a number ≥ 0"),
        (sierpinski("probabilities = \"adaptive\"", NO_W1_AFTER_W1), "function[0].xaos", "adaptive"),
        (
            sierpinski("", ["", "", ""])
                + "[timeline]\nduration_secs = 1\n[[key]]\ntime_secs = 0\n[[key.function]]\nname = \"f1\"\nxaos = [0, 1, 1]\n",
            "xaos",
            "unknown field",
        ),
    ];
    for (text, field, why) in cases {
        let e = Scene::parse(&text, "bad.toml").expect_err(&text).to_string();
        assert!(e.contains("bad.toml") && e.contains(field) && e.contains(why), "{text}\n→ {e}");
    }
}

#[test]
fn xaos_survives_a_round_trip_through_the_scene_file() {
    let (scene, _) = compiled(&sierpinski("", ["xaos = [0, 1, 1]", "xaos = [0.5, 2]", ""]));
    assert_eq!(scene.functions[0].xaos, [0.0, 1.0, 1.0]);
    assert_eq!(scene.functions[1].xaos, [0.5, 2.0]);
    assert!(scene.functions[2].xaos.is_empty());
    let text = scene.to_toml();
    assert!(text.contains("xaos = [0.5, 2.0]"), "{text}");
    let again = Scene::parse(&text, "again.toml").unwrap_or_else(|e| panic!("{text}\n{e}"));
    assert_eq!(again.functions, scene.functions);
}

/// The GPU draws the xaos attractor as the CPU does: nothing in [0, ¼)² (checked pixel by
/// pixel), densities within the bound of `tests/gpu_vs_cpu.rs`, and in palette colour the mean
/// colour within 1 % of the CPU's (the colour coordinate shares the stored w with the row).
#[test]
fn the_gpu_draws_xaos_as_the_cpu() {
    let Some(ctx) = gpu() else { return };
    let (scene, plain) = compiled(&sierpinski("", NO_W1_AFTER_W1));
    let palette = nlifs::palette::Palette::builtin("ember").expect("a built-in palette");
    let colored = plain.clone().with_palette(vec![0.0, 0.5, 1.0], &palette);
    let (width, height, k, orbits) = (96u32, 96u32, 8u32, 1u32 << 16);
    let bounds = (glam::DVec3::new(0.0, 0.0, -0.1), glam::DVec3::new(1.0, 1.0, 0.1));
    let view = SplatView::new(&scene.camera_for(bounds), width, height, bounds, SplatMode::Density, 0.0, [0.0; 3]);
    let mut game = GpuChaosGame::new(&ctx.device, orbits, width, height);
    for (label, compiled) in [("function colour", &plain), ("palette colour", &colored)] {
        // The transient alone (nothing splatted), then `k` steps from the stored points (the
        // xaos row and colour coordinate read back from their w).
        let t = compiled.transient;
        let accum = common::gpu_accum(&ctx, &mut game, compiled, &view, &[(t, t, true), (k, 0, false)]);
        let counts: Vec<u32> = accum.iter().map(|a| a[3]).collect();
        // The pixels of [0, 0.24]²: those the CPU's splat of a fine lattice of it lights.
        let lattice: Vec<(f32, f32)> =
            (0..200).flat_map(|i| (0..200).map(move |j| (i as f32 * 0.0012, j as f32 * 0.0012))).collect();
        let (xs, ys): (Vec<f32>, Vec<f32>) = lattice.into_iter().unzip();
        let mut square = nlifs::splat::Framebuffer::new(view, compiled.colors.clone());
        let batch = chaos_game::PointBatch { x: &xs, y: &ys, z: &vec![0.0; xs.len()], functions: &vec![0; xs.len()] };
        chaos_game::PointSink::consume(&mut square, batch);
        let inside_px: Vec<bool> = square.accum.iter().map(|a| a[3] > 0).collect();
        let square_px = inside_px.iter().filter(|&&b| b).count();
        let in_square: u64 = counts.iter().zip(&inside_px).filter(|(_, b)| **b).map(|(&c, _)| c as u64).sum();
        eprintln!("{label}: {in_square} GPU points on the {square_px} pixels of [0, 0.24]²");
        assert!(square_px > 100, "the square covers pixels: {square_px}");
        assert_eq!(in_square, 0, "{label}: the GPU drew points where w1 w1 would put them");
        let found = assert_gpu_density_matches_cpu(label, "GPU", &counts, compiled, view, (orbits, k), (12, 12));
        assert!(found.gpu_samples > 0.99 * (orbits * k) as f64, "every step drawn: {}", found.gpu_samples);
        if compiled.color_coords.is_some() {
            let mean = |accum: &[[u32; 4]]| {
                let n: f64 = accum.iter().map(|a| a[3] as f64).sum();
                [0, 1, 2].map(|c| accum.iter().map(|a| a[c] as f64).sum::<f64>() / n)
            };
            let mut fb = nlifs::splat::Framebuffer::new(view, compiled.colors.clone());
            for c in 0..orbits / ORBITS_PER_CHUNK as u32 {
                chaos_game::run_chunk(compiled, 77, 0, c, k as usize, &mut fb);
            }
            let (gpu, cpu) = (mean(&accum), mean(&fb.accum));
            eprintln!("mean colour sums: GPU {gpu:?}, CPU {cpu:?}");
            for c in 0..3 {
                assert!((gpu[c] - cpu[c]).abs() <= 0.01 * cpu[c].max(1.0), "channel {c}: GPU {gpu:?}, CPU {cpu:?}");
            }
        }
    }
}

/// Unequal probabilities and multipliers other than 0 and 1 (the fidelity test's "xaos"
/// flame as affine maps): the shares of the functions are the stationary distribution of the
/// chain whose row i is p_j · xaos_ij normalized.
#[test]
fn the_shares_are_the_chains_stationary_distribution() {
    let text = sierpinski(
        "probabilities = \"explicit\"",
        [
            "probability = 0.5\nxaos = [0, 1, 1]",
            "probability = 0.3\nxaos = [1, 0, 3]",
            "probability = 0.2\nxaos = [2, 1, 0]",
        ],
    );
    let (scene, compiled) = compiled(&text);
    let ifs = scene.at(0.0);
    let rows = ifs.xaos_rows();
    let pi = ifs.long_run_shares();
    // Stationary: π P = π.
    for j in 0..3 {
        let flow: f64 = (0..3).map(|i| pi[i] * rows[i][j]).sum();
        assert!((flow - pi[j]).abs() < 1e-9, "π P = π at {j}: {flow} against {}", pi[j]);
    }
    let mut sink = CollectSink::default();
    for chunk in 0..8 {
        chaos_game::run_chunk(&compiled, 9, 0, chunk, 4096, &mut sink);
    }
    for (j, expected) in pi.iter().enumerate() {
        let share = sink.functions.iter().filter(|&&f| f as usize == j).count() as f64 / sink.functions.len() as f64;
        eprintln!("function {j}: share {share:.4}, stationary {expected:.4}");
        assert!((share - expected).abs() < 0.005, "function {j}: share {share}, stationary {expected}");
    }
    // `nlifs info` gives them beside the probabilities.
    let dir = common::temp_dir("xaos-info");
    let file = dir.join("xaos.toml");
    std::fs::write(&file, &text).unwrap();
    let out = common::run_nlifs(&["info", file.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && stdout.contains("xaos share"), "{stdout}");
    assert!(stdout.lines().any(|l| l.starts_with("f1 ") && l.ends_with(&format!("{:.4}", pi[0]))), "{stdout}");
}

/// The deterministic sets keep the compositions the chaos game applies: the nesting view's
/// W^k boxes and the ray tracer's W^n(A) leave out every word with w1 right after w1, and a
/// function that no function may precede leaves no copy (it is drawn only at an orbit's
/// start).
#[test]
fn the_deterministic_sets_keep_only_the_compositions_xaos_allows() {
    let (scene, _) = compiled(&sierpinski("", NO_W1_AFTER_W1));
    let ifs = scene.at(0.0);
    // Words w_a ∘ w_b ∘ w_c (c applied first) without w1 following w1.
    let allowed = |word: &[usize]| word.windows(2).all(|w| !(w[0] == 0 && w[1] == 0));
    let words = |n: u32| {
        let word = |k: usize| -> Vec<usize> { (0..n).map(|d| k / 3usize.pow(d) % 3).collect() };
        (0..3usize.pow(n)).filter(|&k| allowed(&word(k))).count()
    };
    let boxes = nlifs::model::nesting::nested_boxes(&ifs, 3).expect("W^3");
    assert_eq!(boxes.len(), words(3), "W^3: 27 words less those with w1 w1");
    let in_square = |p: glam::DVec3| p.x < 0.249 && p.y < 0.249;
    assert!(boxes.iter().all(|b| !b.faces.iter().flatten().all(|&p| in_square(p))), "a box inside w1(w1(T))");
    let h = nlifs::raytrace::build_fixed(&ifs, &nlifs::raytrace::Initial::Sphere, 5).expect("W^5");
    assert_eq!(h.leaf_count, words(5), "W^5(A): 243 words less those with w1 w1");
    let leaves: Vec<_> = h.leaf_spheres().collect();
    assert!(leaves.iter().all(|n| !(n.centre.x < 0.249 && n.centre.y < 0.249)), "a sphere in w1(w1(T))");
    let plain = compiled(&sierpinski("", ["", "", ""])).0.at(0.0);
    assert_eq!(nlifs::raytrace::build_fixed(&plain, &nlifs::raytrace::Initial::Sphere, 5).unwrap().leaf_count, 243);
    // Rows w1, w2, w3 all [1, 1, 0]: nothing goes to w3, so an orbit applies it at most at its
    // start and W^n(A) has no copy of it.
    let (scene, _) = compiled(&sierpinski("", ["xaos = [1, 1, 0]", "xaos = [1, 1, 0]", "xaos = [1, 1, 0]"]));
    let ifs = scene.at(0.0);
    assert_eq!(ifs.recurrent_functions(ifs.xaos_successors().as_deref()), [0, 1]);
    let h = nlifs::raytrace::build_fixed(&ifs, &nlifs::raytrace::Initial::Sphere, 4).expect("W^4");
    assert_eq!(h.leaf_count, 16, "W^4 of w1 and w2 alone");
    assert!(h.leaf_spheres().all(|n| n.function != 2));
}

/// Rows that make the chain periodic (w1 and w2 take turns) and leave w3 behind after the
/// start: the long-run shares are ½, ½ and 0, as the chaos game draws them.
#[test]
fn the_long_run_shares_settle_on_a_periodic_chain() {
    let (scene, compiled) = compiled(&sierpinski("", ["xaos = [0, 1, 0]", "xaos = [1, 0, 0]", ""]));
    let shares = scene.at(0.0).long_run_shares();
    assert!((shares[0] - 0.5).abs() < 1e-9 && (shares[1] - 0.5).abs() < 1e-9 && shares[2] < 1e-9, "{shares:?}");
    let mut sink = CollectSink::default();
    chaos_game::run_chunk(&compiled, 2, 0, 0, 4096, &mut sink);
    let w3 = sink.functions.iter().filter(|&&f| f == 2).count();
    assert_eq!(w3, 0, "w3 drawn after the transient");
}
