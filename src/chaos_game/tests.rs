//! Tests of the chaos game: the compiled kernel against the f64 model, every fast path bit for
//! bit against the reference map, whole chunks against plain reference orbits.

use glam::{DVec3, Vec3};

use super::run::{Path, run_chunk_on};
#[cfg(target_arch = "x86_64")]
use super::x86;
use super::*;
use crate::model::ProbabilityMode;
use crate::model::{AffineMap, Function, GridMap, Map, RectGrid};
use glam::DMat3;

fn warped_ifs() -> Ifs {
    let grid = RectGrid { axes: [vec![0.0, 0.3, 1.0], vec![0.0, 0.5, 0.8, 1.0], vec![0.0, 0.4, 1.0]] };
    let mut r = Pcg32::for_stream(9, 0, 0);
    let functions = (0..3)
        .map(|i| Function {
            name: format!("f{i}"),
            map: Map::Grid(GridMap::from_fn(grid.clone(), |p| {
                0.45 * p + DVec3::new(r.next_f32() as f64 * 0.5, r.next_f32() as f64 * 0.5, r.next_f32() as f64 * 0.5)
            })),
            color: [1.0; 3],
            weight: None,
            enabled: true,
            xaos: Vec::new(),
        })
        .chain(std::iter::once(Function {
            name: "affine".into(),
            map: Map::Affine(AffineMap { matrix: DMat3::from_diagonal(DVec3::splat(0.3)), offset: DVec3::splat(0.1) }),
            color: [1.0; 3],
            weight: None,
            enabled: true,
            xaos: Vec::new(),
        }))
        .collect();
    Ifs { domain: grid, functions, probability_mode: ProbabilityMode::Contractivity, final_xform: None }
}

/// The compiled f32 kernel agrees with the f64 model within f32 rounding of the
/// coordinates (relative 1e-6 of the domain size, with room for the ~20 operations).
#[test]
fn compiled_matches_model() {
    let ifs = warped_ifs();
    let c = CompiledIfs::new(&ifs).unwrap();
    let mut r = Pcg32::for_stream(3, 0, 0);
    for _ in 0..5000 {
        let p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.2 - 0.1;
        for fi in 0..4 {
            let want = ifs.eval(fi, p.as_dvec3());
            let got = c.map(fi, p).as_dvec3();
            assert!(got.distance(want) < 2e-5, "f{fi} at {p}: {got} vs {want}");
        }
    }
}

/// The CPU's binned cell search gives bit-identical results to the reference search that
/// the GPU mirrors, including points on and near cell faces and outside the grid.
#[test]
fn fast_map_is_bit_identical() {
    let ifs = warped_ifs();
    let c = CompiledIfs::new(&ifs).unwrap();
    let mut r = Pcg32::for_stream(4, 0, 0);
    let faces = [0.0f32, 0.3, 0.5, 0.8, 0.4, 1.0];
    for k in 0..20_000 {
        let mut p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.4 - 0.2;
        if k % 4 == 0 {
            // Exactly on a face, or one ulp either side.
            let f = faces[k / 4 % faces.len()];
            p.y = match k % 3 {
                0 => f,
                1 => f.next_up(),
                _ => f.next_down(),
            };
        }
        for fi in 0..4 {
            assert_eq!(c.map_fast(fi, p), c.map(fi, p), "f{fi} at {p:?}");
        }
    }
}

/// The lane kernel (the common case's fast path) is bit-identical to the reference map,
/// on and near cell faces and outside the grid, and is the path the warped IFS takes.
#[test]
fn lane_map_is_bit_identical() {
    // The warped IFS has several cells along every axis; its variant on a 1×2×1 grid
    // (as the paper's tapering, 1×3×1) takes the kernel specialized for y alone.
    // With 2 cells along y the IFS has 7 cells (every vector lookup applies), with 3 it has
    // 10 (the 16-entry lookups and the gathers), the warped IFS 37 (the gathers).
    for (ifs, multi) in [
        (warped_ifs(), [true; 3]),
        (y_only_ifs(&[0.0, 0.3, 1.0]), [false, true, false]),
        (y_only_ifs(&[0.0, 0.3, 0.8, 1.0]), [false, true, false]),
    ] {
        check_lane_map(&ifs, multi);
    }
}

/// The warped IFS with its grid maps on a 1×n×1 grid with y coordinates `ys`.
fn y_only_ifs(ys: &[f64]) -> Ifs {
    let mut y_only = warped_ifs();
    let grid = RectGrid { axes: [vec![0.0, 1.0], ys.to_vec(), vec![0.0, 1.0]] };
    for (i, f) in y_only.functions.iter_mut().enumerate().take(3) {
        let o = DVec3::new(0.1 * i as f64, 0.5, 0.2);
        f.map = Map::Grid(GridMap::from_fn(grid.clone(), |p| 0.4 * p + o + DVec3::new(0.0, 0.1 * p.x * p.y, 0.0)));
    }
    y_only.domain = grid;
    y_only
}

/// The vector kernel's lookups this CPU runs for `c` (none without AVX2 or off x86-64).
fn simd_paths(c: &CompiledIfs) -> Vec<Path> {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = &c.simd {
        return simd.supported_lookups().into_iter().map(Path::Simd).collect();
    }
    let _ = c;
    Vec::new()
}

fn check_lane_map(ifs: &Ifs, multi: [bool; 3]) {
    let c = CompiledIfs::new(ifs).unwrap();
    let lanes = c.lanes.as_ref().expect("the IFS takes the lane path");
    assert_eq!(lanes.multi, multi);
    let mut r = Pcg32::for_stream(4, 0, 1);
    let faces = [0.0f32, 0.3, 0.5, 0.8, 0.4, 1.0];
    let mut points = Vec::new();
    for k in 0..20_000 {
        let mut p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.4 - 0.2;
        if k % 2 == 0 {
            let f = faces[k / 2 % faces.len()];
            let g = match k % 3 {
                0 => f,
                1 => f.next_up(),
                _ => f.next_down(),
            };
            match k % 5 {
                0 => p.x = g,
                1 | 2 => p.y = g,
                _ => p.z = g,
            }
        }
        if k % 97 == 0 {
            p = Vec3::new(f32::NAN, 1e30, -1e30);
        }
        for fi in 0..4 {
            let got = Vec3::from(lanes.map_any(fi, p.into()));
            let want = c.map(fi, p);
            assert_eq!(got.to_array().map(f32::to_bits), want.to_array().map(f32::to_bits), "f{fi} at {p:?}");
        }
        points.push(p);
    }
    // The vector kernel, a vector of points at a time with mixed functions, every lookup.
    let paths = simd_paths(&c);
    #[cfg(target_arch = "x86_64")]
    if crate::simd::SimdLevel::detect().avx2() {
        assert!(paths.contains(&Path::Simd(x86::Lookup::Gather)), "{paths:?}");
    }
    for path in paths {
        #[cfg(target_arch = "x86_64")]
        if let Path::Simd(lookup) = path {
            let simd = c.simd.as_ref().unwrap();
            let fi: Vec<u32> = (0..points.len()).map(|i| ((i + i / 16) % 4) as u32).collect();
            let p: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
            let got = simd.map_points(lookup, &fi, &p);
            for i in 0..points.len() {
                let want = c.map(fi[i] as usize, points[i]);
                assert_eq!(
                    got[i].map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{lookup:?} f{} at {:?}",
                    fi[i],
                    points[i]
                );
            }
        }
        let _ = path;
    }
}

/// The lane kernel's bucketed selection equals the table's threshold count for every
/// r near each threshold and at random.
#[test]
fn lane_select_matches_table() {
    let c = CompiledIfs::new(&warped_ifs()).unwrap();
    let lanes = c.lanes.as_ref().unwrap();
    let mut r = Pcg32::for_stream(6, 0, 0);
    let mut rs: Vec<u32> = (0..100_000).map(|_| r.next_u32()).collect();
    for &t in &c.selection.thresholds {
        for d in -3i64..=3 {
            let r24 = (t as i64 + d).clamp(0, (1 << 24) - 1) as u32;
            rs.extend([r24 << 8, r24 << 8 | 0xff]);
        }
    }
    for &r in &rs {
        assert_eq!(lanes.select(r), c.selection.select(0, r), "r = {r:#x}");
    }
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = &c.simd {
        // Whole vectors: pad with a value already tested.
        rs.resize(rs.len().next_multiple_of(16), rs[0]);
        for got in simd.select_points(&rs) {
            for (&r, &fi) in rs.iter().zip(&got) {
                assert_eq!(fi as usize, c.selection.select(0, r), "r = {r:#x}");
            }
        }
    }
}

/// `run_chunk` against a plain oracle: lane k of chunk c draws from stream (seed, frame,
/// 64c + k), starts at a random domain point, selects with the table and maps with the
/// reference `map`; every point must be bit-identical, on the lane path (global
/// probabilities; the portable lane kernel and the vector kernel with each lookup the CPU
/// has) and on the general path (adaptive probabilities).
#[test]
fn run_chunk_matches_reference_orbits() {
    let cases = [
        (warped_ifs(), ProbabilityMode::Contractivity),
        (warped_ifs(), ProbabilityMode::Adaptive),
        (y_only_ifs(&[0.0, 0.3, 1.0]), ProbabilityMode::Contractivity),
        (y_only_ifs(&[0.0, 0.3, 0.8, 1.0]), ProbabilityMode::Contractivity),
    ];
    for (mut ifs, mode) in cases {
        ifs.probability_mode = mode;
        let c = CompiledIfs::new(&ifs).unwrap();
        assert_eq!(c.lanes.is_some(), mode == ProbabilityMode::Contractivity);
        // Palette colour: the same orbits, the points carrying the colour coordinate.
        let coords = (0..c.functions.len()).map(|i| [0.9, 0.15, 0.6, 0.35][i % 4]).collect();
        let colored = c.clone().with_palette(coords, &crate::palette::Palette::builtin("ember").unwrap());
        for path in [Path::Fastest, Path::Portable].into_iter().chain(simd_paths(&c)) {
            check_chunk(&c, path);
            check_chunk(&colored, path);
        }
    }
}

/// Palette colour on the live view's persistent chains: a chunk continued in two calls from
/// its start (skip = the transient, then the rest) makes exactly `run_chunk`'s points and
/// colour indices, on every path `continue_chunk` takes (the fastest), for lane and general
/// IFSs.
#[test]
fn continued_chunks_carry_the_colour_coordinate() {
    for mode in [ProbabilityMode::Contractivity, ProbabilityMode::Adaptive] {
        let mut ifs = warped_ifs();
        ifs.probability_mode = mode;
        let c = CompiledIfs::new(&ifs).unwrap();
        let c = c.with_palette(vec![0.0, 1.0, 0.25, 0.7], &crate::palette::Palette::builtin("moss").unwrap());
        let mut want = CollectSink::default();
        run_chunk(&c, 3, 1, 7, 50, &mut want);
        let mut chains = ChunkChains::start(&c, 3, 1, 7);
        let mut got = CollectSink::default();
        continue_chunk(&c, &mut chains, c.transient, 20, &mut got);
        continue_chunk(&c, &mut chains, 0, 30, &mut got);
        assert_eq!(got.functions, want.functions, "{mode:?}");
        assert_eq!(got.points, want.points, "{mode:?}");
    }
}

fn check_chunk(c: &CompiledIfs, path: Path) {
    let mode = (c.selection.cells, path);
    let (seed, frame, chunk, steps) = (11, 2, 5u32, 40);
    let mut got = CollectSink::default();
    run_chunk_on(c, path, seed, frame, chunk, steps, &mut got);
    let k_n = ORBITS_PER_CHUNK;
    let mut want = vec![Vec3::ZERO; k_n * steps];
    let mut want_fn = vec![0u8; k_n * steps];
    for k in 0..k_n {
        let mut rng = Pcg32::for_stream(seed, frame, chunk * k_n as u32 + k as u32);
        let mut p = c.start_point(&mut rng);
        // The colour coordinate, f64 here: every value (c + c_i) / 2 of f32s is exact in f64
        // and rounds to f32 as the kernel's f32 sum, then halves exactly.
        let mut color = C_START;
        for s in 0..c.transient as usize + steps {
            let fi = c.selection.select(c.selection.cell_of(p), rng.next_u32());
            p = c.map(fi, p);
            if let Some(coords) = &c.color_coords {
                color = ((color as f64 + coords[fi] as f64) as f32) * 0.5;
            }
            if s >= c.transient as usize {
                let row = s - c.transient as usize;
                want[row * k_n + k] = p;
                want_fn[row * k_n + k] =
                    if c.color_coords.is_some() { crate::palette::index_of(color) } else { fi as u8 };
            }
        }
    }
    assert_eq!(got.functions, want_fn, "{mode:?}");
    let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&got.points), bits(&want), "{mode:?}");
}

#[test]
fn grid_points_compile_exactly_enough() {
    let ifs = warped_ifs();
    let c = CompiledIfs::new(&ifs).unwrap();
    if let Map::Grid(g) = &ifs.functions[0].map {
        for (i, p) in g.grid.points().into_iter().enumerate() {
            assert!(c.map(0, p.as_vec3()).as_dvec3().distance(g.points[i]) < 1e-6);
        }
    }
}

#[test]
fn selection_follows_probabilities() {
    let probs = vec![vec![0.2, 0.5, 0.3]];
    let t = SelectionTable::from_probabilities([1, 1, 1], Vec3::ZERO, Vec3::ZERO, &probs);
    let mut r = Pcg32::for_stream(5, 0, 0);
    let n = 300_000;
    let mut counts = [0usize; 3];
    for _ in 0..n {
        counts[t.select(0, r.next_u32())] += 1;
    }
    for k in 0..3 {
        let p = probs[0][k];
        let sigma = (p * (1.0 - p) / n as f64).sqrt();
        // 5 standard deviations of a binomial proportion.
        assert!((counts[k] as f64 / n as f64 - p).abs() < 5.0 * sigma, "{counts:?}");
    }
}

#[test]
fn chunks_are_independent_of_threads() {
    let ifs = warped_ifs();
    let c = CompiledIfs::new(&ifs).unwrap();
    let run = || {
        run_parallel(
            &c,
            7,
            0,
            &ChunkPlan::new(600_000).unwrap(),
            CollectSink::default,
            |mut a, b| {
                a.points.extend(b.points);
                a
            },
            || {},
        )
        .points
        .len()
    };
    assert_eq!(run(), run());
    let mut a = CollectSink::default();
    let mut b = CollectSink::default();
    run_chunk(&c, 7, 0, 3, 100, &mut a);
    run_chunk(&c, 7, 0, 3, 100, &mut b);
    assert_eq!(a.points, b.points);
}

/// Flame functions beside a grid function, with what each branch of the flame path meets:
/// xforms that batch (spherical points sent out of the plane now and then, julia's random bit,
/// waves whose sin leaves its vector core's range so that the batch is redone with libm), one
/// mapped point by point (exponential), pre_blur, a post-affine, an opacity below 1, xaos, and
/// a final xform that batches (`final_batches`) or not, of opacity `final_opacity`.
fn flame_ifs(final_batches: bool, final_opacity: f64) -> Ifs {
    use crate::flame::{Variation, VariationTerm, Xform};
    use crate::model::FlameMap;
    let term = |name: &str, weight: f64| {
        let variation = Variation::by_name(name).expect("variation");
        VariationTerm { variation, weight, params: variation.default_params() }
    };
    let xform = |color: f64, coefs: [f64; 6], variations: Vec<VariationTerm>| Xform {
        weight: 1.0,
        color,
        color_speed: 0.4,
        opacity: 1.0,
        coefs,
        post: None,
        variation_coefs: None,
        variations,
        chaos: Vec::new(),
    };
    let mut xforms = [
        xform(0.0, [0.5, 0.0, 0.0, 0.5, -0.5, -0.3], vec![term("linear", 0.6), term("spherical", 0.4)]),
        xform(1.0, [0.5, 0.2, -0.2, 0.5, 0.5, 0.3], vec![term("linear", 0.7), term("exponential", 0.1)]),
        xform(
            0.5,
            [0.4, 0.0, 0.1, 0.4, 0.0, 0.0],
            vec![term("julia", 0.3), term("sinusoidal", 0.2), term("waves", 0.1), term("pre_blur", 0.1)],
        ),
    ];
    xforms[1].opacity = 0.6;
    xforms[1].post = Some([0.9, 0.1, -0.1, 0.9, 0.05, 0.0]);
    let flame = |x: &Xform, xaos: Vec<f64>| Function {
        name: "flame".into(),
        map: Map::Flame(FlameMap { xform: x.clone() }),
        color: [1.0; 3],
        weight: Some(1.0),
        enabled: true,
        xaos,
    };
    let mut functions: Vec<Function> =
        vec![flame(&xforms[0], vec![1.0, 2.0, 0.0, 1.0]), flame(&xforms[1], Vec::new()), flame(&xforms[2], Vec::new())];
    let mut grid = warped_ifs().functions.swap_remove(3);
    grid.weight = Some(0.5);
    functions.push(grid);
    let final_terms =
        if final_batches { vec![term("linear", 0.9), term("swirl", 0.1)] } else { vec![term("rings", 0.5)] };
    let final_xform = Xform { opacity: final_opacity, ..xform(0.8, [0.9, 0.1, -0.1, 0.9, 0.0, 0.1], final_terms) };
    Ifs {
        domain: RectGrid { axes: [vec![-1.0, 1.0], vec![-1.0, 1.0], vec![0.0, 0.0]] },
        functions,
        probability_mode: ProbabilityMode::Explicit,
        final_xform: Some(final_xform),
    }
}

/// The flame path steps all of a chunk's orbits at a time, each flame function's orbits as
/// one batch (`CompiledIfs::map_flame_row`): its points, their colour coordinates and the
/// orbits' generators are those of `map_with_rng` orbit by orbit (the portable path), bit for
/// bit, with and without a final xform that batches, of opacity 1 and below.
#[test]
fn flame_rows_give_the_points_of_one_orbit_at_a_time() {
    for (final_batches, final_opacity) in [(true, 1.0), (false, 1.0), (true, 0.7), (false, 0.4)] {
        let c = CompiledIfs::new(&flame_ifs(final_batches, final_opacity)).unwrap();
        assert!(c.has_flames() && c.has_final_xform());
        let colored =
            c.clone().with_palette(vec![0.1, 0.9, 0.5, 0.3], &crate::palette::Palette::builtin("ember").unwrap());
        for ifs in [&c, &colored] {
            let (mut want, mut got) = (CollectSink::default(), CollectSink::default());
            let mut want_chains = ChunkChains::start(ifs, 5, 1, 3);
            let mut got_chains = want_chains.clone();
            super::run::run_chains(ifs, Path::Portable, &mut want_chains, ifs.transient, 300, &mut want);
            super::run::run_chains(ifs, Path::Fastest, &mut got_chains, ifs.transient, 300, &mut got);
            let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            let (got_bits, want_bits) = (bits(&got.points), bits(&want.points));
            let first = got_bits.iter().zip(&want_bits).position(|(a, b)| a != b);
            assert_eq!(
                first,
                None,
                "final batches: {final_batches}, opacity {final_opacity}: {:?}",
                first.map(|i| (i, got.points[i], want.points[i]))
            );
            assert_eq!(got.functions, want.functions);
            assert_eq!(got_chains.rngs, want_chains.rngs);
            assert!(want.points.iter().any(|p| p.is_nan()), "some steps re-seed or are not drawn");
        }
    }
}

/// A final xform of opacity o maps a drawn point with chance o (flam3's final opacity) and
/// leaves the others as they are, drawn with the orbit's colour coordinate: here it moves its
/// points 100 to the right and colours them with palette entry 255 (c_f 1 at speed 1), which no
/// orbit's coordinate (the functions' are at most 0.9) reaches. Both paths; opacity 0 and 1
/// move none and all.
#[test]
fn a_final_xform_maps_a_drawn_point_with_the_chance_of_its_opacity() {
    use crate::flame::{Variation, VariationTerm};
    for opacity in [0.0, 0.3, 1.0] {
        let mut ifs = flame_ifs(true, 1.0);
        let linear = Variation::by_name("linear").expect("linear");
        let translation = crate::flame::Xform {
            color: 1.0,
            color_speed: 1.0,
            opacity,
            coefs: [1.0, 0.0, 0.0, 1.0, 100.0, 0.0],
            variations: vec![VariationTerm { variation: linear, weight: 1.0, params: Vec::new() }],
            ..ifs.final_xform.clone().unwrap()
        };
        ifs.final_xform = Some(translation);
        let c = CompiledIfs::new(&ifs).unwrap();
        let colored = c.with_palette(vec![0.1, 0.9, 0.5, 0.3], &crate::palette::Palette::builtin("ember").unwrap());
        for path in [Path::Portable, Path::Fastest] {
            let mut sink = CollectSink::default();
            let mut chains = ChunkChains::start(&colored, 9, 0, 2);
            super::run::run_chains(&colored, path, &mut chains, colored.transient, 400, &mut sink);
            let drawn: Vec<(Vec3, u8)> =
                sink.points.iter().zip(&sink.functions).filter(|(p, _)| !p.is_nan()).map(|(p, &f)| (*p, f)).collect();
            let moved = drawn.iter().filter(|(p, _)| p.x > 50.0).count();
            for (p, entry) in &drawn {
                assert_eq!(p.x > 50.0, *entry == 255, "opacity {opacity}, {path:?}: {p} drawn with entry {entry}");
            }
            let share = moved as f64 / drawn.len() as f64;
            eprintln!("opacity {opacity}, {path:?}: {moved} of {} drawn points mapped ({share:.4})", drawn.len());
            assert!(drawn.len() > 10_000);
            assert!((share - opacity).abs() < 0.03, "opacity {opacity}, {path:?}: {share} of the points mapped");
        }
    }
}
