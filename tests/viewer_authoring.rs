//! Authoring from the viewer, headless: a function's kind changed (the map kept exactly where
//! the new kind can hold it), colours, probabilities, xaos, a builder's steps added, removed and
//! reordered, keys dragged along the timeline. Each through commands, each one undo step that
//! undo and redo restore exactly; the changed scenes save, load back and pass `nlifs info`.

mod common;

use glam::DVec3;
use nlifs::color::{linear_to_srgb8, srgb8_to_linear};
use nlifs::edit::{Edit, FunctionKind, MIN_KEY_GAP_SECS};
use nlifs::live::LiveSettings;
use nlifs::model::builder::{Axis, Step, StepKind};
use nlifs::model::{Map, ProbabilityMode, RectGrid};
use nlifs::scene::Scene;
use nlifs::scene::spec::{FunctionDef, flatten};
use nlifs::viewer::command::Command;
use nlifs::viewer::state::ViewerState;

fn state_for(file: &str) -> ViewerState {
    let path = common::repo_path("scenes").join(file);
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    ViewerState::new(scene, Some(path), LiveSettings::default())
}

/// Points spread through the grid's box (a 7-per-axis lattice, shifted off the grid lines by a
/// seeded fraction so that they fall inside cells).
fn probe_points(domain: &RectGrid) -> Vec<DVec3> {
    let (lo, hi) = (domain.min(), domain.max());
    let n = if domain.dimension() == 3 { 7 } else { 1 };
    let mut out = Vec::new();
    for (k, t) in (0..7 * 7 * n).map(|k| (k, [k % 7, (k / 7) % 7, k / 49])) {
        let jitter = ((k * 37 % 11) as f64 + 0.5) / 11.0 / 7.0;
        let u = DVec3::new(t[0] as f64 / 7.0, t[1] as f64 / 7.0, t[2] as f64 / 7.0) + DVec3::splat(jitter);
        let mut p = lo + (hi - lo) * u;
        if domain.dimension() == 2 {
            p.z = lo.z;
        }
        out.push(p);
    }
    out
}

/// Saves the viewer's scene, loads the file back (it must equal the scene) and runs
/// `nlifs info` on it (it must accept it).
fn save_reload_info(s: &mut ViewerState, name: &str) -> Scene {
    let dir = common::temp_dir(&format!("viewer-authoring-{name}"));
    let path = dir.join(format!("{name}.toml"));
    s.apply([Command::SaveScene(path.clone())]);
    assert!(s.error.is_none(), "save: {:?}", s.error);
    let loaded = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.functions, s.scene.functions, "the file holds the edited functions");
    assert_eq!(loaded.timeline, s.scene.timeline);
    assert_eq!(loaded.probability_mode, s.scene.probability_mode);
    let out = common::run_nlifs(&["info", path.to_str().unwrap()]);
    assert!(out.status.success(), "nlifs info refused the file: {}", String::from_utf8_lossy(&out.stderr));
    loaded
}

#[test]
fn affine_to_grid_is_the_same_map_and_grid_to_affine_recovers_it() {
    // 2D (sierpinski's affine maps on a 2×2 grid) and 3D (an added affine function on plant2's
    // non-uniform 2×4×2 grid).
    for (file, add) in [("sierpinski.toml", false), ("plant2.toml", true)] {
        let mut s = state_for(file);
        if add {
            s.apply([Command::AddFunction]);
        }
        let f = s.scene.functions.len() - 1;
        let FunctionDef::Affine(affine) = s.scene.functions[f].def.clone() else { panic!("{file}: not affine") };
        let original = s.scene.clone();
        s.apply([Command::SetFunctionKind { function: f, kind: FunctionKind::Grid }]);
        assert!(matches!(s.scene.functions[f].def, FunctionDef::Grid { .. }), "{file}: {:?}", s.error);
        assert!(s.message.as_deref().unwrap_or("").contains("the same map"), "{:?}", s.message);
        // Bi/trilinear interpolation of an affine map's samples is the map: equal up to
        // rounding, a few ulps of the coordinates (tolerance 1e-12 of the grid's extent).
        let map = s.scene.resolve(&s.scene.functions[f].def);
        let extent = (s.scene.domain.max() - s.scene.domain.min()).length();
        for p in probe_points(&s.scene.domain) {
            let err = map.eval(p).distance(affine.matrix * p + affine.offset);
            assert!(err <= 1e-12 * extent, "{file}: affine→grid differs by {err:e} at {p}");
        }
        // And back: the least-squares fit of an affine grid is the map.
        s.apply([Command::SetFunctionKind { function: f, kind: FunctionKind::Affine }]);
        let FunctionDef::Affine(back) = &s.scene.functions[f].def else { panic!() };
        let scale = affine.matrix.to_cols_array().iter().fold(1.0f64, |m, e| m.max(e.abs()));
        assert!(
            (back.matrix - affine.matrix).to_cols_array().iter().all(|e| e.abs() <= 1e-12 * scale),
            "{file}: {:?} vs {:?}",
            back.matrix,
            affine.matrix
        );
        assert!(back.offset.distance(affine.offset) <= 1e-12 * extent);
        assert!(s.message.as_deref().unwrap_or("").contains("the same map"), "{:?}", s.message);
        // Each change is one undo step.
        s.apply([Command::Undo]);
        assert!(matches!(s.scene.functions[f].def, FunctionDef::Grid { .. }));
        s.apply([Command::Undo]);
        assert_eq!(s.scene, original);
        s.apply([Command::Redo, Command::Redo]);
        assert!(matches!(s.scene.functions[f].def, FunctionDef::Affine(_)));
    }
}

#[test]
fn grid_to_affine_says_when_it_is_only_a_fit() {
    let mut approximate = 0;
    for file in ["plant1.toml", "tapering.toml"] {
        let original = state_for(file);
        for f in 0..original.scene.functions.len() {
            let mut s = original.clone();
            let Map::Grid(g) = s.scene.resolve(&s.scene.functions[f].def) else { panic!() };
            s.apply([Command::SetFunctionKind { function: f, kind: FunctionKind::Affine }]);
            let FunctionDef::Affine(fit) = s.scene.functions[f].def.clone() else { panic!("{:?}", s.error) };
            let cost = |m: glam::DMat3, o: DVec3| {
                g.grid.points().iter().zip(&g.points).map(|(p, q)| (m * *p + o - *q).length_squared()).sum::<f64>()
            };
            // The message says "approximate" exactly when the fit misses a grid point by more
            // than rounding (1e-9 of the grid's diagonal).
            let diagonal = (s.scene.domain.max() - s.scene.domain.min()).length();
            let misses = g
                .grid
                .points()
                .iter()
                .zip(&g.points)
                .any(|(p, q)| (fit.matrix * *p + fit.offset).distance(*q) > 1e-9 * diagonal);
            let message = s.message.clone().unwrap_or_default();
            assert_eq!(message.contains("approximate"), misses, "{file} f{f}: {message}");
            assert_eq!(message.contains("the same map"), !misses, "{file} f{f}: {message}");
            assert_eq!(s.ui.toast.as_deref(), Some(message.as_str()), "said over the view too");
            approximate += usize::from(misses);
            // The fit is the least-squares one: no affine map in a small neighbourhood comes
            // closer to the grid points (a convex problem, so a local test suffices).
            let best = cost(fit.matrix, fit.offset);
            for k in 0..12 {
                let mut m = fit.matrix;
                m.col_mut(k % 3)[(k / 3) % 3] += if k % 2 == 0 { 1e-4 } else { -1e-4 };
                assert!(cost(m, fit.offset) > best, "{file} f{f}: nudge {k} lowered the cost");
                let o = fit.offset + DVec3::splat(if k % 2 == 0 { 0.01 } else { -0.01 });
                assert!(cost(fit.matrix, o) > best, "{file} f{f}");
            }
        }
    }
    assert!(approximate > 0, "the scenes hold a grid that is not affine");
}

#[test]
fn changing_a_kind_in_an_animated_scene_changes_every_key_and_the_file_has_it() {
    let mut s = state_for("twist-anim.toml");
    let keyed: Vec<usize> = (0..s.scene.functions.len())
        .filter(|&f| s.scene.timeline.as_ref().unwrap().keys.iter().any(|k| k.function(f).is_some()))
        .collect();
    let f = keyed[0];
    let t_key = s.scene.timeline.as_ref().unwrap().keys.iter().find(|k| k.function(f).is_some()).unwrap().t_secs;
    let before_at_key = s.scene.resolve(&s.scene.function_def_at(f, t_key));
    s.apply([Command::SetFunctionKind { function: f, kind: FunctionKind::Grid }]);
    assert!(s.error.is_none(), "{:?}", s.error);
    for key in &s.scene.timeline.as_ref().unwrap().keys {
        if let Some(def) = key.function(f) {
            assert!(matches!(def, FunctionDef::Grid { .. }), "key at {} keeps a {def:?}", key.t_secs);
        }
    }
    // At the key, the grid function is the builder's resolved map sampled at the scene grid's
    // points (exactly, both are evaluated the same way).
    let after_at_key = s.scene.resolve(&s.scene.function_def_at(f, t_key));
    for p in s.scene.domain.points() {
        assert!(after_at_key.eval(p).distance(before_at_key.eval(p)) <= 1e-12, "at {p}");
    }
    let loaded = save_reload_info(&mut s, "kind-anim");
    assert!(matches!(loaded.functions[f].def, FunctionDef::Grid { .. }));
    // Grid → builder: one affine step, the same in every key.
    s.apply([Command::SetFunctionKind { function: f, kind: FunctionKind::Builder }]);
    let FunctionDef::Builder { builder, .. } = &s.scene.functions[f].def else { panic!("{:?}", s.error) };
    assert!(matches!(builder.steps[..], [Step::Affine { .. }]));
    save_reload_info(&mut s, "kind-anim-builder");
    // A Julia map has no other form: refused, scene unchanged.
    let mut j = state_for("julia.toml");
    let before = j.scene.clone();
    j.apply([Command::SetFunctionKind { function: 0, kind: FunctionKind::Grid }]);
    assert_eq!(j.scene, before);
    assert!(j.error.as_deref().unwrap_or("").contains("julia"), "{:?}", j.error);
}

#[test]
fn colour_and_enabled_are_undoable_and_a_picker_drag_is_one_step() {
    let mut s = state_for("plant2.toml");
    let original = s.scene.clone();
    for k in 1..=8 {
        s.apply([Command::SetFunctionColor { function: 1, color: [0.1 * k as f32, 0.2, 0.3] }]);
    }
    s.apply([Command::EndGesture]);
    // Snapped to 8-bit sRGB (what the picker shows and the file stores exactly).
    let snapped = [0.8f32, 0.2, 0.3].map(|c| srgb8_to_linear(linear_to_srgb8(c)));
    assert!(snapped.iter().zip([0.8f32, 0.2, 0.3]).all(|(a, b)| (a - b).abs() < 4e-3), "{snapped:?}");
    assert_eq!(s.scene.functions[1].color, snapped);
    s.apply([Command::SetFunctionEnabled { function: 2, enabled: false }]);
    assert!(!s.scene.functions[2].enabled);
    s.apply([Command::Undo]);
    assert!(s.scene.functions[2].enabled);
    s.apply([Command::Undo]);
    assert_eq!(s.scene, original, "the whole picker drag is one undo step");
    s.apply([Command::Redo]);
    assert_eq!(s.scene.functions[1].color, snapped);
    let loaded = save_reload_info(&mut s, "colour");
    assert_eq!(loaded.functions[1].color, snapped);
}

#[test]
fn a_typed_probability_makes_the_scene_explicit_and_auto_goes_back() {
    let mut s = state_for("plant2.toml");
    let original = s.scene.clone();
    assert_eq!(s.scene.probability_mode, ProbabilityMode::Contractivity);
    let auto_shares = s.report.as_ref().unwrap().functions.iter().map(|f| f.probability).collect::<Vec<_>>();
    // A drag on function 0's p: several values, one gesture.
    for w in [0.3, 0.4, 0.5] {
        s.apply([Command::SetFunctionProbability { function: 0, probability: Some(w) }]);
    }
    s.apply([Command::EndGesture]);
    assert_eq!(s.scene.probability_mode, ProbabilityMode::Explicit);
    let weights: Vec<f64> = s.scene.functions.iter().map(|f| f.probability.unwrap()).collect();
    assert_eq!(weights[0], 0.5);
    // The others keep their automatic shares (rounded to 3 decimals).
    for (i, w) in weights.iter().enumerate().skip(1) {
        assert!((w - auto_shares[i]).abs() <= 5e-4 + 1e-12, "function {i}: weight {w} vs share {}", auto_shares[i]);
    }
    // The shares used are the weights normalized.
    let total: f64 = weights.iter().sum();
    for (f, w) in s.report.as_ref().unwrap().functions.iter().zip(&weights) {
        assert!((f.probability - w / total).abs() < 1e-12);
    }
    let loaded = save_reload_info(&mut s, "explicit");
    assert_eq!(loaded.probability_mode, ProbabilityMode::Explicit);
    // Clearing one weight of an explicit scene is refused (the file would not load).
    let explicit = s.scene.clone();
    s.apply([Command::SetFunctionProbability { function: 1, probability: None }]);
    assert_eq!(s.scene, explicit);
    assert!(s.error.is_some());
    // Back to automatic: the weights go, the shares are the automatic ones again.
    s.apply([Command::SetProbabilityMode(ProbabilityMode::Contractivity)]);
    assert!(s.scene.functions.iter().all(|f| f.probability.is_none()));
    assert_eq!(s.scene.functions, original.functions);
    s.apply([Command::Undo]);
    assert_eq!(s.scene, explicit);
    s.apply([Command::Undo]);
    // (Saving gave the scene its new file; the rest is as loaded.)
    assert_eq!(
        (&s.scene.functions, s.scene.probability_mode),
        (&original.functions, original.probability_mode),
        "the p drag was one undo step"
    );
    // Explicit from the menu: the weights are the current shares.
    s.apply([Command::SetProbabilityMode(ProbabilityMode::Explicit)]);
    let shares = s.report.as_ref().unwrap().functions.iter().map(|f| f.probability).collect::<Vec<_>>();
    for (a, b) in shares.iter().zip(&auto_shares) {
        assert!((a - b).abs() < 2e-3, "explicit shares {shares:?} vs automatic {auto_shares:?}");
    }
    // A function added to an explicit scene gets a weight (the mean of the others), so that
    // the file still loads.
    s.apply([Command::AddFunction]);
    let n = s.scene.functions.len();
    let mean = s.scene.functions[..n - 1].iter().map(|f| f.probability.unwrap()).sum::<f64>() / (n - 1) as f64;
    assert_eq!(s.scene.functions[n - 1].probability, Some(mean));
    save_reload_info(&mut s, "explicit-menu");
}

/// The xaos table: a drag is one undo step, the file holds the row, a deleted function's
/// column goes with it, a copy is reached as its original is, and adaptive probabilities (by
/// the point's place) are refused while a row is set, and the other way round.
#[test]
fn xaos_edits_are_undoable_and_follow_deleted_and_copied_functions() {
    let mut s = state_for("sierpinski.toml");
    let original = s.scene.clone();
    for v in [0.8, 0.4, 0.0] {
        s.apply([Command::SetFunctionXaos { function: 0, to: 0, value: v }]);
    }
    s.apply([Command::EndGesture]);
    assert_eq!(s.scene.functions[0].xaos, [0.0]);
    s.apply([Command::SetFunctionXaos { function: 1, to: 2, value: 2.5 }]);
    s.apply([Command::EndGesture]);
    assert_eq!(s.scene.functions[1].xaos, [1.0, 1.0, 2.5]);
    s.apply([Command::Undo]);
    assert!(s.scene.functions[1].xaos.is_empty());
    s.apply([Command::Undo]);
    assert_eq!(s.scene.functions, original.functions, "the drag was one undo step");
    s.apply([Command::Redo, Command::Redo]);
    let loaded = save_reload_info(&mut s, "xaos");
    assert_eq!(loaded.functions[1].xaos, [1.0, 1.0, 2.5]);
    // A row of only 1s is no row.
    s.apply([Command::SetFunctionXaos { function: 0, to: 0, value: 1.0 }, Command::EndGesture]);
    assert!(s.scene.functions[0].xaos.is_empty());
    s.apply([Command::SetProbabilityMode(ProbabilityMode::Adaptive)]);
    assert!(s.error.take().is_some_and(|e| e.contains("xaos")), "adaptive refused with xaos");
    assert_eq!(s.scene.probability_mode, original.probability_mode);
    // A copy of w3 is reached as w3 is; deleting w1 takes its column out of every row.
    s.apply([Command::DuplicateFunction(2)]);
    assert_eq!(s.scene.functions[1].xaos, [1.0, 1.0, 2.5, 2.5]);
    s.apply([Command::DeleteFunction(0)]);
    assert_eq!(s.scene.functions[0].xaos, [1.0, 2.5, 2.5]);
    save_reload_info(&mut s, "xaos-copied");
    s.apply([Command::SetFunctionXaos { function: 0, to: 0, value: 1.0 }, Command::EndGesture]);
    s.apply([Command::SetFunctionXaos { function: 0, to: 1, value: 1.0 }, Command::EndGesture]);
    s.apply([Command::SetFunctionXaos { function: 0, to: 2, value: 1.0 }, Command::EndGesture]);
    assert!(s.scene.functions.iter().all(|f| f.xaos.is_empty()));
    s.apply([Command::SetProbabilityMode(ProbabilityMode::Adaptive)]);
    assert_eq!(s.scene.probability_mode, ProbabilityMode::Adaptive);
    let adaptive = s.scene.clone();
    s.apply([Command::SetFunctionXaos { function: 0, to: 0, value: 0.0 }]);
    assert_eq!(s.scene, adaptive, "no xaos on an adaptive scene");
    assert!(s.error.is_some());
}

#[test]
fn builder_steps_are_added_removed_and_reordered_in_every_key() {
    for file in ["builders.toml", "twist-anim.toml"] {
        let mut s = state_for(file);
        let f = s.scene.functions.iter().position(|f| matches!(f.def, FunctionDef::Builder { .. })).unwrap();
        let original = s.scene.clone();
        let steps_of = |s: &ViewerState| match &s.scene.functions[f].def {
            FunctionDef::Builder { builder, .. } => builder.steps.clone(),
            _ => panic!(),
        };
        let n = steps_of(&s).len();
        let ifs_before = s.scene.at(0.3);
        // An added step is the identity: the IFS at any time is unchanged (to rounding).
        // A twist about x (not the format's default axis), its range the grid's x extent.
        let (lo, hi) = (s.scene.domain.min(), s.scene.domain.max());
        let twist = Step::identity(StepKind::Twist, 3, lo, hi).with_axes((Axis::X, Axis::X), lo, hi);
        // A bend towards its own axis does not exist: refused, nothing changes.
        let bad = Step::identity(StepKind::Bend, 3, lo, hi).with_axes((Axis::Y, Axis::Y), lo, hi);
        s.apply([Command::InsertBuilderStep { function: f, index: 0, step: bad }]);
        assert_eq!(s.scene, original);
        assert!(s.error.is_some());
        s.apply([Command::InsertBuilderStep { function: f, index: n, step: twist.clone() }]);
        assert_eq!(steps_of(&s)[n], twist);
        assert_eq!(steps_of(&s).len(), n + 1, "{file}: {:?}", s.error);
        assert_eq!(steps_of(&s)[n].kind(), StepKind::Twist);
        let ifs_after = s.scene.at(0.3);
        for (a, b) in ifs_before.functions.iter().zip(&ifs_after.functions) {
            for p in probe_points(&s.scene.domain) {
                assert!(a.map.eval(p).distance(b.map.eval(p)) < 1e-9, "{file}: an identity step moved {p}");
            }
        }
        // Every key that overrides the builder got the step too.
        for key in s.scene.timeline.iter().flat_map(|tl| &tl.keys) {
            if let Some(FunctionDef::Builder { builder, .. }) = key.function(f) {
                assert_eq!(builder.steps.len(), n + 1, "{file}: key at {}", key.t_secs);
            }
        }
        let added = s.scene.clone();
        // Move it to the front, then remove it: back to the original steps.
        s.apply([Command::MoveBuilderStep { function: f, from: n, to: 0 }]);
        assert_eq!(steps_of(&s)[0].kind(), StepKind::Twist);
        assert_eq!(steps_of(&s)[1..], steps_of(&state_for(file))[..]);
        save_reload_info(&mut s, &format!("steps-{}", file.trim_end_matches(".toml")));
        s.apply([Command::RemoveBuilderStep { function: f, step: 0 }]);
        assert_eq!(s.scene.functions, original.functions);
        assert_eq!(s.scene.timeline, original.timeline);
        // Each was one undo step.
        // (Saving gave the scene its new file; the rest is as edited.)
        let same = |a: &Scene, b: &Scene| a.functions == b.functions && a.timeline == b.timeline;
        s.apply([Command::Undo, Command::Undo]);
        assert!(same(&s.scene, &added));
        s.apply([Command::Undo]);
        assert!(same(&s.scene, &original));
        s.apply([Command::Redo, Command::Redo, Command::Redo]);
        assert_eq!(s.scene.functions, original.functions);
        // Out-of-range steps are refused with a message, the scene unchanged.
        let before = s.scene.clone();
        s.apply([
            Command::RemoveBuilderStep { function: f, step: 99 },
            Command::MoveBuilderStep { function: f, from: 0, to: 99 },
        ]);
        assert_eq!(s.scene, before);
        assert!(s.error.is_some());
    }
}

#[test]
fn a_key_drag_clamps_keeps_the_order_and_is_one_undo_step() {
    let mut s = state_for("twist-anim.toml");
    let original = s.scene.clone();
    let times = |s: &ViewerState| s.scene.timeline.as_ref().unwrap().keys.iter().map(|k| k.t_secs).collect::<Vec<_>>();
    let t0 = times(&s);
    assert!(t0.len() >= 3, "{t0:?}");
    let d = s.scene.timeline.as_ref().unwrap().duration_secs;
    // Drag key 1 far right, past key 2: it stops a millisecond before key 2.
    for k in 1..=10 {
        s.apply([Command::MoveKey { key: 1, t_secs: t0[1] + k as f64 * d }]);
    }
    let t = times(&s);
    assert!((t[1] - (t0[2] - MIN_KEY_GAP_SECS)).abs() < 1e-12, "{t:?}");
    assert!(t.windows(2).all(|w| w[1] - w[0] >= MIN_KEY_GAP_SECS - 1e-12), "order kept: {t:?}");
    // Then left past key 0, same gesture.
    s.apply([Command::MoveKey { key: 1, t_secs: -5.0 }]);
    let t = times(&s);
    assert!((t[1] - (t0[0] + MIN_KEY_GAP_SECS)).abs() < 1e-12, "{t:?}");
    s.apply([Command::EndGesture]);
    assert_eq!(times(&s)[0], t0[0]);
    s.apply([Command::Undo]);
    assert_eq!(s.scene, original, "one undo takes back the whole drag");
    s.apply([Command::Redo]);
    assert!((times(&s)[1] - (t0[0] + MIN_KEY_GAP_SECS)).abs() < 1e-12);
    s.apply([Command::Undo]);
    // The first key stops at 0, the last at the end of the timeline (loop: before the period
    // ends, where the first key comes again).
    let last = t0.len() - 1;
    s.apply([Command::MoveKey { key: 0, t_secs: -1.0 }, Command::EndGesture]);
    assert_eq!(times(&s)[0], 0.0);
    s.apply([Command::MoveKey { key: last, t_secs: 10.0 * d }, Command::EndGesture]);
    let end = times(&s)[last];
    assert!(end < d && end >= d - MIN_KEY_GAP_SECS - 1e-12, "last key at {end} of {d}");
    // A key moved to a middle time: the animation follows (the key's values now hold there).
    s.apply([Command::Undo, Command::Undo]);
    assert_eq!(s.scene, original);
    let k = (0..t0.len()).find(|&k| k > 0 && !s.scene.timeline.as_ref().unwrap().keys[k].functions.is_empty()).unwrap();
    let mid = 0.5 * (t0[k - 1] + t0[k]);
    let key = s.scene.timeline.as_ref().unwrap().keys[k].clone();
    s.apply([Command::MoveKey { key: k, t_secs: mid }, Command::EndGesture]);
    assert_eq!(times(&s)[k], mid);
    for fk in &key.functions {
        let (now, keyed) = (flatten(&s.scene.function_def_at(fk.function, mid)), flatten(&fk.def));
        assert!(now.iter().zip(&keyed).all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs().max(1.0)), "{now:?} vs {keyed:?}");
    }
    save_reload_info(&mut s, "key-drag");
    // The edit checks what it is applied to: a move made for another state is refused.
    let stale = Edit::move_key(&original, k, mid).unwrap();
    assert!(stale.apply(&mut s.scene.clone()).is_err());
}
