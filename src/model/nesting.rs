//! The nesting view of the paper's plates 5 and 7: W^k(A) for the domain box A, the images of
//! the initial grid's box under every composition f_i1 ∘ … ∘ f_ik of k enabled functions.
//! W^0 is the box itself, W^1 shows how each function places its copy, and the boxes of W^k
//! shrink onto the attractor as k grows.
//!
//! A box is kept as its faces sampled on a small lattice (one face in 2D, six in 3D), because a
//! nonlinear map bends the straight edges: the samples are mapped, not the corners. W^k is built
//! as W(W^(k-1)) = ∪_i f_i(W^(k-1)), so box `b` of level k carries the word's outermost function
//! (the colour the view draws it in). With xaos a copy f_i(b) is left out where f_i may not
//! follow b's outermost function ([`Ifs::xaos_successors`]: the chaos game never applies them in
//! that order). The count of boxes is at most m^k for m enabled functions, so a level is
//! refused past [`MAX_NESTED_BOXES`].

use glam::DVec3;

use super::Ifs;

/// The most boxes one nesting level may hold (m^k): past it the picture is a haze of lines and
/// the mapping takes more than a frame.
pub const MAX_NESTED_BOXES: usize = 4096;

/// Samples along each side of a face (the face is a `FACE_SAMPLES` × `FACE_SAMPLES` lattice):
/// enough for the bend of one level's maps to read as a curve.
pub const FACE_SAMPLES: usize = 5;

/// One face of a mapped box: `FACE_SAMPLES`² points, row-major (u fastest).
pub type Face = Vec<DVec3>;

/// One box of W^k(A): the outermost function of its word (None for W^0) and its faces.
#[derive(Clone, Debug, PartialEq)]
pub struct NestedBox {
    pub outer_function: Option<usize>,
    pub faces: Vec<Face>,
}

/// Why a nesting level cannot be shown.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NestingError {
    #[error("W^{level} of {functions} functions has {boxes} boxes, more than the {max} the view draws")]
    TooManyBoxes { level: u32, functions: usize, boxes: u128, max: usize },
}

/// The deepest level whose box count m^k stays within [`MAX_NESTED_BOXES`] for `functions`
/// enabled functions (m ≤ 1 has no limit worth drawing past; it is capped at 16).
pub fn max_level(functions: usize) -> u32 {
    if functions <= 1 {
        return 16;
    }
    let mut level = 0;
    let mut boxes = 1usize;
    while boxes * functions <= MAX_NESTED_BOXES {
        boxes *= functions;
        level += 1;
    }
    level
}

/// The faces of the domain box, sampled (`Face` lattices): the z = min face in 2D, all six in 3D.
pub fn domain_faces(ifs: &Ifs) -> Vec<Face> {
    let (lo, hi) = (ifs.domain.min(), ifs.domain.max());
    let n = FACE_SAMPLES;
    let lerp = |a: f64, b: f64, s: usize| a + (b - a) * s as f64 / (n - 1) as f64;
    // A face: fix `axis` at `value`, sweep the other two axes (u, v).
    let face = |axis: usize, value: f64| -> Face {
        let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut points = Vec::with_capacity(n * n);
        for v in 0..n {
            for u in 0..n {
                let mut p = [0.0; 3];
                p[axis] = value;
                p[u_axis] = lerp(lo[u_axis], hi[u_axis], u);
                p[v_axis] = lerp(lo[v_axis], hi[v_axis], v);
                points.push(DVec3::from_array(p));
            }
        }
        points
    };
    if ifs.dimension() < 3 {
        return vec![face(2, lo.z)];
    }
    (0..3).flat_map(|axis| [face(axis, lo[axis]), face(axis, hi[axis])]).collect()
}

/// W^level(A) of the domain box A under the enabled functions.
pub fn nested_boxes(ifs: &Ifs, level: u32) -> Result<Vec<NestedBox>, NestingError> {
    let active = ifs.active();
    let boxes = (active.len() as u128).checked_pow(level).unwrap_or(u128::MAX);
    if boxes > MAX_NESTED_BOXES as u128 {
        return Err(NestingError::TooManyBoxes { level, functions: active.len(), boxes, max: MAX_NESTED_BOXES });
    }
    let successors = ifs.xaos_successors();
    let mut current = vec![NestedBox { outer_function: None, faces: domain_faces(ifs) }];
    for _ in 0..level {
        let mut next = Vec::with_capacity(current.len() * active.len());
        for &i in &active {
            for b in
                current.iter().filter(|b| b.outer_function.is_none_or(|o| successors.as_ref().is_none_or(|s| s[o][i])))
            {
                let faces: Vec<Face> =
                    b.faces.iter().map(|face| face.iter().map(|&p| ifs.eval(i, p)).collect()).collect();
                // A map that sends the box to infinity (a broken edit) leaves that copy out
                // rather than drawing lines to nowhere.
                if faces.iter().flatten().all(|p| p.is_finite()) {
                    next.push(NestedBox { outer_function: Some(i), faces });
                }
            }
        }
        current = next;
    }
    Ok(current)
}

/// The outline of a face: its four sides as one closed polyline of lattice points.
pub fn face_outline(face: &Face) -> Vec<DVec3> {
    let n = FACE_SAMPLES;
    let at = |u: usize, v: usize| face[v * n + u];
    let mut outline = Vec::with_capacity(4 * (n - 1) + 1);
    outline.extend((0..n).map(|u| at(u, 0)));
    outline.extend((1..n).map(|v| at(n - 1, v)));
    outline.extend((0..n - 1).rev().map(|u| at(u, n - 1)));
    outline.extend((0..n - 1).rev().map(|v| at(0, v)));
    outline
}

/// The triangles of a face's lattice (index triples into the face), two per lattice cell.
pub fn face_triangles() -> Vec<[usize; 3]> {
    let n = FACE_SAMPLES;
    let mut triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for v in 0..n - 1 {
        for u in 0..n - 1 {
            let (a, b, c, d) = (v * n + u, v * n + u + 1, (v + 1) * n + u, (v + 1) * n + u + 1);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use glam::DMat3;

    use super::*;
    use crate::model::{AffineMap, Function, Map, ProbabilityMode, RectGrid};

    fn affine_ifs(maps: &[(DMat3, DVec3)], dim3: bool) -> Ifs {
        let hi = if dim3 { DVec3::ONE } else { DVec3::new(1.0, 1.0, 0.0) };
        let counts = if dim3 { [2, 2, 2] } else { [2, 2, 1] };
        Ifs {
            domain: RectGrid::uniform(DVec3::ZERO, hi, counts),
            functions: maps
                .iter()
                .enumerate()
                .map(|(i, (matrix, offset))| Function {
                    name: format!("f{i}"),
                    map: Map::Affine(AffineMap { matrix: *matrix, offset: *offset }),
                    color: [1.0; 3],
                    weight: None,
                    enabled: true,
                    xaos: Vec::new(),
                })
                .collect(),
            probability_mode: ProbabilityMode::default(),
            final_xform: None,
        }
    }

    /// The Sierpinski triangle's three half-scale maps: W^k's boxes are the 3^k squares of side
    /// 2^-k at the closed-form offsets Σ 2^-j o_j; corner samples must land there to rounding
    /// (each coordinate a dyadic rational, so exactly).
    #[test]
    fn affine_boxes_land_at_the_closed_form_corners() {
        let half = DMat3::from_diagonal(DVec3::new(0.5, 0.5, 0.0));
        let offsets = [DVec3::ZERO, DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, 0.5, 0.0)];
        let ifs = affine_ifs(&offsets.map(|o| (half, o)), false);
        for level in 0..=4u32 {
            let boxes = nested_boxes(&ifs, level).unwrap();
            assert_eq!(boxes.len(), 3usize.pow(level));
            let side = 0.5f64.powi(level as i32);
            let mut corners: Vec<(u64, u64)> = boxes
                .iter()
                .map(|b| {
                    let lo = b.faces[0][0];
                    let hi = b.faces[0][FACE_SAMPLES * FACE_SAMPLES - 1];
                    assert_eq!(hi - lo, DVec3::new(side, side, 0.0), "level {level}");
                    ((lo.x / side) as u64, (lo.y / side) as u64)
                })
                .collect();
            corners.sort_unstable();
            // Closed form: the lower-left corners are the cells (i, j) of the 2^k lattice with
            // i & j == 0 (the Sierpinski pattern of Pascal's triangle mod 2).
            let n = 1u64 << level;
            let expected: Vec<(u64, u64)> =
                (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).filter(|(i, j)| i & j == 0).collect();
            assert_eq!(corners, expected, "level {level}");
        }
    }

    #[test]
    fn level_zero_is_the_domain_box_and_3d_boxes_have_six_faces() {
        let ifs = affine_ifs(&[(DMat3::IDENTITY * 0.5, DVec3::ZERO), (DMat3::IDENTITY * 0.5, DVec3::splat(0.5))], true);
        let boxes = nested_boxes(&ifs, 0).unwrap();
        assert_eq!(boxes.len(), 1);
        assert_eq!(boxes[0].outer_function, None);
        assert_eq!(boxes[0].faces.len(), 6);
        let all: Vec<DVec3> = boxes[0].faces.iter().flatten().copied().collect();
        assert!(all.iter().all(|p| p.min_element() >= 0.0 && p.max_element() <= 1.0));
        let level2 = nested_boxes(&ifs, 2).unwrap();
        assert_eq!(level2.len(), 4);
        // The outermost function decides where the box lies: f1's copies are in [0.5, 1]³.
        // (Its centre: f0(f1(box)) touches 0.5 at a corner.)
        for b in &level2 {
            let points: Vec<DVec3> = b.faces.iter().flatten().copied().collect();
            let centre = points.iter().sum::<DVec3>() / points.len() as f64;
            assert_eq!(centre.min_element() > 0.5, b.outer_function == Some(1), "{centre}");
        }
    }

    #[test]
    fn levels_past_the_box_budget_are_refused() {
        let ifs = affine_ifs(&vec![(DMat3::IDENTITY * 0.2, DVec3::ZERO); 5], true);
        let max = max_level(5);
        assert!(5usize.pow(max) <= MAX_NESTED_BOXES && 5usize.pow(max + 1) > MAX_NESTED_BOXES);
        assert!(nested_boxes(&ifs, max).is_ok());
        assert!(matches!(nested_boxes(&ifs, max + 1), Err(NestingError::TooManyBoxes { .. })));
        assert!(matches!(nested_boxes(&ifs, u32::MAX), Err(NestingError::TooManyBoxes { .. })));
    }

    #[test]
    fn outline_walks_the_four_sides_once() {
        let face: Face = (0..FACE_SAMPLES * FACE_SAMPLES).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        let outline = face_outline(&face);
        assert_eq!(outline.len(), 4 * (FACE_SAMPLES - 1) + 1);
        assert_eq!(outline.first(), outline.last());
        assert_eq!(face_triangles().len(), 2 * (FACE_SAMPLES - 1) * (FACE_SAMPLES - 1));
    }
}
