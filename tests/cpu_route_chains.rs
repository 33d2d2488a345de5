//! The live view's CPU route keeps its points across frames (`src/live/cpu_source.rs`), as the
//! GPU route does. No GPU needed: the CPU point source is driven directly.
//!
//! 1. Continuing chains ([`continue_chunk`]) makes exactly the points of [`run_chunk`] on every
//!    kernel path, in one call or split over two.
//! 2. The chains persist across an edit: the same points before the next frame, which then
//!    continues them (settle steps unsplatted) into exactly the uploaded accumulation.
//! 3. Chains that leave the finite floats are restarted: new streams of that frame, the
//!    transient run at once.
//! 4. After an edit and convergence, the density of the persistent chains matches the
//!    fresh-orbit route's (new orbits every frame, `run_chunk`) within 6 standard deviations.

mod common;

use common::{Density, assert_densities_agree, coarse_density};
use nlifs::chaos_game::{self, ChunkChains, CollectSink, CompiledIfs, ORBITS_PER_CHUNK, continue_chunk, run_chunk};
use nlifs::live::cpu_source::{CpuChaosGame, chain_bound, frame_layout};
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::{Framebuffer, SplatView};

/// A scene from `scenes/` with `replace` applied to its text (first occurrence).
fn scene_with(name: &str, replace: Option<(&str, &str)>) -> Scene {
    let path = common::scene_path(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    if let Some((from, to)) = replace {
        assert!(text.contains(from), "{name} has no {from}");
        text = text.replacen(from, to, 1);
    }
    Scene::parse(&text, &path.display().to_string()).unwrap()
}

/// plant2, and plant2 with one grid point of f1 (the stem) moved by `dx` along x (an edit).
fn plant2_and_edit(dx: f64) -> (Scene, CompiledIfs, CompiledIfs) {
    let scene = scene_with("plant2", None);
    let moved = format!("[{}, -13.33, -0.1]", 0.9 + dx);
    let edited = scene_with("plant2", Some(("[0.9, -13.33, -0.1]", &moved)));
    let a = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let b = CompiledIfs::new(&edited.at(0.0)).unwrap();
    assert_ne!(a, b);
    (scene, a, b)
}

fn view_of(scene: &Scene, ifs: &CompiledIfs, mode: SplatMode, width: u32, height: u32) -> SplatView {
    let bounds = chaos_game::attractor_bounds(ifs, 1);
    let camera = scene.camera_for(bounds);
    SplatView::new(&camera, width, height, bounds, mode, 0.0, [0.0; 3])
}

fn points(sink: &CollectSink) -> Vec<[u32; 3]> {
    sink.points.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

#[test]
fn continuing_chains_makes_the_points_of_run_chunk() {
    // plant2 takes the vector or lane kernel, the adaptive twisting the general path.
    let twisting = {
        let path = common::scene_path("twisting");
        let text =
            std::fs::read_to_string(&path).unwrap().replacen("\n[grid]", "\nprobabilities = \"adaptive\"\n\n[grid]", 1);
        Scene::parse(&text, &path.display().to_string()).unwrap()
    };
    for (name, scene) in [("plant2", scene_with("plant2", None)), ("twisting adaptive", twisting)] {
        let ifs = CompiledIfs::new(&scene.at(0.0)).unwrap();
        let (seed, frame, chunk) = (3, 7, 5);
        let mut expected = CollectSink::default();
        run_chunk(&ifs, seed, frame, chunk, 40, &mut expected);
        // One call.
        let mut chains = ChunkChains::start(&ifs, seed, frame, chunk);
        let mut one = CollectSink::default();
        continue_chunk(&ifs, &mut chains, ifs.transient, 40, &mut one);
        assert_eq!(points(&one), points(&expected), "{name}: one call");
        assert_eq!(one.functions, expected.functions, "{name}: one call");
        // Two calls of 24 and 16 steps; the chains end where the single run's orbits end.
        let mut split = ChunkChains::start(&ifs, seed, frame, chunk);
        let mut two = CollectSink::default();
        continue_chunk(&ifs, &mut split, ifs.transient, 24, &mut two);
        continue_chunk(&ifs, &mut split, 0, 16, &mut two);
        assert_eq!(points(&two), points(&expected), "{name}: two calls");
        assert_eq!(split, chains, "{name}: chain state after the same steps");
        // The last batch row holds each lane's final position.
        let last = &expected.points[expected.points.len() - ORBITS_PER_CHUNK..];
        for (k, p) in last.iter().enumerate() {
            assert_eq!(chains.pos[k].to_array(), p.to_array(), "{name}: lane {k}");
        }
    }
}

#[test]
fn chains_persist_across_an_edit() {
    let (scene, ifs, edited) = plant2_and_edit(3.0);
    let (seed, points_per_frame, settle) = (5u32, 1u64 << 16, 8u32);
    let view = view_of(&scene, &ifs, SplatMode::Closest, 96, 64);
    let mut cpu = CpuChaosGame::default();
    cpu.set_ifs(&ifs, true, settle);
    cpu.clear(&view);
    for frame in 0..2 {
        cpu.advance(seed, frame, points_per_frame);
    }
    let before = cpu.chains().to_vec();
    let (chunks, steps) = frame_layout(points_per_frame, rayon::current_num_threads());
    assert_eq!(before.len(), chunks as usize);
    assert_eq!(cpu.restarted_chains(), 0);
    // The edit: same points until the next frame, whatever else happens (the accumulation is
    // cleared for a new view).
    cpu.set_ifs(&edited, false, settle);
    cpu.clear(&view);
    assert_eq!(cpu.chains(), &before[..], "the chains moved on an edit");
    // The next frame continues them under the edited IFS, settle steps first: the oracle is
    // every chunk continued one by one into one framebuffer.
    let splats = cpu.advance(seed, 2, points_per_frame);
    assert_eq!(splats, chunks as u64 * ORBITS_PER_CHUNK as u64 * steps as u64);
    let mut expected = Framebuffer::new(view, edited.colors.clone());
    let mut oracle = before.clone();
    for chains in &mut oracle {
        continue_chunk(&edited, chains, settle, steps, &mut expected);
    }
    assert_eq!(cpu.chains(), &oracle[..], "chains after the frame following the edit");
    assert_eq!(cpu.merged(), &expected.closest[..], "accumulation of the frame following the edit");
    // A new scene starts them afresh: chunk c as run_chunk starts chunk c of that frame.
    cpu.set_ifs(&ifs, true, settle);
    cpu.clear(&view);
    cpu.advance(seed, 3, points_per_frame);
    let mut fresh = ChunkChains::start(&ifs, seed, 3, 0);
    continue_chunk(&ifs, &mut fresh, ifs.transient, steps, &mut CollectSink::default());
    assert_eq!(cpu.chains()[0], fresh, "chunk 0 after a restart");
}

#[test]
fn chains_that_leave_the_finite_floats_restart() {
    // Expanding affine maps (x ↦ 2x + b): every orbit overflows f32 within a frame's steps.
    let scene = scene_with("sierpinski", None);
    let text =
        std::fs::read_to_string(common::scene_path("sierpinski")).unwrap().replace("0.5, 0], [0, 0.5", "2, 0], [0, 2");
    let diverging = Scene::parse(&text, "diverging.toml").unwrap();
    let mut ifs = CompiledIfs::new(&diverging.at(0.0)).unwrap();
    // A short transient keeps a restarted orbit inside the bound.
    ifs.transient = 4;
    let view = view_of(&scene, &CompiledIfs::new(&scene.at(0.0)).unwrap(), SplatMode::Density, 64, 64);
    let (seed, points_per_frame) = (11u32, 1u64 << 15);
    // A frame's steps (over 100) take every orbit past the bound (2^20 times the domain).
    let (chunks, steps) = frame_layout(points_per_frame, rayon::current_num_threads());
    assert!(steps >= 100, "{steps} steps a frame: too few to diverge");
    let mut cpu = CpuChaosGame::default();
    cpu.set_ifs(&ifs, true, 8);
    cpu.clear(&view);
    let bound = chain_bound(&ifs);
    for frame in 0..2u32 {
        cpu.advance(seed, frame, points_per_frame);
        assert_eq!(cpu.restarted_chains(), chunks as u64 * ORBITS_PER_CHUNK as u64, "frame {frame}");
        for (c, chains) in cpu.chains().iter().enumerate() {
            let mut expected = ChunkChains::start(&ifs, seed, frame, c as u32);
            continue_chunk(&ifs, &mut expected, ifs.transient, 0, &mut CollectSink::default());
            assert_eq!(chains, &expected, "frame {frame} chunk {c}: restarted as a fresh chunk");
            assert!(chains.pos.iter().all(|p| p.is_finite() && p.abs().max_element() <= bound));
        }
    }
    // A contractive IFS keeps them all.
    let sierpinski = CompiledIfs::new(&scene.at(0.0)).unwrap();
    cpu.set_ifs(&sierpinski, false, 8);
    cpu.clear(&view);
    cpu.advance(seed, 2, points_per_frame);
    assert_eq!(cpu.restarted_chains(), 0);
}

#[test]
fn converged_density_matches_the_fresh_orbit_route() {
    let (scene, ifs, edited) = plant2_and_edit(10.0);
    let (width, height, cells) = (160u32, 120u32, (16usize, 12usize));
    let view = view_of(&scene, &edited, SplatMode::Density, width, height);
    let (seed, points_per_frame, frames) = (5u32, 1u64 << 22, 6u32);
    let workers = rayon::current_num_threads();
    let (chunks, steps) = frame_layout(points_per_frame, workers);
    // Persistent chains: converged on plant2, then edited; frames after the edit accumulate.
    let mut cpu = CpuChaosGame::default();
    cpu.set_ifs(&ifs, true, 8);
    cpu.clear(&view);
    for frame in 0..3 {
        cpu.advance(seed, frame, points_per_frame);
    }
    cpu.set_ifs(&edited, false, 8);
    cpu.clear(&view);
    let mut n_chains = 0;
    for frame in 3..3 + frames {
        n_chains += cpu.advance(seed, frame, points_per_frame);
    }
    let chain_counts: Vec<u32> = cpu.merged().chunks(4).map(|a| a[3]).collect();
    // The fresh-orbit route: new orbits, each from the domain past its transient; short ones
    // (`fresh_k` steps), so that the chains' correlation dominates the tolerance.
    let fresh_k = 128;
    let mut fresh = Framebuffer::new(view, edited.colors.clone());
    for chunk in 0..2 * n_chains as u32 / (ORBITS_PER_CHUNK * fresh_k) as u32 {
        run_chunk(&edited, seed + 1, 0, chunk, fresh_k, &mut fresh);
    }
    let fresh_counts: Vec<u32> = fresh.accum.iter().map(|a| a[3]).collect();
    let total = |c: &[u32]| c.iter().map(|&n| n as f64).sum::<f64>();
    let (n_on_chains, n_on_fresh) = (total(&chain_counts), total(&fresh_counts));
    assert!(n_on_chains > 0.5 * n_chains as f64, "{n_on_chains} of {n_chains} points on screen");
    let pc = coarse_density(&chain_counts, width as usize, height as usize, cells);
    let pf = coarse_density(&fresh_counts, width as usize, height as usize, cells);
    // Samples of one chain since the edit are correlated over all its frames' steps.
    let worst = assert_densities_agree(
        "persistent chains vs fresh orbits",
        &Density {
            label: "persistent chains",
            density: &pc,
            samples: n_on_chains,
            steps_per_orbit: (frames as usize * steps) as f64,
        },
        &Density { label: "fresh orbits", density: &pf, samples: n_on_fresh, steps_per_orbit: fresh_k as f64 },
        cells,
    );
    eprintln!("{chunks} chunks × {steps} steps a frame: worst |Δ|/tolerance {worst:.3}");
    // The bound is not vacuous: had the chains stayed on the unedited plant2, its density
    // would fail it (the same tolerance, the unedited density in place of the chains'): the
    // moved stem reaches a cell that the unedited plant2 leaves empty (about 2× the tolerance).
    let mut before = Framebuffer::new(view, ifs.colors.clone());
    for chunk in 0..n_chains as u32 / (ORBITS_PER_CHUNK * fresh_k) as u32 {
        run_chunk(&ifs, seed + 2, 0, chunk, fresh_k, &mut before);
    }
    let before_counts: Vec<u32> = before.accum.iter().map(|a| a[3]).collect();
    let pb = coarse_density(&before_counts, width as usize, height as usize, cells);
    let separation = pb.iter().zip(&pf).fold(0.0f64, |worst, (&b, &f)| {
        let p = 0.5 * (b + f);
        let sigma =
            (p * (1.0 - p) * ((frames as usize * steps) as f64 / n_on_chains + fresh_k as f64 / n_on_fresh)).sqrt();
        worst.max((b - f).abs() / (6.0 * sigma + 1e-12))
    });
    eprintln!("unedited vs edited: worst |Δ|/tolerance {separation:.3}");
    assert!(separation > 1.0, "the edit does not move the density beyond the bound: the test cannot fail");
}

/// The viewer cuts a costly frame to a time (`LiveView::bound_frame_time`): the same chains
/// advance fewer steps, so frames cut in four splat exactly what the whole frame splats, and no
/// chain restarts.
#[test]
fn a_frame_cut_short_advances_the_same_chains_fewer_steps() {
    let scene = scene_with("plant2", None);
    let ifs = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let (seed, points) = (9u32, 1u64 << 16);
    let (chunks, steps) = frame_layout(points, rayon::current_num_threads());
    let per_step = chunks as u64 * ORBITS_PER_CHUNK as u64;
    assert_eq!(steps % 4, 0, "the test cuts a frame of {steps} steps in four");
    for mode in [SplatMode::Closest, SplatMode::Density] {
        let view = view_of(&scene, &ifs, mode, 96, 64);
        let mut whole = CpuChaosGame::default();
        whole.set_ifs(&ifs, true, 8);
        whole.clear(&view);
        assert_eq!(whole.advance(seed, 0, points), per_step * steps as u64);

        let mut cut = CpuChaosGame::default();
        cut.set_ifs(&ifs, true, 8);
        cut.clear(&view);
        let quarter = per_step * steps as u64 / 4;
        for frame in 0..4 {
            // A bound between whole steps rounds down to them.
            assert_eq!(cut.advance_within(seed, frame, points, quarter + per_step / 2), quarter, "{mode:?}");
            assert_eq!(cut.chains().len(), chunks as usize);
        }
        assert_eq!(cut.restarted_chains(), 0);
        assert_eq!(cut.chains(), whole.chains(), "{mode:?}: the chains end where the whole frame's end");
        assert!(cut.merged() == whole.merged(), "{mode:?}: the cut frames splat what the whole frame splats");
        // At least one step of every chain, however small the bound.
        assert_eq!(cut.advance_within(seed, 4, points, 1), per_step);
    }
}
