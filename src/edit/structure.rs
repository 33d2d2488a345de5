//! Edits of a function's structure: its kind (grid, builder, affine) and a builder's list of
//! steps (added, removed, reordered). Every definition of a function, the base one and each
//! key's override, must keep one structure so that keys interpolate, so each of these edits
//! changes all of them the same way and is one [`Edit::ReplaceScene`].
//!
//! Changing the kind keeps the map as close as the new kind allows: an affine map sampled on
//! the grid is the same map (bilinear or trilinear interpolation reproduces an affine map), a
//! grid or builder becomes the least-squares affine fit of its grid points
//! (`crate::model::fit`), a builder becomes a grid through its resolved map sampled at the
//! scene grid's points, and a grid or affine map becomes a builder of one affine step (the fit,
//! or the map itself). [`KindChange`] says how far the new map lies from the old one, measured
//! on a sample twice as fine as either grid, so that the viewer can say when a change was only
//! approximate. The Julia maps have no such form and are refused.

use glam::DVec3;

use crate::model::builder::{Builder, Step};
use crate::model::fit::fit_affine;
use crate::model::{AffineMap, Map, RectGrid};
use crate::scene::Scene;
use crate::scene::spec::FunctionDef;

use super::{Edit, EditError};

/// The kinds a function can be changed between.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FunctionKind {
    Grid,
    Builder,
    Affine,
}

impl FunctionKind {
    pub const ALL: [FunctionKind; 3] = [FunctionKind::Grid, FunctionKind::Builder, FunctionKind::Affine];

    /// The kind's name in the scene format.
    pub fn name(self) -> &'static str {
        match self {
            FunctionKind::Grid => "grid",
            FunctionKind::Builder => "builder",
            FunctionKind::Affine => "affine",
        }
    }

    /// The kind of `def`; None for a Julia map or a flame.
    pub fn of(def: &FunctionDef) -> Option<FunctionKind> {
        match def {
            FunctionDef::Grid { .. } => Some(FunctionKind::Grid),
            FunctionDef::Builder { .. } => Some(FunctionKind::Builder),
            FunctionDef::Affine(_) => Some(FunctionKind::Affine),
            FunctionDef::Julia(_) | FunctionDef::Flame(_) => None,
        }
    }

    /// How a change from `self` to `to` keeps the map, in a few words.
    pub fn conversion_note(self, to: FunctionKind) -> &'static str {
        use FunctionKind::*;
        match (self, to) {
            (a, b) if a == b => "unchanged",
            (Affine, _) => "exact: the same affine map",
            (Grid, Affine) => "least-squares affine fit of the grid points (exact only for an affine grid)",
            (Grid, Builder) => {
                "a builder of one affine step, the grid's least-squares fit (exact only for an affine grid)"
            }
            (Builder, Grid) => {
                "the built map sampled on the scene grid (exact when the grids agree or the steps are affine)"
            }
            (Builder, Affine) => "least-squares affine fit of the built grid (exact only for affine steps)",
            _ => "",
        }
    }
}

/// A change of kind: the edit, and how far the new map lies from the old one.
#[derive(Clone, Debug, PartialEq)]
pub struct KindChange {
    pub edit: Edit,
    /// The largest distance between the old and the new map's images of the sample points,
    /// over the base definition and every key's override (world units).
    pub max_deviation: f64,
    /// The length of the scene grid's diagonal, the scale of `max_deviation`.
    pub grid_diagonal: f64,
}

/// A deviation up to this share of the grid's diagonal is rounding, and the change exact: the
/// fit and the sampling each cost a few ulps of the coordinates, far below 1e-9.
pub const CONVERSION_EXACT_TOL_REL: f64 = 1e-9;

impl KindChange {
    pub fn exact(&self) -> bool {
        self.max_deviation <= CONVERSION_EXACT_TOL_REL * self.grid_diagonal
    }
}

/// The resolution a new builder samples its steps at: the scene format's default.
fn default_resolution(dim: usize) -> [usize; 3] {
    if dim == 3 { [5, 5, 5] } else { [9, 9, 1] }
}

/// `def` as a definition of kind `to` over `scene`'s grid; None when it has no such form.
pub fn convert(scene: &Scene, def: &FunctionDef, to: FunctionKind) -> Option<FunctionDef> {
    let domain = &scene.domain;
    let dim = domain.dimension();
    let affine_of = |def: &FunctionDef| -> Option<AffineMap> {
        match def {
            FunctionDef::Affine(a) => Some(a.clone()),
            FunctionDef::Grid { points } => fit_affine(&domain.points(), points, dim),
            FunctionDef::Builder { resolution, builder } => {
                let from = RectGrid::uniform(domain.min(), domain.max(), *resolution).points();
                let to: Vec<DVec3> = from.iter().map(|&p| builder.apply(p)).collect();
                fit_affine(&from, &to, dim)
            }
            FunctionDef::Julia(_) | FunctionDef::Flame(_) => None,
        }
    };
    let from = FunctionKind::of(def)?;
    if from == to {
        return Some(def.clone());
    }
    Some(match to {
        FunctionKind::Grid => {
            let map = scene.resolve(def);
            FunctionDef::Grid { points: domain.points().into_iter().map(|p| map.eval(p)).collect() }
        }
        FunctionKind::Affine => FunctionDef::Affine(affine_of(def)?),
        FunctionKind::Builder => {
            let a = affine_of(def)?;
            FunctionDef::Builder {
                resolution: default_resolution(dim),
                builder: Builder { steps: vec![Step::Affine { matrix: a.matrix, offset: a.offset }] },
            }
        }
    })
}

/// The largest distance between the images of `a` and `b` on a uniform sample of the grid's box
/// with about twice as many points per axis as the finer of the maps' grids (cell centres
/// included, where bilinear pieces of different grids differ most), at most 33 per axis.
fn max_deviation(domain: &RectGrid, a: &Map, b: &Map) -> f64 {
    let per_axis = |m: &Map| match m {
        Map::Grid(g) => g.grid.dims(),
        _ => [2, 2, 2],
    };
    let (da, db, dd) = (per_axis(a), per_axis(b), domain.dims());
    let counts: [usize; 3] = std::array::from_fn(|k| {
        if k == 2 && domain.dimension() == 2 { 1 } else { (2 * da[k].max(db[k]).max(dd[k]) - 1).clamp(3, 33) }
    });
    RectGrid::uniform(domain.min(), domain.max(), counts)
        .points()
        .into_iter()
        .map(|p| a.eval(p).distance(b.eval(p)))
        .fold(0.0, f64::max)
}

impl Edit {
    /// Changes function `function` to kind `to`, in the base scene and in every key (None when
    /// it is of that kind already).
    pub fn change_kind(scene: &Scene, function: usize, to: FunctionKind) -> Result<Option<KindChange>, EditError> {
        let spec = scene.functions.get(function).ok_or(EditError::NoFunction(function))?;
        let refuse = || EditError::NoConversion {
            function,
            kind: match &spec.def {
                FunctionDef::Julia(_) => "julia",
                FunctionDef::Flame(_) => "flame",
                _ => "degenerate",
            },
        };
        if FunctionKind::of(&spec.def).ok_or_else(refuse)? == to {
            return Ok(None);
        }
        let mut after = scene.clone();
        let mut deviation = 0.0f64;
        let mut change = |def: &mut FunctionDef| -> Result<(), EditError> {
            let new = convert(scene, def, to).ok_or_else(refuse)?;
            deviation = deviation.max(max_deviation(&scene.domain, &scene.resolve(def), &scene.resolve(&new)));
            *def = new;
            Ok(())
        };
        change(&mut after.functions[function].def)?;
        if let Some(tl) = &mut after.timeline {
            for key in &mut tl.keys {
                if let Some(mut def) = key.function(function).cloned() {
                    change(&mut def)?;
                    key.set_function(function, Some(def));
                }
            }
        }
        Ok(Some(KindChange {
            edit: Edit::ReplaceScene { before: Box::new(scene.clone()), after: Box::new(after) },
            max_deviation: deviation,
            grid_diagonal: (scene.domain.max() - scene.domain.min()).length(),
        }))
    }

    /// Inserts `step` at position `index` of builder function `function`'s steps (the same
    /// step in every key, so that keys keep animating what they did).
    pub fn insert_step(scene: &Scene, function: usize, index: usize, step: Step) -> Result<Edit, EditError> {
        Self::check_step(scene, function, index, 1)?;
        Self::edit_steps(scene, function, |steps| steps.insert(index, step.clone()))
    }

    /// Removes step `step` of builder function `function`, in the base scene and every key.
    pub fn remove_step(scene: &Scene, function: usize, step: usize) -> Result<Edit, EditError> {
        Self::check_step(scene, function, step, 0)?;
        Self::edit_steps(scene, function, |steps| {
            steps.remove(step);
        })
    }

    /// Moves step `from` of builder function `function` to position `to` (the others shift),
    /// in the base scene and every key.
    pub fn move_step(scene: &Scene, function: usize, from: usize, to: usize) -> Result<Edit, EditError> {
        Self::check_step(scene, function, from.max(to), 0)?;
        Self::edit_steps(scene, function, |steps| {
            let s = steps.remove(from);
            steps.insert(to, s);
        })
    }

    /// Whether `function` is a builder with a step `step` (or, with `past_end` 1, a place
    /// `step` to insert at: up to one past the last step).
    fn check_step(scene: &Scene, function: usize, step: usize, past_end: usize) -> Result<(), EditError> {
        let spec = scene.functions.get(function).ok_or(EditError::NoFunction(function))?;
        let FunctionDef::Builder { builder, .. } = &spec.def else {
            return Err(EditError::WrongKind { function, expected: "builder" });
        };
        let count = builder.steps.len();
        if step >= count + past_end {
            return Err(EditError::NoStep { function, step, count });
        }
        Ok(())
    }

    /// Applies `change` to the steps of every definition of builder function `function`.
    fn edit_steps(scene: &Scene, function: usize, change: impl Fn(&mut Vec<Step>)) -> Result<Edit, EditError> {
        let mut after = scene.clone();
        let steps_of = |def: &mut FunctionDef, change: &dyn Fn(&mut Vec<Step>)| {
            if let FunctionDef::Builder { builder, .. } = def {
                change(&mut builder.steps);
            }
        };
        steps_of(&mut after.functions[function].def, &change);
        if let Some(tl) = &mut after.timeline {
            for key in &mut tl.keys {
                if let Some(mut def) = key.function(function).cloned() {
                    steps_of(&mut def, &change);
                    key.set_function(function, Some(def));
                }
            }
        }
        Ok(Edit::ReplaceScene { before: Box::new(scene.clone()), after: Box::new(after) })
    }
}
