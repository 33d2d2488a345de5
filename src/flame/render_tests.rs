//! Tests of the flame chaos game: its workers (chains grouped by xform, batches, buckets in
//! flight) against flam3's loop run one run after another.

use super::*;
use crate::flame::{Variation, VariationTerm};

/// Three xforms with xaos, an opacity, a spherical term that sends points out of the plane
/// now and then, a final xform plotted half the time, a rotated camera, a linear palette.
fn flame() -> Flame {
    let term = |name: &str, weight: f64| {
        let variation = Variation::by_name(name).expect("variation");
        VariationTerm { variation, weight, params: variation.default_params() }
    };
    let xform = |weight: f64, color: f64, coefs: [f64; 6], chaos: Vec<f64>| Xform {
        weight,
        color,
        color_speed: 0.5,
        opacity: 1.0,
        coefs,
        post: None,
        variation_coefs: None,
        variations: vec![term("linear", 0.6), term("spherical", 0.4)],
        chaos,
    };
    let mut xforms = vec![
        xform(0.5, 0.0, [0.5, 0.0, 0.0, 0.5, -0.5, -0.3], vec![1.0, 2.0, 0.0]),
        xform(0.5, 1.0, [0.5, 0.2, -0.2, 0.5, 0.5, 0.3], vec![]),
        xform(0.3, 0.5, [0.4, 0.0, 0.1, 0.4, 0.0, 0.6], vec![0.5, 1.0, 1.0]),
    ];
    xforms[1].opacity = 0.6;
    // The batch path's other branches: a variation drawing a random bit (julia), sin's vector
    // core (sinusoidal), waves with e = 0, whose sin(y / ε) is beyond the core's range so that
    // the batches are redone with libm's sin, pre_blur, a post-affine; and an xform mapped point
    // by point (exponential is not batched).
    xforms[2].variations.extend([
        term("julia", 0.3),
        term("sinusoidal", 0.2),
        term("waves", 0.1),
        term("pre_blur", 0.1),
    ]);
    xforms[0].variations.push(term("exponential", 0.05));
    xforms[1].post = Some([0.9, 0.1, -0.1, 0.9, 0.05, 0.0]);
    let mut final_xform = xform(0.0, 0.8, [0.9, 0.1, -0.1, 0.9, 0.0, 0.1], vec![]);
    final_xform.opacity = 0.5;
    Flame {
        size: [40, 30],
        scale: 12.0,
        rotate: 20.0,
        quality: 30.0,
        palette_mode: PaletteMode::Linear,
        palette: (0..256).map(|i| [i as f64 / 255.0, 1.0 - i as f64 / 255.0, 0.5, 1.0]).collect(),
        xforms,
        final_xform: Some(final_xform),
        ..Flame::default()
    }
}

/// The other branches of a round: a step palette, no final xform, no rotation, one xform
/// plotted at weight 10^(log₂ 0.6) and the others at 1.
fn step_flame() -> Flame {
    let mut f = flame();
    f.palette_mode = PaletteMode::Step;
    f.final_xform = None;
    f.rotate = 0.0;
    f
}

/// The layout and chaos game of `flame`.
fn game_of(flame: &Flame) -> (Layout, ChaosGame) {
    let layout = Layout::new(flame).expect("layout");
    let game = ChaosGame::new(flame, &layout).expect("game");
    (layout, game)
}

/// The oracle: flam3's loop, one run after another, each sample added at once.
fn one_run_after_another(game: &ChaosGame, seed: u32, samples: u64, cells: usize) -> (Vec<Bucket>, u64) {
    let mut histogram = vec![[0u32; 5]; cells];
    let mut bad = 0;
    for run in 0..samples.div_ceil(RUN_SAMPLES) {
        let n = RUN_SAMPLES.min(samples - run * RUN_SAMPLES) as i64;
        let mut rng = Pcg32::for_stream(seed, 0, run as u32);
        let mut p = [uniform11(&mut rng), uniform11(&mut rng)];
        let mut color = rng.next_f64();
        let (mut last, mut consecutive_bad, mut i) = (0, 0, -FUSE_ITERATIONS);
        while i < n {
            let entry = rng.next_u32() as usize & (CHOICE_ENTRIES - 1);
            let row = if game.xaos { last } else { 0 };
            let k = game.choice[row * CHOICE_ENTRIES + entry] as usize;
            let x = &game.xforms[k];
            color = x.color_of(color);
            p = x.map.apply(p, &mut rng);
            if is_bad(p) {
                p = [uniform11(&mut rng), uniform11(&mut rng)];
                bad += 1;
                consecutive_bad += 1;
                if consecutive_bad < 5 {
                    continue;
                }
            }
            consecutive_bad = 0;
            last = k + 1;
            let (mut shown, mut shown_color) = (p, color);
            if let Some(f) = &game.final_xform
                && (f.opacity == 1.0 || rng.next_f64() < f.opacity)
            {
                shown_color = f.color_of(color);
                shown = f.map.apply(p, &mut rng);
                if is_bad(shown) {
                    shown = [uniform11(&mut rng), uniform11(&mut rng)];
                }
            }
            if let (b, true) = game.camera.bucket(shown)
                && i >= 0
                && x.plotted_weight != 0.0
            {
                add(&mut histogram[b], &game.increments_of(shown_color, x.plotted_weight));
            }
            i += 1;
        }
    }
    (histogram, bad)
}

/// The workers (chains mapped in batches by xform, buckets prefetched) sum exactly what
/// one run after another does, on one thread and on three, for a sample count that ends
/// in a partial run and is more runs than one worker's chains.
#[test]
fn batched_chains_sum_what_one_run_after_another_sums() {
    for (name, flame) in [("flame", flame()), ("step_flame", step_flame())] {
        let (layout, game) = game_of(&flame);
        let samples = (CHAINS as u64 + 9) * RUN_SAMPLES + 1234;
        let cells = layout.hist_width * layout.hist_height;
        let expected = one_run_after_another(&game, 5, samples, cells);
        assert!(expected.0.iter().any(|b| b[4] != 0), "{name}: nothing plotted");
        assert!(expected.1 > 0, "{name}: no re-seed");
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            let got = pool.install(|| game.run_f64(5, samples, &layout, &|_| {}));
            assert!(
                (got.0.buckets(), got.1) == expected,
                "{name}, {threads} thread(s): the histograms or re-seed counts differ"
            );
        }
    }
}

/// The chaos game's AVX-512 and AVX2 builds (where the CPU runs them) sum the bits of the
/// portable one: no fused multiply-add, and `flame::trig`'s functions are the same operations
/// in every build.
#[test]
fn every_build_sums_the_same_bits() {
    let (layout, game) = game_of(&flame());
    let samples = (CHAINS as u64 + 3) * RUN_SAMPLES + 77;
    let cells = layout.hist_width * layout.hist_height;
    let one_worker = |build: &dyn Fn(&AtomicU64, &mut [Bucket]) -> u64| {
        let mut histogram = vec![[0u32; 5]; cells];
        let bad = build(&AtomicU64::new(0), &mut histogram);
        (histogram, bad)
    };
    let portable = one_worker(&|next, h| game.run_chains(5, samples, next, h, &|_| {}, false));
    assert!(portable.0.iter().any(|b| b[4] != 0), "nothing plotted");
    #[cfg(target_arch = "x86_64")]
    {
        use crate::simd::SimdLevel;
        #[expect(unsafe_code, reason = "the AVX2 and AVX-512 builds, entered after the CPU check")]
        {
            let level = SimdLevel::detect();
            if level.avx2() {
                // SAFETY: the CPU runs AVX2 (detected).
                let avx2 = one_worker(&|next, h| unsafe { game.run_chains_avx2(5, samples, next, h, &|_| {}) });
                assert!(avx2 == portable, "the AVX2 build differs");
            }
            if level == SimdLevel::Avx512 {
                // SAFETY: the CPU runs AVX-512F (detected).
                let avx512 = one_worker(&|next, h| unsafe { game.run_chains_avx512(5, samples, next, h, &|_| {}) });
                assert!(avx512 == portable, "the AVX-512 build differs");
            }
        }
    }
}

/// The chaos game's bucket and palette entry arithmetic (clamp, then `whole_u32`, so that it
/// vectorizes) gives what converting with `as` and then clamping gives, for points in and far
/// out of view, NaN and infinities included.
#[test]
fn buckets_and_palette_entries_are_those_of_as_then_clamp() {
    let (_, game) = game_of(&step_flame());
    let cam = &game.camera;
    let mut rng = Pcg32::for_stream(7, 0, 0);
    let specials = [0.0, -0.0, 1e-300, -1e-300, 0.5, 1.0, 1e10, -1e10, f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
    for n in 0..200_000 {
        let coordinate = |rng: &mut Pcg32| match n % 4 {
            0 => specials[rng.next_u32() as usize % specials.len()],
            1 => (rng.next_f64() * 2.0 - 1.0) * 1e12,
            _ => (rng.next_f64() * 2.0 - 1.0) * 4.0,
        };
        let p = [coordinate(&mut rng), coordinate(&mut rng)];
        let i = ((cam.x_scale * p[0] - cam.x_offset) as i64).clamp(0, cam.hist_width as i64 - 1) as usize;
        let j = ((cam.y_scale * p[1] - cam.y_offset) as i64).clamp(0, cam.hist_height as i64 - 1) as usize;
        assert_eq!(cam.bucket_of_rotated(p).0 as usize, i + j * cam.hist_width, "{p:?}");
        let color = coordinate(&mut rng) / 4.0;
        let entry = (color * 256.0).clamp(0.0, 255.0) as usize;
        #[expect(clippy::manual_clamp, reason = "the chaos game's form: NaN gives 0")]
        let got = whole_u32((color * 256.0).max(0.0).min(255.0)) as usize;
        assert_eq!(got, entry, "colour {color}");
    }
    for v in [0.0, 0.25, 0.999_999, 1.0, 254.5, 255.0, 65_535.9, 2_147_483_647.0, 4_294_967_295.0] {
        assert_eq!(whole_u32(v), v as u32, "{v}");
    }
}

/// `Round::group` gives the same groups with and without AVX-512 (where the CPU runs it):
/// every chain once, in the group of the xform it drew, each group in chain order.
#[test]
fn grouping_by_xform_places_every_chain_once() {
    let mut rng = Pcg32::for_stream(9, 0, 0);
    let wide = cfg!(target_arch = "x86_64") && crate::simd::SimdLevel::detect() == crate::simd::SimdLevel::Avx512;
    for xforms in [1, 2, 3, 7, 16, 64, 65, 200] {
        for live in [1, 15, 16, 17, 100, CHAINS - 1, CHAINS] {
            // Skewed draws, so that some xforms get no chain.
            let chosen: Vec<u32> =
                (0..live).map(|_| (rng.next_u32() % xforms as u32).min(rng.next_u32() % xforms as u32)).collect();
            let mut groups = Vec::new();
            for vector in [false, wide] {
                let mut r = Round::new(xforms);
                r.chosen[..live].copy_from_slice(&chosen);
                r.group(live, xforms, vector);
                let mut by_xform = vec![Vec::new(); xforms];
                for &x in &r.drawn {
                    let (start, count) = (r.start[x] as usize, r.count[x] as usize);
                    assert!(count > 0, "xform {x} drawn without chains");
                    by_xform[x] = r.order[start..start + count].to_vec();
                }
                for (x, members) in by_xform.iter().enumerate() {
                    let expected: Vec<ChainNumber> =
                        (0..live as ChainNumber).filter(|&k| r.chosen[k as usize] as usize == x).collect();
                    assert_eq!(*members, expected, "xform {x} of {xforms}, {live} chains, vector {vector}");
                }
                groups.push(by_xform);
            }
            assert_eq!(groups[0], groups[1]);
        }
    }
}
