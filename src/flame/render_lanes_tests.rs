//! Tests of the f32 lane chaos game: its xforms against the f64 ones, which flames it takes,
//! and its sums on one and two threads.

use super::super::{ChaosGame, Flame, Layout, Xform};
use super::*;
use crate::flame::render_base::HistogramCell;
use crate::flame::variations_lanes::{self as lanes, Draw};
use crate::flame::{Variation, VariationTerm};

/// An xform of colour speed 0.5 and opacity 1, without post map or xaos.
fn xform(weight: f64, color: f64, coefs: [f64; 6], variations: Vec<VariationTerm>) -> Xform {
    Xform {
        weight,
        color,
        color_speed: 0.5,
        opacity: 1.0,
        coefs,
        post: None,
        variation_coefs: None,
        variations,
        chaos: vec![],
    }
}

/// A 40×30 flame of `xforms` with an opaque palette, and its layout.
fn small_flame(xforms: Vec<Xform>) -> (Flame, Layout) {
    let palette = (0..256).map(|i| [f64::from(i) / 255.0, 0.5, 1.0, 1.0]).collect();
    let flame = Flame { size: [40, 30], scale: 12.0, xforms, palette, ..Flame::default() };
    let layout = Layout::new(&flame).expect("layout");
    (flame, layout)
}

/// A flame of one xform whose only term is variation `v` (its default parameters, those
/// that default to 0 at 0.4), and its chaos game.
fn one_term(v: u8) -> (Flame, Layout) {
    one_term_moved(v, None)
}

/// [`one_term`], each parameter moved at random by up to its size plus 1 either way where
/// `moves` gives a generator (two parameters of the same default swapped in a formula then
/// differ).
fn one_term_moved(v: u8, moves: Option<&mut Pcg32>) -> (Flame, Layout) {
    let variation = Variation(v);
    let mut params: Vec<f64> = variation.default_params().into_iter().map(|p| if p == 0.0 { 0.4 } else { p }).collect();
    if let Some(r) = moves {
        for p in &mut params {
            *p += (r.next_f64() - 0.5) * 2.0 * (p.abs() + 1.0);
        }
    }
    let term = VariationTerm { variation, weight: 0.9, params };
    let mut one = xform(1.0, 0.5, [0.8, 0.3, -0.2, 0.7, 0.3, -0.4], vec![term]);
    one.post = Some([0.9, 0.1, -0.1, 0.9, 0.05, 0.0]);
    small_flame(vec![one])
}

/// Each supported variation that draws nothing maps points as the f64 xform does, within
/// f32's rounding, with its default parameters and with three random sets: at most 1 % of
/// 4096 points (where a tangent or a division is ill conditioned) differ by more than 10^−3
/// relative to the point's size. (A wrong formula differs almost everywhere.)
#[test]
fn lanes_map_as_the_f64_xforms() {
    let mut checked = 0;
    let cases =
        SUPPORTED.iter().filter(|&&v| lanes::draw_of(v) == Draw::None).flat_map(|&v| (0..4).map(move |s| (v, s)));
    for (v, set) in cases {
        let mut moves = Pcg32::for_stream(set, 99, u32::from(v));
        let (flame, layout) = one_term_moved(v, (set > 0).then_some(&mut moves));
        let game = ChaosGame::new(&flame, &layout).expect("game");
        let lane_game = LaneGame::new(&game).unwrap_or_else(|e| panic!("variation {v} runs in lanes: {e}"));
        let mut rng = LaneRng::new(7, 0);
        let mut f64_rng = Pcg32::for_stream(7, 0, 0);
        let mut far = 0;
        let mut points = Pcg32::for_stream(1, 2, u32::from(v));
        for _ in 0..4096 / LANES {
            let mut x = Lanes(std::array::from_fn(|_| points.next_f32() * 4.0 - 2.0));
            let mut y = Lanes(std::array::from_fn(|_| points.next_f32() * 4.0 - 2.0));
            let (x0, y0) = (x, y);
            lane_game.xforms[0].apply(&mut x, &mut y, &mut rng, &mut Scratch::new());
            for l in 0..LANES {
                let [ex, ey] = game.xforms[0].map.apply([f64::from(x0[l]), f64::from(y0[l])], &mut f64_rng);
                let size = 1.0 + ex.abs().max(ey.abs());
                let off = (f64::from(x[l]) - ex).abs().max((f64::from(y[l]) - ey).abs());
                // (Both out of the plane counts as agreeing: the point is re-seeded.)
                let both_bad = !(ex.abs() <= 1e10) && !(x[l].abs() <= 1e10);
                if !(off <= 1e-3 * size) && !both_bad {
                    far += 1;
                }
            }
        }
        assert!(far <= 40, "variation {v}, parameter set {set}: {far} of 4096 points differ from the f64 xform's");
        checked += 1;
    }
    assert!(checked >= 4 * 80, "{checked} variations and parameter sets checked");
}

/// Every variation runs in lanes. A flame with a palette entry that is not opaque (the cells keep
/// one sum for A and the count), or more xforms than the lanes choose among, takes the f64 game
/// (`runs_in_lanes` says so too).
#[test]
fn other_flames_take_the_f64_game() {
    for v in Variation::all() {
        assert!(super::super::runs_in_lanes(&one_term(v.0).0), "variation {}", v.name());
    }
    let refusal = |flame: &Flame| super::super::lanes_refusal(flame).unwrap_or_default();
    let (mut flame, _) = one_term(17);
    flame.palette[100][3] = 0.5;
    assert_eq!(refusal(&flame), "a palette entry that is not opaque");
    let (mut flame, _) = one_term(17);
    flame.xforms = vec![flame.xforms[0].clone(); MAX_XFORMS + 1];
    assert_eq!(refusal(&flame), "more than 64 xforms");
    let (mut flame, _) = one_term(17);
    flame.center = [1e6, 0.0];
    assert_eq!(refusal(&flame), "a view too deep or too far from the origin for f32");
}

/// The lane game's picture is a pure function of the seed, whatever the thread count: with
/// queues (wedge-petals) and without (one xform: its terms are shared).
#[test]
fn same_sums_on_one_and_two_threads() {
    for (flame, layout) in [one_term(17), wedge_petals()] {
        let game = ChaosGame::new(&flame, &layout).expect("game");
        let shared = LaneGame::new(&game).expect("lanes").shared;
        assert_eq!(shared, flame.xforms.len() == 1);
        let samples = 3 * BLOCK_SAMPLES / 2;
        let sums = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            pool.install(|| game.run(5, samples, &layout, &|_| {}))
        };
        let (one, two) = (sums(1), sums(2));
        assert!(one.0.buckets().iter().any(|b| b[4] > 0), "something is drawn");
        assert_eq!(one, two, "shared terms: {shared}");
    }
}

fn wedge_petals() -> (Flame, Layout) {
    let text = include_str!("../../docs/gallery/flames/wedge-petals.flame");
    let flame = crate::flame::read_str(text, "wedge-petals.flame").expect("flame").flames.remove(0);
    let layout = Layout::new(&flame).expect("layout");
    (flame, layout)
}

/// Three xforms with the same terms (swirl and linear, the weights differing), one with a post
/// map: a flame for the shared-terms game.
fn shared_terms() -> (Flame, Layout) {
    let term = |name: &str, weight: f64| VariationTerm {
        variation: Variation::by_name(name).expect("variation"),
        weight,
        params: vec![],
    };
    let terms = |swirl: f64| vec![term("swirl", swirl), term("linear", 1.0 - swirl)];
    let mut xforms = vec![
        xform(0.5, 0.0, [0.55, 0.1, -0.1, 0.55, -0.6, -0.4], terms(0.3)),
        xform(0.3, 0.5, [0.5, -0.2, 0.2, 0.5, 0.6, -0.4], terms(0.1)),
        xform(0.2, 1.0, [0.45, 0.0, 0.0, 0.45, 0.0, 0.6], terms(0.5)),
    ];
    xforms[1].post = Some([0.9, 0.1, -0.1, 0.9, 0.05, 0.0]);
    small_flame(xforms)
}

/// Which flames take the shared-terms game: the same variations and parameters in every
/// xform (weights may differ) and the same plotted weight.
#[test]
fn shared_terms_are_found() {
    let (flame, layout) = shared_terms();
    let game = ChaosGame::new(&flame, &layout).expect("game");
    let mut xforms = LaneGame::new(&game).expect("lanes").xforms;
    assert!(shared::share_terms(&xforms));
    xforms[2].terms[0].k[0] += 1.0;
    assert!(!shared::share_terms(&xforms), "a parameter differs");
    xforms[2].terms.pop();
    assert!(!shared::share_terms(&xforms), "a term fewer");
    let (flame, layout) = wedge_petals();
    assert!(!LaneGame::new(&ChaosGame::new(&flame, &layout).expect("game")).expect("lanes").shared);
}

/// The shared-terms game draws the flame the queues draw: their histograms, 4 M samples each,
/// summed over blocks of 4 × 3 buckets, differ by under 1 % of the total (measured: 0.23 %; the
/// queues with two seeds, 0.28 %; the shared game without xform 1's post map, 29 %).
#[test]
fn shared_terms_draw_what_the_queues_draw() {
    let (flame, layout) = shared_terms();
    let game = ChaosGame::new(&flame, &layout).expect("game");
    let mut lane_game = LaneGame::new(&game).expect("lanes");
    let cells = layout.hist_width * layout.hist_height + LANES;
    let mut sums = |shared: bool| {
        lane_game.shared = shared;
        let mut histogram = vec![Cell::default(); cells];
        let next = std::sync::atomic::AtomicU64::new(0);
        lane_game.run_worker(11, 2 * BLOCK_SAMPLES, &next, &mut histogram, &|_| {});
        let mut coarse = vec![0u64; (layout.hist_width / 4 + 1) * (layout.hist_height / 3 + 1)];
        for (i, c) in histogram[..cells - LANES].iter().enumerate() {
            let (u, v) = (i % layout.hist_width / 4, i / layout.hist_width / 3);
            coarse[u + v * (layout.hist_width / 4 + 1)] += u64::from(c.bucket()[4]);
        }
        coarse
    };
    let (with_queues, shared) = (sums(false), sums(true));
    let total: u64 = with_queues.iter().sum();
    let off: u64 = with_queues.iter().zip(&shared).map(|(a, b)| a.abs_diff(*b)).sum();
    assert!(total > 0, "something is drawn");
    let share = off as f64 / total as f64;
    assert!(share < 0.01, "{:.2} % of the histogram differs", share * 100.0);
}

/// The AVX-512 append (where the CPU has it) and the portable one give the same sums: the
/// queues' contents past their ends, which differ between the two, do not reach the picture.
/// (wedge-petals, whose pictures differed before the queues' tails were cleared.)
#[test]
fn same_sums_with_either_append() {
    let (flame, layout) = wedge_petals();
    let game = ChaosGame::new(&flame, &layout).expect("game");
    let lane_game = LaneGame::new(&game).expect("lanes");
    let cells = layout.hist_width * layout.hist_height + LANES;
    // The dispatched build (AVX-512's compress where the CPU has it), then the portable build.
    let sums = |dispatched: bool| {
        let mut histogram = vec![Cell::default(); cells];
        let next = std::sync::atomic::AtomicU64::new(0);
        let samples = 4 * BLOCK_SAMPLES;
        if dispatched {
            lane_game.run_worker(3, samples, &next, &mut histogram, &|_| {});
        } else {
            lane_game.run_blocks(3, samples, &next, &mut histogram, &|_| {}, false);
        }
        histogram
    };
    let (wide, portable) = (sums(true), sums(false));
    assert!(wide.iter().any(|c| c.bucket()[4] > 0), "something is drawn");
    assert_eq!(wide, portable);
}
