//! The GPU chaos game on flame functions (`shaders/variations.wgsl`) against its CPU twin
//! (`CompiledIfs::map_with_rng`, f64), on flames that cover every variation: groups of three
//! variations, one per flame function, each with parameters away from their defaults where the
//! default is 0 (a zero often makes a variation constant). Runs on any adapter (lavapipe in CI);
//! without one it skips loudly, unless NLIFS_REQUIRE_GPU=1.
//!
//! 1. One step from the start point: the same function chosen by the same random draw, and the
//!    f32 image close to the f64 one for nearly every thread (the rule is at the assertion); the
//!    colour coordinate stepped with the functions' colour speeds exactly as the CPU steps it.
//! 2. Normalized densities on a coarse grid agree within the bound of `tests/gpu_vs_cpu.rs`.
//! 3. An xform's opacity: the GPU draws a point with its plotted weight as the CPU does.
//! 4. A final xform: the GPU draws its images, in its colour, as the CPU does.

mod common;

use common::{assert_gpu_density_matches_cpu, gpu};
use glam::Vec3;
use nlifs::chaos_game::{self, CompiledIfs};
use nlifs::flame::variations::VARIATIONS;
use nlifs::gpu::GpuContext;
use nlifs::gpu::chaos_game::{FrameArgs, GpuChaosGame};
use nlifs::gpu::readback::read_buffer;
use nlifs::rng::Pcg32;
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::SplatView;

/// Variations per test flame (one flame function each).
const GROUP: usize = 3;

/// A parameter's value in the test flames: its default, or 0.4 + 0.15·j for the j-th parameter
/// when the default is 0.
fn param_value(default: f64, j: usize) -> f64 {
    if default == 0.0 { 0.4 + 0.15 * j as f64 } else { default }
}

/// The scene of variations `group` (indices into [`VARIATIONS`]): function i a contractive
/// rotation and offset (the offsets keep waves', popcorn's, rings' and fan's constants, made
/// of the coefs, away from 0) with variation i of weight 0.8 and, for the second function, a
/// post-affine and `pre_blur`; colour speeds 0.2, 0.5 and 0.9.
fn group_scene(group: &[usize]) -> Scene {
    let mut text = String::from("version = 1\n[grid]\nx = [-1.0, 1.0]\ny = [-1.0, 1.0]\n");
    for (i, &v) in group.iter().enumerate() {
        let info = &VARIATIONS[v];
        let angle = 0.7 + 1.9 * i as f64;
        let (s, c) = angle.sin_cos();
        let (e, f) = (0.35 * (i as f64 - 1.0) + 0.2, 0.3 - 0.25 * i as f64);
        let params: Vec<String> =
            info.params.iter().enumerate().map(|(j, (name, d))| format!("{name} = {}", param_value(*d, j))).collect();
        text += &format!(
            "[[function]]\nkind = \"flame\"\nprobability = {}\npalette_index = {}\ncolor_speed = {}\n\
             coefs = [{}, {}, {}, {}, {e}, {f}]\nvariations = {{ {} = 0.8{} }}\n",
            1.0 + i as f64,
            i as f64 / 2.0,
            [0.2, 0.5, 0.9][i % 3],
            0.6 * c,
            0.6 * s,
            -0.6 * s,
            0.6 * c,
            info.name,
            if i == 1 && info.name != "pre_blur" { ", pre_blur = 0.05" } else { "" },
        );
        if !params.is_empty() {
            text += &format!("params = {{ {} }}\n", params.join(", "));
        }
        if i == 1 {
            text += "post = [0.9, 0.1, -0.1, 0.9, 0.05, -0.05]\n";
        }
    }
    Scene::parse(&text, "group.toml").unwrap_or_else(|e| panic!("{text}\n{e}"))
}

/// Every variation, in groups of [`GROUP`].
fn groups() -> Vec<Vec<usize>> {
    (0..VARIATIONS.len()).collect::<Vec<_>>().chunks(GROUP).map(<[usize]>::to_vec).collect()
}

fn names(group: &[usize]) -> String {
    group.iter().map(|&v| VARIATIONS[v].name).collect::<Vec<_>>().join("+")
}

/// The points buffer after one GPU step of every thread from its start point.
fn gpu_first_step(ctx: &GpuContext, game: &mut GpuChaosGame, compiled: &CompiledIfs, seed: u32) -> Vec<[f32; 4]> {
    let bounds = (glam::DVec3::splat(-2.0), glam::DVec3::splat(2.0));
    let camera = nlifs::camera::OrbitCamera::framing(bounds, 2);
    let view = SplatView::new(&camera, 64, 48, bounds, SplatMode::Density, 0.0, [0.0; 3]);
    game.set_ifs(&ctx.device, &ctx.queue, compiled);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let args = FrameArgs { view: &view, seed, frame: 0, steps: 1, skip_steps: 0, restart: true, clear: true };
    game.encode(&ctx.device, &ctx.queue, &mut encoder, &args);
    ctx.queue.submit([encoder.finish()]);
    bytemuck::pod_collect_to_vec(&read_buffer(ctx, &game.points).unwrap())
}

#[test]
fn first_step_matches_the_cpu_for_every_variation() {
    let Some(ctx) = gpu() else { return };
    let n = 4096u32;
    let seed = 11u32;
    let mut game = GpuChaosGame::new(&ctx.device, n, 64, 48);
    let palette = nlifs::palette::Palette::builtin("ember").expect("a built-in palette");
    for group in groups() {
        let name = names(&group);
        let scene = group_scene(&group);
        let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
        assert!(compiled.has_flames());
        let gpu_points = gpu_first_step(&ctx, &mut game, &compiled, seed);
        // Per function: threads that chose it, and those whose image is close to the CPU's.
        let mut chosen = vec![0u32; group.len()];
        let mut close = vec![0u32; group.len()];
        for thread in 0..n {
            let mut rng = Pcg32::for_stream(seed, 0, thread);
            let t = Vec3::new(rng.next_f32(), rng.next_f32(), 0.0);
            let start = compiled.domain_lo + t * (compiled.domain_hi - compiled.domain_lo);
            let fi = compiled.selection.select(0, rng.next_u32());
            let (cpu, _) = compiled.map_with_rng(fi, start, &mut rng);
            let g = gpu_points[thread as usize];
            assert_eq!(
                g[3] as usize, fi,
                "{name}: thread {thread} chose function {} on the GPU, {fi} on the CPU",
                g[3]
            );
            chosen[fi] += 1;
            // Close: within 1e-3 of the CPU's point, relative to its size (at least 1). f32
            // holds 7 digits; a handful of operations keeps 5 or more where the variation is
            // well conditioned at the point.
            let gpu = Vec3::new(g[0], g[1], g[2]);
            let both_bad = !cpu.is_finite() && !gpu.is_finite();
            if both_bad || (gpu - cpu).length() <= 1e-3 * cpu.length().max(1.0) {
                close[fi] += 1;
            }
        }
        for (i, &v) in group.iter().enumerate() {
            // Nearly every thread: where a variation is ill conditioned (a sine of 10^10, a
            // pole, a branch decided by a value on its threshold) f32 and f64 part, on a few
            // points of the square at most; a wrong formula, constant or random draw misses on
            // most of them. The bound: at most 3 % of a function's threads apart.
            let fraction = close[i] as f64 / chosen[i].max(1) as f64;
            eprintln!("{:>16}: {:.4} of {} threads close", VARIATIONS[v].name, fraction, chosen[i]);
            assert!(chosen[i] > 200, "{name}: function {i} chosen by {} threads only", chosen[i]);
            assert!(
                fraction >= 0.97,
                "{name}: {} ({i}): {:.2} % of {} threads close to the CPU's image",
                VARIATIONS[v].name,
                100.0 * fraction,
                chosen[i]
            );
        }
        // Palette colour: the colour coordinate after one step, with the functions' speeds.
        let coords: Vec<f32> = (0..group.len()).map(|i| i as f32 / 2.0).collect();
        let colored = compiled.clone().with_palette(coords.clone(), &palette);
        let speeds = colored.color_speeds.clone().expect("the colour speeds differ from ½");
        let gpu_points = gpu_first_step(&ctx, &mut game, &colored, seed);
        for thread in 0..n {
            let mut rng = Pcg32::for_stream(seed, 0, thread);
            rng.next_f32();
            rng.next_f32();
            let fi = compiled.selection.select(0, rng.next_u32());
            let c = chaos_game::step_color_speed(chaos_game::C_START, coords[fi], speeds[fi]);
            // One rounding apart at most (the GPU may fuse the multiply-add).
            let g = gpu_points[thread as usize][3];
            assert!(
                (g - c).abs() <= 1e-6,
                "{name}: thread {thread}'s colour coordinate {g} on the GPU, {c} on the CPU"
            );
        }
    }
}

/// The GPU's hits per pixel of `view`: every orbit from its start point, the transient not
/// splatted, then `k` steps.
fn gpu_density_counts(
    ctx: &GpuContext,
    game: &mut GpuChaosGame,
    compiled: &CompiledIfs,
    view: &SplatView,
    k: u32,
) -> Vec<u32> {
    gpu_accum(ctx, game, compiled, view, k).iter().map(|a| a[3]).collect()
}

/// [`gpu_density_counts`]'s sums: r, g, b and the count per pixel, in one dispatch.
fn gpu_accum(
    ctx: &GpuContext,
    game: &mut GpuChaosGame,
    compiled: &CompiledIfs,
    view: &SplatView,
    k: u32,
) -> Vec<[u32; 4]> {
    common::gpu_accum(ctx, game, compiled, view, &[(compiled.transient + k, compiled.transient, true)])
}

/// Sierpiński's triangle as three flame functions of opacity 1, ½ and 0 (plotted weights 1,
/// 0.1 and 0): the GPU draws (1 + 0.1 + 0) / 3 of its steps, as the CPU does, and its density
/// agrees with the CPU's (the corner of opacity 0 empty on both).
#[test]
fn opacity_draws_as_on_the_cpu() {
    let Some(ctx) = gpu() else { return };
    let mut text = String::from("version = 1\n[grid]\nx = [-1.0, 1.0]\ny = [-1.0, 1.0]\n");
    for ((vx, vy), opacity) in [((-1.0, -1.0), 1.0), ((1.0, -1.0), 0.5), ((0.0, 1.0), 0.0)] {
        text += &format!(
            "[[function]]\nkind = \"flame\"\nprobability = 1\ncoefs = [0.5, 0, 0, 0.5, {}, {}]\n\
             variations = {{ linear = 1 }}\nopacity = {opacity}\n",
            0.5 * vx,
            0.5 * vy
        );
    }
    let scene = Scene::parse(&text, "opacity.toml").unwrap_or_else(|e| panic!("{text}\n{e}"));
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let (width, height, k, orbits) = (96u32, 72u32, 8u32, 1u32 << 16);
    let bounds = (glam::DVec3::new(-1.05, -1.05, -0.1), glam::DVec3::new(1.05, 1.05, 0.1));
    let view = SplatView::new(&scene.camera_for(bounds), width, height, bounds, SplatMode::Density, 0.0, [0.0; 3]);
    let mut game = GpuChaosGame::new(&ctx.device, orbits, width, height);
    let gpu_counts = gpu_density_counts(&ctx, &mut game, &compiled, &view, k);
    let found = assert_gpu_density_matches_cpu("opacity", "GPU", &gpu_counts, &compiled, view, (orbits, k), (12, 9));
    let expected = 1.1 / 3.0;
    for (side, samples) in [("GPU", found.gpu_samples), ("CPU", found.cpu_samples)] {
        let drawn = samples / (orbits as f64 * k as f64);
        eprintln!("{side}: {drawn:.4} of the steps drawn ({expected:.4} expected)");
        assert!((drawn - expected).abs() < 0.01, "the {side} drew {drawn:.4} of its steps, not {expected:.4}");
    }
}

/// Sierpiński's triangle of three flame functions with a final xform (swirl and linear, colour
/// coordinate 1 at speed 0.9, palette colour): the GPU draws the final xform's images where the
/// CPU draws them (densities within the bound) in its colour (the mean colour of every point
/// drawn within 1 % of the CPU's; the final's colour step moves it by far more). At opacity 1
/// and ½ (the final xform maps half the points; the others are drawn as they are, in the
/// orbit's colour).
#[test]
fn a_final_xform_draws_as_on_the_cpu() {
    let Some(ctx) = gpu() else { return };
    for opacity in [1.0, 0.5] {
        a_final_xform_of_opacity_draws_as_on_the_cpu(&ctx, opacity);
    }
}

fn a_final_xform_of_opacity_draws_as_on_the_cpu(ctx: &nlifs::gpu::GpuContext, opacity: f64) {
    let scene_text = |final_speed: f64| {
        let mut text = String::from("version = 1\n[grid]\nx = [-1.0, 1.0]\ny = [-1.0, 1.0]\n");
        for (vx, vy) in [(-1.0, -1.0), (1.0, -1.0), (0.0, 1.0)] {
            text += &format!(
                "[[function]]\nkind = \"flame\"\nprobability = 1\ncoefs = [0.5, 0, 0, 0.5, {}, {}]\n\
                 variations = {{ linear = 1 }}\n",
                0.5 * vx,
                0.5 * vy
            );
        }
        text + &format!(
            "[final]\npalette_index = 1\ncolor_speed = {final_speed}\ncoefs = [0.9, 0.2, -0.2, 0.9, 0.1, 0]\n\
             variations = {{ swirl = 0.5, linear = 0.5 }}\nopacity = {opacity}\n"
        )
    };
    let palette = nlifs::palette::Palette::builtin("ember").expect("a built-in palette");
    let compile = |final_speed: f64| {
        let text = scene_text(final_speed);
        let scene = Scene::parse(&text, "final.toml").unwrap_or_else(|e| panic!("{text}\n{e}"));
        let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap().with_palette(vec![0.0, 0.5, 1.0], &palette);
        assert!(compiled.has_final_xform());
        (scene, compiled)
    };
    let (scene, compiled) = compile(0.9);
    let (width, height, k, orbits) = (96u32, 72u32, 8u32, 1u32 << 16);
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let view = SplatView::new(&scene.camera_for(bounds), width, height, bounds, SplatMode::Density, 0.0, [0.0; 3]);
    let mut game = GpuChaosGame::new(&ctx.device, orbits, width, height);
    let accum = gpu_accum(ctx, &mut game, &compiled, &view, k);
    let counts: Vec<u32> = accum.iter().map(|a| a[3]).collect();
    let name = format!("final xform of opacity {opacity}");
    let found = assert_gpu_density_matches_cpu(&name, "GPU", &counts, &compiled, view, (orbits, k), (12, 9));
    assert!(found.gpu_samples > 0.99 * (orbits * k) as f64, "every step drawn: {}", found.gpu_samples);
    let mean_color = |accum: &[[u32; 4]]| {
        let n: f64 = accum.iter().map(|a| a[3] as f64).sum();
        [0, 1, 2].map(|c| accum.iter().map(|a| a[c] as f64).sum::<f64>() / n)
    };
    let cpu_mean = |compiled: &CompiledIfs| {
        let mut fb = nlifs::splat::Framebuffer::new(view, compiled.colors.clone());
        for c in 0..orbits / chaos_game::ORBITS_PER_CHUNK as u32 {
            chaos_game::run_chunk(compiled, 77, 0, c, k as usize, &mut fb);
        }
        mean_color(&fb.accum)
    };
    let (gpu, cpu, cpu_without_step) = (mean_color(&accum), cpu_mean(&compiled), cpu_mean(&compile(0.0).1));
    eprintln!(
        "opacity {opacity}: mean colour sums: GPU {gpu:?}, CPU {cpu:?}, CPU without the final's colour step {cpu_without_step:?}"
    );
    for c in 0..3 {
        assert!((gpu[c] - cpu[c]).abs() <= 0.01 * cpu[c].max(1.0), "channel {c}: GPU {gpu:?}, CPU {cpu:?}");
    }
    let moved = (0..3).map(|c| (cpu[c] - cpu_without_step[c]).abs() / cpu[c].max(1.0)).fold(0.0, f64::max);
    assert!(moved > 0.05, "the final's colour step moves the mean colour: {cpu:?} against {cpu_without_step:?}");
}

#[test]
fn densities_match_the_cpu_for_every_variation() {
    let Some(ctx) = gpu() else { return };
    let (width, height) = (96u32, 72u32);
    let cells = (12usize, 9usize);
    // Steps per orbit after the transient, on both sides (the bound's k).
    let k = 4u32;
    let orbits = 1u32 << 16;
    let mut game = GpuChaosGame::new(&ctx.device, orbits, width, height);
    let mut worst_overall = 0.0f64;
    for group in groups() {
        let name = names(&group);
        let scene = group_scene(&group);
        let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
        let bounds = chaos_game::attractor_bounds(&compiled, 1);
        let camera = scene.camera_for(bounds);
        let view = SplatView::new(&camera, width, height, bounds, SplatMode::Density, 0.0, [0.0; 3]);

        let gpu_counts = gpu_density_counts(&ctx, &mut game, &compiled, &view, k);

        // CPU: as many orbits of k steps after the same transient, another seed; within 6
        // standard deviations of the difference of two frequencies with variance ≤ k p (1 − p) / N
        // each.
        let found = assert_gpu_density_matches_cpu(
            &format!("flames {name}"),
            "GPU",
            &gpu_counts,
            &compiled,
            view,
            (orbits, k),
            cells,
        );
        eprintln!(
            "{name}: {} GPU / {} CPU samples, worst |Δ|/tolerance {:.3}",
            found.gpu_samples, found.cpu_samples, found.worst
        );
        worst_overall = worst_overall.max(found.worst);
    }
    eprintln!("worst |Δ|/tolerance over every group: {worst_overall:.3}");
}
