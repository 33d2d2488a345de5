//! Grid builders: Barr's global deformations (taper, twist, bend; A. H. Barr, "Global and Local
//! Deformations of Solid Primitives", 1984) composed with affine steps. A builder stays a list
//! of parameters (so the viewer can edit it and the timeline can animate it) and is resolved to
//! grid points by applying its steps in order to every point of a grid.

use glam::{DMat3, DVec3};

/// An axis of the scene's coordinate frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub fn index(self) -> usize {
        self as usize
    }

    /// The two other axes, in right-handed order (so that (a, b) rotate like (x, y) about z).
    pub fn others(self) -> (usize, usize) {
        match self {
            Axis::X => (1, 2),
            Axis::Y => (2, 0),
            Axis::Z => (0, 1),
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "z" => Some(Axis::Z),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        ["x", "y", "z"][self.index()]
    }
}

/// One step of a builder. Deformations act about `center` (default: the scene grid's centre)
/// and vary along `axis` over `range` (default: the grid's extent along `axis`); outside the
/// range the deformation of the nearest range end applies, as in Barr's paper.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Scales by `by` about `center`.
    Scale {
        by: DVec3,
        center: DVec3,
    },
    /// Rotates by `degrees` about `axis` through `center`.
    Rotate {
        axis: Axis,
        degrees: f64,
        center: DVec3,
    },
    Translate {
        by: DVec3,
    },
    /// Barr's taper: the coordinates across `axis` are scaled, about `center`, by a factor that
    /// goes linearly from 1 at the start of `range` to `1 - amount` at its end.
    Taper {
        axis: Axis,
        amount: f64,
        range: [f64; 2],
        center: DVec3,
    },
    /// Barr's twist: rotation about `axis` through `center` by an angle growing linearly from 0
    /// at the start of `range` to `degrees` at its end, the range measured along `along` (the
    /// rotation axis itself in 3D; in 2D the rotation is about z and the angle grows along x or y).
    Twist {
        axis: Axis,
        along: Axis,
        degrees: f64,
        range: [f64; 2],
        center: DVec3,
    },
    /// Barr's bend: the part of the shape along `axis` within `range` is bent towards the
    /// `toward` axis by a total angle of `degrees` (radius = range length / angle); beyond the
    /// range it continues straight along the bent tangent.
    Bend {
        axis: Axis,
        toward: Axis,
        degrees: f64,
        range: [f64; 2],
        center: DVec3,
    },
    /// A general affine step p' = matrix * p + offset.
    Affine {
        matrix: DMat3,
        offset: DVec3,
    },
}

/// What a step does, without its numbers: the choice offered when a step is added.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepKind {
    Scale,
    Rotate,
    Translate,
    Taper,
    Twist,
    Bend,
    Affine,
}

impl StepKind {
    pub const ALL: [StepKind; 7] = [
        StepKind::Scale,
        StepKind::Rotate,
        StepKind::Translate,
        StepKind::Taper,
        StepKind::Twist,
        StepKind::Bend,
        StepKind::Affine,
    ];

    /// The step's `op` in the scene format.
    pub fn name(self) -> &'static str {
        match self {
            StepKind::Scale => "scale",
            StepKind::Rotate => "rotate",
            StepKind::Translate => "translate",
            StepKind::Taper => "taper",
            StepKind::Twist => "twist",
            StepKind::Bend => "bend",
            StepKind::Affine => "affine",
        }
    }
}

/// Linear ramp from 0 at `range[0]` to 1 at `range[1]`, clamped.
fn ramp(x: f64, range: [f64; 2]) -> f64 {
    let len = range[1] - range[0];
    if len.abs() < 1e-300 {
        return if x >= range[1] { 1.0 } else { 0.0 };
    }
    ((x - range[0]) / len).clamp(0.0, 1.0)
}

fn rotate_about(p: DVec3, axis: Axis, radians: f64, center: DVec3) -> DVec3 {
    let (a, b) = axis.others();
    let d = p - center;
    let (s, c) = radians.sin_cos();
    let mut out = d;
    out[a] = c * d[a] - s * d[b];
    out[b] = s * d[a] + c * d[b];
    center + out
}

impl Step {
    pub fn kind(&self) -> StepKind {
        match self {
            Step::Scale { .. } => StepKind::Scale,
            Step::Rotate { .. } => StepKind::Rotate,
            Step::Translate { .. } => StepKind::Translate,
            Step::Taper { .. } => StepKind::Taper,
            Step::Twist { .. } => StepKind::Twist,
            Step::Bend { .. } => StepKind::Bend,
            Step::Affine { .. } => StepKind::Affine,
        }
    }

    /// A step of `kind` that changes nothing (scale 1, angle 0, amount 0, the identity), on the
    /// grid box [`lo`, `hi`] of dimension `dim`: centred on the box, its range the box's extent
    /// along the step's axis, with the axes the scene format defaults to (y in 3D; in 2D
    /// rotations and twists about z, the twist growing along y, the bend from y towards x).
    /// Added to a builder it leaves the map as it was, and its parameters then shape it.
    pub fn identity(kind: StepKind, dim: usize, lo: DVec3, hi: DVec3) -> Step {
        let center = 0.5 * (lo + hi);
        let range = |a: Axis| [lo[a.index()], hi[a.index()]];
        let about = if dim == 2 { Axis::Z } else { Axis::Y };
        match kind {
            StepKind::Scale => Step::Scale { by: DVec3::ONE, center },
            StepKind::Rotate => Step::Rotate { axis: about, degrees: 0.0, center },
            StepKind::Translate => Step::Translate { by: DVec3::ZERO },
            StepKind::Taper => Step::Taper { axis: Axis::Y, amount: 0.0, range: range(Axis::Y), center },
            StepKind::Twist => Step::Twist { axis: about, along: Axis::Y, degrees: 0.0, range: range(Axis::Y), center },
            StepKind::Bend => {
                Step::Bend { axis: Axis::Y, toward: Axis::X, degrees: 0.0, range: range(Axis::Y), center }
            }
            StepKind::Affine => {
                // A 2D affine map has zeros in its z row and column, as the scene format reads it.
                let matrix = if dim == 2 { DMat3::from_diagonal(DVec3::new(1.0, 1.0, 0.0)) } else { DMat3::IDENTITY };
                Step::Affine { matrix, offset: DVec3::ZERO }
            }
        }
    }

    /// The step's axes: (`axis`, the second axis: `along` for a twist, `toward` for a bend, else
    /// `axis` again); None for the steps without an axis.
    pub fn axes(&self) -> Option<(Axis, Axis)> {
        match *self {
            Step::Rotate { axis, .. } | Step::Taper { axis, .. } => Some((axis, axis)),
            Step::Twist { axis, along, .. } => Some((axis, along)),
            Step::Bend { axis, toward, .. } => Some((axis, toward)),
            _ => None,
        }
    }

    /// The axes a step of `kind` may have in `dim` dimensions, as the scene format accepts them
    /// (in 2D rotations and twists turn about z, tapers and bends stay in the x-y plane).
    pub fn axis_choices(kind: StepKind, dim: usize) -> Vec<(Axis, Axis)> {
        let plane: &[Axis] = if dim == 2 { &[Axis::X, Axis::Y] } else { &[Axis::X, Axis::Y, Axis::Z] };
        match kind {
            StepKind::Rotate if dim == 2 => vec![(Axis::Z, Axis::Z)],
            StepKind::Twist if dim == 2 => plane.iter().map(|&a| (Axis::Z, a)).collect(),
            StepKind::Rotate | StepKind::Taper | StepKind::Twist => plane.iter().map(|&a| (a, a)).collect(),
            StepKind::Bend => {
                plane.iter().flat_map(|&a| plane.iter().filter(move |&&t| t != a).map(move |&t| (a, t))).collect()
            }
            _ => Vec::new(),
        }
    }

    /// The step with axes `axes` (see [`Step::axes`]) and its range the grid box [`lo`, `hi`]'s
    /// extent along the axis it varies along; unchanged for a step without axes.
    pub fn with_axes(mut self, axes: (Axis, Axis), lo: DVec3, hi: DVec3) -> Step {
        let extent = |a: Axis| [lo[a.index()], hi[a.index()]];
        match &mut self {
            Step::Rotate { axis, .. } => *axis = axes.0,
            Step::Taper { axis, range, .. } => (*axis, *range) = (axes.0, extent(axes.0)),
            Step::Twist { axis, along, range, .. } => (*axis, *along, *range) = (axes.0, axes.1, extent(axes.1)),
            Step::Bend { axis, toward, range, .. } => (*axis, *toward, *range) = (axes.0, axes.1, extent(axes.0)),
            _ => {}
        }
        self
    }

    pub fn apply(&self, p: DVec3) -> DVec3 {
        match *self {
            Step::Scale { by, center } => center + (p - center) * by,
            Step::Rotate { axis, degrees, center } => rotate_about(p, axis, degrees.to_radians(), center),
            Step::Translate { by } => p + by,
            Step::Taper { axis, amount, range, center } => {
                let k = 1.0 - amount * ramp(p[axis.index()], range);
                let (a, b) = axis.others();
                let mut out = p;
                out[a] = center[a] + k * (p[a] - center[a]);
                out[b] = center[b] + k * (p[b] - center[b]);
                out
            }
            Step::Twist { axis, along, degrees, range, center } => {
                let angle = degrees.to_radians() * ramp(p[along.index()], range);
                rotate_about(p, axis, angle, center)
            }
            Step::Bend { axis, toward, degrees, range, center } => bend(p, axis, toward, degrees, range, center),
            Step::Affine { matrix, offset } => matrix * p + offset,
        }
    }
}

/// Barr's bend (his equations for bending along y towards z, generalised to any axis pair):
/// coordinates along `axis` in `range` are wrapped onto a circular arc of radius
/// r = (range length) / angle whose centre lies at `center` + r along `toward`.
fn bend(p: DVec3, axis: Axis, toward: Axis, degrees: f64, range: [f64; 2], center: DVec3) -> DVec3 {
    let (ia, it) = (axis.index(), toward.index());
    if ia == it || degrees.abs() < 1e-12 {
        return p;
    }
    let len = range[1] - range[0];
    if len.abs() < 1e-300 {
        return p;
    }
    let k = degrees.to_radians() / len; // bend rate: radians per unit length
    let y = p[ia];
    let y_hat = y.clamp(range[0].min(range[1]), range[0].max(range[1]));
    let theta = k * (y_hat - range[0]);
    let (s, c) = theta.sin_cos();
    let z = p[it] - center[it];
    let r = 1.0 / k;
    let mut out = p;
    // Inside the range: the point moves onto the arc; beyond it: along the tangent.
    out[ia] = range[0] - s * (z - r) + c * (y - y_hat);
    out[it] = center[it] + c * (z - r) + r + s * (y - y_hat);
    out
}

/// A builder: its steps, applied in order.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Builder {
    pub steps: Vec<Step>,
}

impl Builder {
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.steps.iter().fold(p, |q, s| s.apply(q))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_steps_change_nothing() {
        let (lo, hi) = (DVec3::new(-1.0, 0.0, 2.0), DVec3::new(3.0, 5.0, 4.0));
        for dim in [2usize, 3] {
            for kind in StepKind::ALL {
                let step = Step::identity(kind, dim, lo, hi);
                assert_eq!(step.kind(), kind);
                for k in 0..27 {
                    let t = DVec3::new((k % 3) as f64, ((k / 3) % 3) as f64, (k / 9) as f64) / 2.0;
                    let mut p = lo + (hi - lo) * t;
                    if dim == 2 {
                        p.z = 0.0;
                    }
                    assert!(step.apply(p).distance(p) < 1e-12, "{kind:?} in {dim}D moved {p}");
                }
            }
        }
    }

    #[test]
    fn every_axis_choice_keeps_the_identity_and_reads_back() {
        let (lo, hi) = (DVec3::new(-1.0, 0.0, 2.0), DVec3::new(3.0, 5.0, 4.0));
        for dim in [2usize, 3] {
            for kind in StepKind::ALL {
                for axes in Step::axis_choices(kind, dim) {
                    let step = Step::identity(kind, dim, lo, hi).with_axes(axes, lo, hi);
                    assert_eq!(step.axes(), Some(axes), "{kind:?} {dim}D");
                    let p = DVec3::new(0.5, 1.5, if dim == 3 { 3.0 } else { 0.0 });
                    assert!(step.apply(p).distance(p) < 1e-12, "{kind:?} {axes:?} moved {p}");
                }
            }
        }
        // The format's defaults are among the choices.
        for dim in [2usize, 3] {
            for kind in [StepKind::Rotate, StepKind::Taper, StepKind::Twist, StepKind::Bend] {
                let default = Step::identity(kind, dim, lo, hi).axes().unwrap();
                assert!(Step::axis_choices(kind, dim).contains(&default), "{kind:?} {dim}D");
            }
        }
    }

    #[test]
    fn taper_scales_linearly() {
        let s = Step::Taper { axis: Axis::Y, amount: 0.5, range: [0.0, 10.0], center: DVec3::ZERO };
        assert!(s.apply(DVec3::new(2.0, 0.0, 2.0)).distance(DVec3::new(2.0, 0.0, 2.0)) < 1e-12);
        assert!(s.apply(DVec3::new(2.0, 10.0, 2.0)).distance(DVec3::new(1.0, 10.0, 1.0)) < 1e-12);
        assert!(s.apply(DVec3::new(2.0, 5.0, 2.0)).distance(DVec3::new(1.5, 5.0, 1.5)) < 1e-12);
    }

    #[test]
    fn twist_rotates_by_height() {
        let s = Step::Twist { axis: Axis::Y, along: Axis::Y, degrees: 90.0, range: [0.0, 1.0], center: DVec3::ZERO };
        // About y, (z, x) rotate like (x, y): z -> x.
        let top = s.apply(DVec3::new(0.0, 1.0, 1.0));
        assert!(top.distance(DVec3::new(1.0, 1.0, 0.0)) < 1e-12, "{top}");
        assert!(s.apply(DVec3::new(0.0, 0.0, 1.0)).distance(DVec3::new(0.0, 0.0, 1.0)) < 1e-12);
    }

    #[test]
    fn bend_preserves_length_along_axis() {
        // A bend wraps the axis segment onto an arc: arc length equals the segment length.
        let s = Step::Bend { axis: Axis::Y, toward: Axis::X, degrees: 90.0, range: [0.0, 1.0], center: DVec3::ZERO };
        let n = 1000;
        let pts: Vec<DVec3> = (0..=n).map(|i| s.apply(DVec3::new(0.0, i as f64 / n as f64, 0.0))).collect();
        let length: f64 = pts.windows(2).map(|w| w[0].distance(w[1])).sum();
        assert!((length - 1.0).abs() < 1e-5, "length {length}");
        // The end tangent is turned by 90°: the end point is at (r, r) with r = 2/π.
        let r = 2.0 / std::f64::consts::PI;
        assert!(pts[n].distance(DVec3::new(r, r, 0.0)) < 1e-9, "{}", pts[n]);
    }
}
