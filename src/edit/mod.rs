//! Scene edits as plain data, and an undo/redo history of whole gestures.
//!
//! An [`Edit`] carries both the value before and after, so it can be applied and inverted
//! without looking at anything else; a gesture (a whole drag of grid points, a slider drag on a
//! builder parameter, adding a key) is one edit, or a [`Edit::Batch`] of them. The viewer may
//! preview a drag by changing the scene directly and, on release, hand the gesture's edit
//! (before = the value at the press) to [`History::record_applied`]; or apply edits through
//! [`History::apply`]. Edits address a function's definition in the base scene (`key: None`)
//! or its override in key `key` of the timeline; the `*_at_playhead` constructors choose,
//! creating the key at the playhead when there is none. Edits that change a function's
//! structure (its kind, a builder's list of steps) are in `structure.rs`.

use glam::DVec3;

use crate::model::builder::Step;
use crate::scene::Scene;
use crate::scene::spec::{self, FunctionDef};
use crate::scene::timeline::{self, Key, Timeline};

mod structure;

pub use structure::{FunctionKind, KindChange};

/// The least time between two keys that a key drag leaves: a millisecond, far above
/// [`timeline::KEY_TIME_TOL_SECS`], so that two keys never read as one.
pub const MIN_KEY_GAP_SECS: f64 = 1e-3;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum EditError {
    #[error("there is no function {0}")]
    NoFunction(usize),
    #[error("there is no key {0}")]
    NoKey(usize),
    #[error("the scene has no timeline")]
    NoTimeline,
    #[error("function {function} is not a {expected} function")]
    WrongKind { function: usize, expected: &'static str },
    #[error("grid point {point} does not exist (function {function} has {count})")]
    NoPoint { function: usize, point: usize, count: usize },
    #[error("step {step} does not exist (function {function} has {count})")]
    NoStep { function: usize, step: usize, count: usize },
    #[error("the new definition of function {function} {message}")]
    Structure { function: usize, message: String },
    #[error("function {function} is a {kind} function, which has no grid, builder or affine form")]
    NoConversion { function: usize, kind: &'static str },
    #[error("the scene is not in the state this edit expects (it was made for another scene, or edits were skipped)")]
    Stale,
}

/// One undoable change to a scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// Function `function`'s definition: in the base scene (`key: None`, both sides Some) or its
    /// override in key `key` (None: the key does not override it).
    SetFunction {
        function: usize,
        key: Option<usize>,
        before: Option<FunctionDef>,
        after: Option<FunctionDef>,
    },
    InsertKey {
        index: usize,
        key: Key,
    },
    DeleteKey {
        index: usize,
        key: Key,
    },
    /// Key `index` replaced (boxed: two keys would make every edit twice a key's size).
    ReplaceKey {
        index: usize,
        before: Box<Key>,
        after: Box<Key>,
    },
    /// Key `index` moved in time from `before_secs` to `after_secs`, staying between its
    /// neighbours (keys keep their order).
    MoveKey {
        index: usize,
        before_secs: f64,
        after_secs: f64,
    },
    /// The timeline's duration (period in loop mode).
    SetDuration {
        before: f64,
        after: f64,
    },
    /// Makes a scene animated (None → Some) or still again.
    SetTimeline {
        before: Option<Timeline>,
        after: Option<Timeline>,
    },
    /// The whole scene (adding, duplicating or deleting a function, which renumbers the
    /// functions that keys refer to).
    ReplaceScene {
        before: Box<Scene>,
        after: Box<Scene>,
    },
    /// Several edits as one gesture, applied in order and undone in reverse.
    Batch(Vec<Edit>),
}

fn function_def(scene: &Scene, function: usize, key: Option<usize>) -> Result<Option<FunctionDef>, EditError> {
    let base = &scene.functions.get(function).ok_or(EditError::NoFunction(function))?.def;
    match key {
        None => Ok(Some(base.clone())),
        Some(k) => {
            let tl = scene.timeline.as_ref().ok_or(EditError::NoTimeline)?;
            Ok(tl.keys.get(k).ok_or(EditError::NoKey(k))?.function(function).cloned())
        }
    }
}

impl Edit {
    /// Sets function `function`'s definition in the base scene or in key `key`.
    pub fn set_function(
        scene: &Scene,
        function: usize,
        key: Option<usize>,
        def: FunctionDef,
    ) -> Result<Edit, EditError> {
        let before = function_def(scene, function, key)?;
        Ok(Edit::SetFunction { function, key, before, after: Some(def) })
    }

    /// The definition a gesture starts from at `key`: the key's override, else the function's
    /// value at the key's time (so a new override continues the animation where it is).
    fn start_def(scene: &Scene, function: usize, key: Option<usize>) -> Result<FunctionDef, EditError> {
        match function_def(scene, function, key)? {
            Some(d) => Ok(d),
            None => {
                let (tl, k) = (scene.timeline.as_ref().ok_or(EditError::NoTimeline)?, key.unwrap_or(0));
                Ok(scene.function_def_at(function, tl.keys[k].t_secs))
            }
        }
    }

    /// Moves grid points `(index, new position)` of grid function `function`: one drag gesture.
    pub fn move_grid_points(
        scene: &Scene,
        function: usize,
        key: Option<usize>,
        moves: &[(usize, DVec3)],
    ) -> Result<Edit, EditError> {
        let mut def = Self::start_def(scene, function, key)?;
        let FunctionDef::Grid { points } = &mut def else {
            return Err(EditError::WrongKind { function, expected: "grid" });
        };
        for &(point, p) in moves {
            let count = points.len();
            *points.get_mut(point).ok_or(EditError::NoPoint { function, point, count })? = p;
        }
        Self::set_function(scene, function, key, def)
    }

    /// Replaces step `step` of builder function `function` (same kind and axes: parameters only
    /// when `key` is Some; any step in the base scene if no key overrides the function).
    pub fn set_step(
        scene: &Scene,
        function: usize,
        key: Option<usize>,
        step: usize,
        value: Step,
    ) -> Result<Edit, EditError> {
        let mut def = Self::start_def(scene, function, key)?;
        let FunctionDef::Builder { builder, .. } = &mut def else {
            return Err(EditError::WrongKind { function, expected: "builder" });
        };
        let count = builder.steps.len();
        *builder.steps.get_mut(step).ok_or(EditError::NoStep { function, step, count })? = value;
        Self::set_function(scene, function, key, def)
    }

    /// Sets `function`'s definition at the playhead `t_secs`: in the key there, or in a new key
    /// inserted there (making the scene animated if it was still).
    pub fn set_function_at_playhead(
        scene: &Scene,
        t_secs: f64,
        function: usize,
        def: FunctionDef,
    ) -> Result<Edit, EditError> {
        scene.functions.get(function).ok_or(EditError::NoFunction(function))?;
        if let Some(k) = scene.timeline.as_ref().and_then(|tl| tl.key_index_at(t_secs)) {
            return Self::set_function(scene, function, Some(k), def);
        }
        let mut key = Key::new(t_secs);
        key.set_function(function, Some(def));
        Self::add_key(scene, key)
    }

    /// Adds `key` (or replaces the key at its time).
    pub fn add_key(scene: &Scene, key: Key) -> Result<Edit, EditError> {
        let mut edits = Vec::new();
        let timeline = match &scene.timeline {
            Some(tl) => tl.clone(),
            None => {
                let tl = Timeline::default();
                edits.push(Edit::SetTimeline { before: None, after: Some(tl.clone()) });
                tl
            }
        };
        let edit = match timeline.key_index_at(key.t_secs) {
            Some(index) => {
                Edit::ReplaceKey { index, before: Box::new(timeline.keys[index].clone()), after: Box::new(key) }
            }
            None => {
                // Once and ping-pong: the duration grows to cover the new key.
                if timeline.loop_mode != timeline::LoopMode::Loop && key.t_secs > timeline.duration_secs {
                    edits.push(Edit::SetDuration { before: timeline.duration_secs, after: key.t_secs });
                }
                Edit::InsertKey { index: timeline.insertion_index(key.t_secs), key }
            }
        };
        edits.push(edit);
        Ok(if edits.len() == 1 { edits.remove(0) } else { Edit::Batch(edits) })
    }

    /// Deletes key `index`.
    pub fn delete_key(scene: &Scene, index: usize) -> Result<Edit, EditError> {
        let tl = scene.timeline.as_ref().ok_or(EditError::NoTimeline)?;
        Ok(Edit::DeleteKey { index, key: tl.keys.get(index).ok_or(EditError::NoKey(index))?.clone() })
    }

    /// Moves key `index` towards `t_secs`, clamped so that it stays at least
    /// [`MIN_KEY_GAP_SECS`] from its neighbours and inside the timeline (`[0, duration]`; in
    /// loop mode before the period's end, where the first key comes again).
    pub fn move_key(scene: &Scene, index: usize, t_secs: f64) -> Result<Edit, EditError> {
        let tl = scene.timeline.as_ref().ok_or(EditError::NoTimeline)?;
        let key = tl.keys.get(index).ok_or(EditError::NoKey(index))?;
        let end = if tl.loop_mode == timeline::LoopMode::Loop {
            tl.duration_secs - MIN_KEY_GAP_SECS
        } else {
            tl.duration_secs
        };
        let lo = index.checked_sub(1).map_or(0.0, |k| tl.keys[k].t_secs + MIN_KEY_GAP_SECS);
        let hi = tl.keys.get(index + 1).map_or(end, |k| k.t_secs - MIN_KEY_GAP_SECS);
        // No room between the neighbours (or a time that is not a number): the key stays.
        let after_secs = if t_secs.is_finite() && lo <= hi { t_secs.clamp(lo, hi) } else { key.t_secs };
        Ok(Edit::MoveKey { index, before_secs: key.t_secs, after_secs })
    }

    /// The edit that undoes this one.
    pub fn inverse(&self) -> Edit {
        match self.clone() {
            Edit::SetFunction { function, key, before, after } => {
                Edit::SetFunction { function, key, before: after, after: before }
            }
            Edit::InsertKey { index, key } => Edit::DeleteKey { index, key },
            Edit::DeleteKey { index, key } => Edit::InsertKey { index, key },
            Edit::ReplaceKey { index, before, after } => Edit::ReplaceKey { index, before: after, after: before },
            Edit::MoveKey { index, before_secs, after_secs } => {
                Edit::MoveKey { index, before_secs: after_secs, after_secs: before_secs }
            }
            Edit::SetTimeline { before, after } => Edit::SetTimeline { before: after, after: before },
            Edit::SetDuration { before, after } => Edit::SetDuration { before: after, after: before },
            Edit::ReplaceScene { before, after } => Edit::ReplaceScene { before: after, after: before },
            Edit::Batch(edits) => Edit::Batch(edits.iter().rev().map(Edit::inverse).collect()),
        }
    }

    /// Applies the edit. The scene must hold the edit's `before` values; on error the scene is
    /// unchanged.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), EditError> {
        if let Edit::Batch(edits) = self {
            let saved = scene.clone();
            for e in edits {
                if let Err(err) = e.apply(scene) {
                    *scene = saved;
                    return Err(err);
                }
            }
            return Ok(());
        }
        self.check(scene)?;
        match self.clone() {
            Edit::SetFunction { function, key: None, after, .. } => {
                scene.functions[function].def = after.ok_or(EditError::Stale)?;
            }
            Edit::SetFunction { function, key: Some(k), after, .. } => {
                let tl = scene.timeline.as_mut().ok_or(EditError::NoTimeline)?;
                tl.keys[k].set_function(function, after);
            }
            Edit::InsertKey { index, key } => {
                let tl = scene.timeline.as_mut().ok_or(EditError::NoTimeline)?;
                tl.keys.insert(index, key);
            }
            Edit::DeleteKey { index, .. } => {
                scene.timeline.as_mut().ok_or(EditError::NoTimeline)?.keys.remove(index);
            }
            Edit::ReplaceKey { index, after, .. } => {
                scene.timeline.as_mut().ok_or(EditError::NoTimeline)?.keys[index] = *after;
            }
            Edit::MoveKey { index, after_secs, .. } => {
                scene.timeline.as_mut().ok_or(EditError::NoTimeline)?.keys[index].t_secs = after_secs;
            }
            Edit::SetTimeline { after, .. } => scene.timeline = after,
            Edit::SetDuration { after, .. } => {
                scene.timeline.as_mut().ok_or(EditError::NoTimeline)?.duration_secs = after
            }
            Edit::ReplaceScene { after, .. } => {
                // The file the scene lives in is not part of the edit (a "save as" between an
                // edit and its undo moves the scene to another file).
                let path = scene.path.take();
                *scene = *after;
                scene.path = path;
            }
            Edit::Batch(_) => unreachable!("handled above"),
        }
        Ok(())
    }

    /// Whether the scene is in the state this edit starts from.
    fn check(&self, scene: &Scene) -> Result<(), EditError> {
        let keys = || scene.timeline.as_ref().map(|tl| &tl.keys).ok_or(EditError::NoTimeline);
        match self {
            Edit::SetFunction { function, key, before, after } => {
                if &function_def(scene, *function, *key)? != before {
                    return Err(EditError::Stale);
                }
                let base = &scene.functions[*function].def;
                // Every definition of a function must keep one structure so that keys interpolate.
                let mut others: Vec<&FunctionDef> =
                    keys().map(|ks| ks.iter().filter_map(|k| k.function(*function)).collect()).unwrap_or_default();
                if key.is_some() {
                    others = vec![base];
                }
                if let Some(after) = after {
                    for other in others {
                        spec::same_structure(other, after)
                            .map_err(|message| EditError::Structure { function: *function, message })?;
                    }
                } else if key.is_none() {
                    return Err(EditError::Stale);
                }
                Ok(())
            }
            Edit::InsertKey { index, key } => {
                let ks = keys()?;
                let sorted = *index <= ks.len()
                    && (*index == 0 || ks[index - 1].t_secs < key.t_secs)
                    && ks.get(*index).is_none_or(|k| k.t_secs > key.t_secs);
                if !sorted {
                    return Err(EditError::Stale);
                }
                Ok(())
            }
            Edit::DeleteKey { index, key } => (keys()?.get(*index) == Some(key)).then_some(()).ok_or(EditError::Stale),
            Edit::ReplaceKey { index, before, after } => {
                let ks = keys()?;
                if ks.get(*index) != Some(&**before)
                    || (after.t_secs - before.t_secs).abs() > timeline::KEY_TIME_TOL_SECS
                {
                    return Err(EditError::Stale);
                }
                Ok(())
            }
            Edit::MoveKey { index, before_secs, after_secs } => {
                let ks = keys()?;
                let tol = timeline::KEY_TIME_TOL_SECS;
                let ordered = ks.get(*index).is_some_and(|k| k.t_secs == *before_secs)
                    && after_secs.is_finite()
                    && *after_secs >= 0.0
                    && index.checked_sub(1).is_none_or(|k| ks[k].t_secs + tol < *after_secs)
                    && ks.get(index + 1).is_none_or(|k| k.t_secs - tol > *after_secs);
                ordered.then_some(()).ok_or(EditError::Stale)
            }
            Edit::SetTimeline { before, .. } => (&scene.timeline == before).then_some(()).ok_or(EditError::Stale),
            Edit::SetDuration { before, .. } => {
                let tl = scene.timeline.as_ref().ok_or(EditError::NoTimeline)?;
                (tl.duration_secs == *before).then_some(()).ok_or(EditError::Stale)
            }
            Edit::ReplaceScene { before, .. } => {
                let same = Scene { path: before.path.clone(), ..scene.clone() } == **before;
                same.then_some(()).ok_or(EditError::Stale)
            }
            Edit::Batch(_) => Ok(()),
        }
    }
}

/// Undo and redo stacks of whole gestures.
#[derive(Clone, Debug, Default)]
pub struct History {
    undo: Vec<Edit>,
    redo: Vec<Edit>,
}

impl History {
    /// Applies `edit` and makes it the latest undoable gesture (clearing the redo stack).
    pub fn apply(&mut self, scene: &mut Scene, edit: Edit) -> Result<(), EditError> {
        edit.apply(scene)?;
        self.record_applied(edit);
        Ok(())
    }

    /// Records a gesture whose effect is already in the scene (a drag previewed live).
    pub fn record_applied(&mut self, edit: Edit) {
        self.undo.push(edit);
        self.redo.clear();
    }

    /// Undoes the latest gesture; false if there is none.
    pub fn undo(&mut self, scene: &mut Scene) -> Result<bool, EditError> {
        let Some(edit) = self.undo.pop() else { return Ok(false) };
        if let Err(e) = edit.inverse().apply(scene) {
            self.undo.push(edit);
            return Err(e);
        }
        self.redo.push(edit);
        Ok(true)
    }

    /// Redoes the latest undone gesture; false if there is none.
    pub fn redo(&mut self, scene: &mut Scene) -> Result<bool, EditError> {
        let Some(edit) = self.redo.pop() else { return Ok(false) };
        if let Err(e) = edit.apply(scene) {
            self.redo.push(edit);
            return Err(e);
        }
        self.undo.push(edit);
        Ok(true)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::builder::Axis;

    const SCENE: &str = r#"
version = 1
[grid]
x = [0, 1]
y = [0, 1]
[[function]]
name = "g"
kind = "grid"
points = [[0, 0], [0, 0.5], [0.5, 0], [0.5, 0.5]]
[[function]]
name = "b"
kind = "builder"
steps = [{ op = "scale", by = 0.5 }, { op = "twist", degrees = 0 }]
"#;

    fn scene() -> Scene {
        Scene::parse(SCENE, "t.toml").unwrap()
    }

    #[test]
    fn a_drag_is_one_gesture_and_undo_redo_restore_exactly() {
        let mut s = scene();
        let original = s.clone();
        let mut h = History::default();
        let drag =
            Edit::move_grid_points(&s, 0, None, &[(1, DVec3::new(0.1, 0.6, 0.0)), (3, DVec3::new(0.6, 0.6, 0.0))])
                .unwrap();
        h.apply(&mut s, drag).unwrap();
        let moved = s.clone();
        let FunctionDef::Grid { points } = &s.functions[0].def else { panic!() };
        assert_eq!(points[1], DVec3::new(0.1, 0.6, 0.0));
        let twist = Edit::set_step(
            &s,
            1,
            None,
            1,
            Step::Twist {
                axis: Axis::Z,
                along: Axis::Y,
                degrees: 30.0,
                range: [0.0, 1.0],
                center: DVec3::new(0.5, 0.5, 0.0),
            },
        )
        .unwrap();
        h.apply(&mut s, twist).unwrap();
        let twisted = s.clone();
        assert!(h.undo(&mut s).unwrap());
        assert_eq!(s, moved);
        assert!(h.undo(&mut s).unwrap());
        assert_eq!(s, original, "one undo takes back the whole two-point drag");
        assert!(!h.undo(&mut s).unwrap());
        assert!(h.redo(&mut s).unwrap() && h.redo(&mut s).unwrap());
        assert_eq!(s, twisted);
        assert!(!h.redo(&mut s).unwrap());
    }

    #[test]
    fn keys_at_the_playhead_add_update_delete() {
        let mut s = scene();
        let original = s.clone();
        let mut h = History::default();
        // Editing at t = 2 on a still scene makes it animated with one key.
        let FunctionDef::Builder { resolution, builder } = s.functions[1].def.clone() else { panic!() };
        let mut turned = builder.clone();
        if let Step::Twist { degrees, .. } = &mut turned.steps[1] {
            *degrees = 90.0;
        }
        let def = FunctionDef::Builder { resolution, builder: turned };
        let e = Edit::set_function_at_playhead(&s, 2.0, 1, def.clone()).unwrap();
        h.apply(&mut s, e).unwrap();
        let tl = s.timeline.as_ref().unwrap();
        assert_eq!((tl.keys.len(), tl.keys[0].t_secs, tl.duration_secs), (1, 2.0, 2.0));
        assert_eq!(s.function_def_at(1, 2.0), def);
        // A second key before it, then editing the existing key updates it in place.
        let e = Edit::add_key(&s, Key::new(0.5)).unwrap();
        h.apply(&mut s, e).unwrap();
        assert_eq!(s.timeline.as_ref().unwrap().keys.len(), 2);
        let e = Edit::move_grid_points(&s, 0, Some(1), &[(0, DVec3::new(0.05, 0.0, 0.0))]).unwrap();
        h.apply(&mut s, e).unwrap();
        assert_eq!(s.timeline.as_ref().unwrap().keys[1].functions.len(), 2);
        // Structure must be kept in keys: a different step kind is refused, scene unchanged.
        let before = s.clone();
        let bad = Edit::set_step(&s, 1, Some(1), 1, Step::Translate { by: DVec3::X });
        assert!(matches!(bad.and_then(|e| h.apply(&mut s, e)), Err(EditError::Structure { .. })));
        assert_eq!(s, before);
        let e = Edit::delete_key(&s, 0).unwrap();
        h.apply(&mut s, e).unwrap();
        assert_eq!(s.timeline.as_ref().unwrap().keys.len(), 1);
        while h.undo(&mut s).unwrap() {}
        assert_eq!(s, original);
        // A stale edit (made for another state) is refused.
        let stale = Edit::delete_key(&before, 0).unwrap();
        assert_eq!(stale.apply(&mut s), Err(EditError::NoTimeline));
    }
}
