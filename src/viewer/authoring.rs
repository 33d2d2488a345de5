//! The authoring commands [`ViewerState::apply`] dispatches to: a function's kind, colour,
//! enabled flag and probability, the scene's probability mode, a builder's steps added, removed
//! and reordered, and keys dragged along the timeline. Each is an undoable edit
//! (`crate::edit`): a click is one undo step; a drag (a colour in the picker, a weight, a key)
//! runs as a gesture whose changes fold into one step, ended by [`Command::EndGesture`] like a
//! grid-point drag.
//!
//! Probabilities, as the model (`crate::model::Ifs::probabilities`) defines them: in the
//! automatic modes the scene's weights are ignored and each function's share comes from its
//! contraction; in explicit mode every function needs a weight, and the shares are the weights
//! normalized. So a weight typed while the scene is automatic first makes it explicit, with
//! every function's weight its current share, and going back to automatic clears the weights.
//!
//! [`Command::EndGesture`]: super::command::Command::EndGesture

use crate::color;
use crate::edit::{Edit, FunctionKind};
use crate::model::ProbabilityMode;
use crate::model::builder::Step;
use crate::scene::Scene;

use super::state::{Gesture, ViewerState};

/// Why a scene cannot have both xaos and adaptive probabilities (the scene check's rule).
const XAOS_NOT_ADAPTIVE: &str =
    "xaos draws the next function after the last, adaptive probabilities by the point's place: use one of them";

impl ViewerState {
    /// Changes function `function` to `kind` (one undo step) and says how close the new map is.
    pub(super) fn set_function_kind(&mut self, function: usize, kind: FunctionKind) -> bool {
        let change = match Edit::change_kind(&self.scene, function, kind) {
            Ok(Some(change)) => change,
            Ok(None) => return false,
            Err(e) => {
                self.error = Some(format!("cannot change the kind: {e}"));
                return false;
            }
        };
        let from = FunctionKind::of(&self.scene.functions[function].def).map_or("", |k| k.name());
        let name = self.scene.functions[function].name.clone();
        let how = if change.exact() {
            "the same map".to_string()
        } else {
            format!(
                "approximate: moves points by up to {:.2} % of the grid's diagonal (Undo restores the {from})",
                100.0 * change.max_deviation / change.grid_diagonal.max(f64::MIN_POSITIVE)
            )
        };
        if !self.apply_edit(change.edit) {
            return false;
        }
        if self.edit.selected_function == Some(function) {
            self.edit.selected_point = None;
        }
        let article = if kind == FunctionKind::Affine { "an" } else { "a" };
        self.message = Some(format!("{name} is now {article} {} function: {how}", kind.name()));
        // Over the view too, where the eye is: an approximate change must not pass unseen.
        self.ui.toast = self.message.clone();
        true
    }

    /// The scene with explicit probabilities: enabled functions weighted by their current
    /// share (so the picture does not change), disabled ones by the share they would have
    /// with every function on; rounded to 3 decimals for a readable file.
    fn with_explicit_weights(&self) -> Scene {
        let mut after = self.scene.clone();
        if after.probability_mode == ProbabilityMode::Explicit {
            return after;
        }
        let shares = self.scene.at(self.t_secs).probabilities();
        let mut all_on = self.scene.clone();
        all_on.functions.iter_mut().for_each(|f| f.enabled = true);
        let shares_all_on = all_on.at(self.t_secs).probabilities();
        for (i, f) in after.functions.iter_mut().enumerate() {
            let share = if f.enabled { shares[i] } else { shares_all_on[i] };
            f.probability = Some(((share * 1e3).round() / 1e3).max(1e-3));
        }
        after.probability_mode = ProbabilityMode::Explicit;
        after
    }

    /// Sets the probability mode (one undo step).
    pub(super) fn set_probability_mode(&mut self, mode: ProbabilityMode) -> bool {
        if mode == self.scene.probability_mode {
            return false;
        }
        if mode == ProbabilityMode::Adaptive && self.scene.functions.iter().any(|f| !f.xaos.is_empty()) {
            self.error = Some(XAOS_NOT_ADAPTIVE.into());
            return false;
        }
        let after = if mode == ProbabilityMode::Explicit {
            self.with_explicit_weights()
        } else {
            let mut after = self.scene.clone();
            after.probability_mode = mode;
            after.functions.iter_mut().for_each(|f| f.probability = None);
            after
        };
        self.apply_edit(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) })
    }

    /// Sets function `function`'s weight (part of the running gesture); a weight on an
    /// automatic scene makes it explicit. None clears the weight where the mode ignores it; an
    /// explicit scene needs every weight, so there it is refused.
    pub(super) fn set_function_probability(&mut self, function: usize, probability: Option<f64>) -> bool {
        if function >= self.scene.functions.len() {
            return false;
        }
        let mut after = match probability {
            Some(w) if w.is_finite() => self.with_explicit_weights(),
            Some(_) => return false,
            None if self.scene.probability_mode == ProbabilityMode::Explicit => {
                self.error = Some(
                    "explicit probabilities need a weight on every function; choose an automatic mode instead".into(),
                );
                return false;
            }
            None => self.scene.clone(),
        };
        after.functions[function].probability = probability.map(|w| w.max(0.0));
        self.preview_scene(after)
    }

    /// Sets function `function`'s xaos multiplier of function `to` (part of the running
    /// gesture); a row of only 1s is cleared.
    pub(super) fn set_function_xaos(&mut self, function: usize, to: usize, value: f64) -> bool {
        let n = self.scene.functions.len();
        if function >= n || to >= n || !(value.is_finite() && value >= 0.0) {
            return false;
        }
        if self.scene.probability_mode == ProbabilityMode::Adaptive {
            self.error = Some(XAOS_NOT_ADAPTIVE.into());
            return false;
        }
        let mut after = self.scene.clone();
        let row = &mut after.functions[function].xaos;
        if row.len() <= to {
            row.resize(to + 1, 1.0);
        }
        row[to] = value;
        if row.iter().all(|&v| v == 1.0) {
            row.clear();
        }
        self.preview_scene(after)
    }

    /// Sets function `function`'s colour (linear RGB; part of the running gesture), snapped to
    /// the nearest 8-bit sRGB colour: what the picker shows, and what the scene file writes as
    /// hex and reads back exactly.
    pub(super) fn set_function_color(&mut self, function: usize, color: [f32; 3]) -> bool {
        if function >= self.scene.functions.len() || color.iter().any(|c| !c.is_finite()) {
            return false;
        }
        let mut after = self.scene.clone();
        after.functions[function].color = color.map(|c| color::srgb8_to_linear(color::linear_to_srgb8(c)));
        self.preview_scene(after)
    }

    /// Sets the final xform's numbers (part of the running gesture): the same variations and
    /// post-affine, as a flame function's edit keeps them; the final xform is not keyed.
    pub(super) fn set_final_xform(&mut self, value: crate::scene::spec::FinalXform) -> bool {
        use crate::scene::spec::{FunctionDef, same_structure};
        let Some(current) = &self.scene.final_xform else { return false };
        let (a, b) = (FunctionDef::Flame(current.def.clone()), FunctionDef::Flame(value.def.clone()));
        if *current == value || same_structure(&a, &b).is_err() || !(0.0..=1.0).contains(&value.palette_index) {
            return false;
        }
        let mut after = self.scene.clone();
        after.final_xform = Some(value);
        self.preview_scene(after)
    }

    /// Sets the variations of flame function `function` (None: the final xform's), one added
    /// or removed: one undo step. Refused, with a message, where a key of the timeline holds the
    /// function (the key holds the numbers of the other list), and for an empty list.
    pub(super) fn set_flame_variations(
        &mut self,
        function: Option<usize>,
        variations: Vec<crate::flame::VariationTerm>,
    ) -> bool {
        use crate::scene::spec::FunctionDef;
        if variations.is_empty() {
            return false;
        }
        if let Some(i) = function.filter(|&i| self.scene.is_keyed(i)) {
            let name = self.scene.functions.get(i).map_or("", |f| f.name.as_str());
            self.error = Some(format!(
                "`{name}` is keyed on the timeline: remove its keys before adding or removing a variation"
            ));
            return false;
        }
        let mut after = self.scene.clone();
        let def = match function {
            Some(i) => match after.functions.get_mut(i).map(|f| &mut f.def) {
                Some(FunctionDef::Flame(def)) => def,
                _ => return false,
            },
            None => match &mut after.final_xform {
                Some(f) => &mut f.def,
                None => return false,
            },
        };
        if def.variations == variations {
            return false;
        }
        def.variations = variations;
        self.apply_edit(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) })
    }

    /// Turns function `function` on or off (one undo step).
    pub(super) fn set_function_enabled(&mut self, function: usize, enabled: bool) -> bool {
        let Some(f) = self.scene.functions.get(function) else { return false };
        if f.enabled == enabled {
            return false;
        }
        let mut after = self.scene.clone();
        after.functions[function].enabled = enabled;
        self.apply_edit(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) })
    }

    /// Shows `after` now as part of the running gesture: a drag's many changes fold into one
    /// whole-scene edit (before of the first, after of the last).
    pub(super) fn preview_scene(&mut self, after: Scene) -> bool {
        if after == self.scene {
            return false;
        }
        let folds = matches!(self.edit.gesture.as_ref().and_then(|g| g.edits.last()), Some(Edit::ReplaceScene { .. }));
        if !folds {
            self.end_gesture();
        }
        let before = std::mem::replace(&mut self.scene, after.clone());
        let edits = &mut self.edit.gesture.get_or_insert_with(Gesture::default).edits;
        match edits.last_mut() {
            Some(Edit::ReplaceScene { after: last, .. }) if folds => **last = after,
            _ => edits.push(Edit::ReplaceScene { before: Box::new(before), after: Box::new(after) }),
        }
        true
    }

    /// Inserts `step` at `index` of builder `function` (one undo step); its axes must be ones
    /// the scene's dimension allows, so that the saved file reads back.
    pub(super) fn insert_builder_step(&mut self, function: usize, index: usize, step: Step) -> bool {
        let dim = self.scene.domain.dimension();
        if let Some(axes) = step.axes()
            && !Step::axis_choices(step.kind(), dim).contains(&axes)
        {
            self.error = Some(format!("a {dim}D scene has no {} step with these axes", step.kind().name()));
            return false;
        }
        let edit = Edit::insert_step(&self.scene, function, index, step);
        self.apply_or_report(edit)
    }

    pub(super) fn remove_builder_step(&mut self, function: usize, step: usize) -> bool {
        let edit = Edit::remove_step(&self.scene, function, step);
        self.apply_or_report(edit)
    }

    pub(super) fn move_builder_step(&mut self, function: usize, from: usize, to: usize) -> bool {
        if from == to {
            return false;
        }
        let edit = Edit::move_step(&self.scene, function, from, to);
        self.apply_or_report(edit)
    }

    fn apply_or_report(&mut self, edit: Result<Edit, crate::edit::EditError>) -> bool {
        match edit {
            Ok(e) => self.apply_edit(e),
            Err(e) => {
                self.error = Some(format!("edit refused: {e}"));
                false
            }
        }
    }

    /// Moves key `key` towards `t_secs` (clamped; part of the running gesture, so that one drag
    /// is one undo step).
    pub(super) fn move_key(&mut self, key: usize, t_secs: f64) -> bool {
        let edit = match Edit::move_key(&self.scene, key, t_secs) {
            Ok(edit) => edit,
            Err(e) => {
                self.error = Some(format!("cannot move the key: {e}"));
                return false;
            }
        };
        let Edit::MoveKey { index, before_secs, after_secs } = edit else { return false };
        if after_secs == before_secs {
            return false;
        }
        let folds = matches!(
            self.edit.gesture.as_ref().and_then(|g| g.edits.last()),
            Some(Edit::MoveKey { index: i, .. }) if *i == index
        );
        if !folds {
            self.end_gesture();
        }
        if let Err(e) = edit.apply(&mut self.scene) {
            self.error = Some(format!("cannot move the key: {e}"));
            return false;
        }
        let edits = &mut self.edit.gesture.get_or_insert_with(Gesture::default).edits;
        match edits.last_mut() {
            Some(Edit::MoveKey { after_secs: last, .. }) if folds => *last = after_secs,
            _ => edits.push(edit),
        }
        true
    }
}
