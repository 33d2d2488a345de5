//! The maths of direct grid manipulation, on a [`SplatView`] (the live view's projection, so
//! that what is picked sits exactly on the splatted points): the grids a function shows,
//! projecting a world point to view pixels, the grid point nearest the cursor, and turning a
//! cursor drag into a new position.
//!
//! A drag keeps the point's view distance: the start point is projected to clip space, moved by
//! the cursor's pixel delta and unprojected. With an axis lock the pixel delta is projected onto
//! the screen image of that world axis instead. The moved coordinates are rounded to the
//! shortest decimal of their f32 (the precision the drag was worked out in), so that a saved
//! file holds short numbers. Nothing here reads the viewer's state: the
//! state gathers the grids and the view, the overlay (`ui/grid_edit.rs`) draws with the same
//! functions.

use glam::{DVec3, Vec2};

use crate::camera::OrbitCamera;
use crate::model::grid::RectGrid;
use crate::scene::Scene;
use crate::scene::spec::FunctionDef;
use crate::splat::SplatView;

/// How near (window pixels) the cursor must be to a grid point to pick it.
pub const PICK_RADIUS_PX: f32 = 12.0;

/// A function's grid as the overlay shows it: the grid's dimensions and the transformed points
/// (at the playhead), and whether its points can be edited (`kind = "grid"`).
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionGrid {
    pub dims: [usize; 3],
    pub points: Vec<DVec3>,
    pub editable: bool,
}

/// The grid of a definition: grid and builder functions (resolved); None for the others.
pub fn definition_grid(scene: &Scene, def: &FunctionDef) -> Option<FunctionGrid> {
    match (def, scene.resolve(def)) {
        (FunctionDef::Grid { points }, _) => {
            Some(FunctionGrid { dims: scene.domain.dims(), points: points.clone(), editable: true })
        }
        (FunctionDef::Builder { .. }, crate::model::Map::Grid(g)) => {
            Some(FunctionGrid { dims: g.grid.dims(), points: g.points, editable: false })
        }
        _ => None,
    }
}

/// View pixel position of a world point (add the view's window origin for window pixels);
/// None behind the camera.
pub fn project(view: &SplatView, p_world: DVec3) -> Option<Vec2> {
    let q = view.pixel_from_world * p_world.as_vec3().extend(1.0);
    (q.w > 1e-6 && q.is_finite()).then(|| Vec2::new(q.x, q.y) / q.w)
}

/// Where a point that started at `start` goes when the cursor moved `delta_px` since the press,
/// in `view` (made from `camera`) over `domain`, along world axis `axis_lock` only when given.
pub fn dragged_position(
    view: &SplatView,
    camera: &OrbitCamera,
    domain: &RectGrid,
    axis_lock: Option<usize>,
    start: DVec3,
    delta_px: [f32; 2],
) -> DVec3 {
    let delta = Vec2::from(delta_px);
    let dim = domain.dimension();
    let moved = match axis_lock {
        Some(axis) => {
            // Along the axis: the pixel delta projected onto the axis' screen direction, scaled
            // by pixels per world unit there.
            let extent = (domain.max() - domain.min()).max_element().max(1e-9);
            let step = 1e-3 * extent;
            let (Some(a), Some(b)) = (project(view, start), project(view, start + step * DVec3::AXES[axis])) else {
                return start;
            };
            let s = b - a;
            if s.length_squared() < 1e-12 {
                return start;
            }
            let mut p = start;
            p[axis] += (delta.dot(s) / s.length_squared()) as f64 * step;
            p
        }
        None => {
            // `pixel_from_world` is singular in perspective (its depth and w rows are both the
            // view distance), so unproject through clip space: same NDC depth, moved NDC x, y.
            // The view's depth range is the camera's for the view's bounds.
            let clip_from_world = camera.clip_from_view(view.width as f32 / view.height as f32, view.near, view.far)
                * camera.view_from_world();
            let world_from_clip = clip_from_world.inverse();
            let q = clip_from_world * start.as_vec3().extend(1.0);
            if !(q.w.abs() > 1e-9) {
                return start;
            }
            let ndc = q.truncate() / q.w;
            let moved =
                ndc + glam::Vec3::new(2.0 * delta.x / view.width as f32, -2.0 * delta.y / view.height as f32, 0.0);
            let unproject = |n: glam::Vec3| {
                let p = world_from_clip * n.extend(1.0);
                p.truncate() / p.w
            };
            let offset = unproject(moved) - unproject(ndc);
            if !offset.is_finite() {
                return start;
            }
            // Offsets in double precision from the start, so an unmoved cursor leaves it exact.
            start + offset.as_dvec3()
        }
    };
    let moved = if dim == 2 { DVec3::new(moved.x, moved.y, start.z) } else { moved };
    // The drag is worked out in f32: each moved coordinate is the shortest decimal that reads
    // back as its f32 (23.061722, not 23.06172164916992, in a saved file); an unmoved one stays.
    DVec3::from_array(std::array::from_fn(|i| if moved[i] == start[i] { start[i] } else { shortest_f32(moved[i]) }))
}

/// The shortest decimal that reads back as `x`'s f32, as f64; `x` itself where f32 cannot hold
/// it (a coordinate past f32's range or below its precision).
fn shortest_f32(x: f64) -> f64 {
    let single = x as f32;
    let short = single.to_string().parse::<f64>().unwrap_or(x);
    if single.is_finite() && (short - x).abs() <= 1e-6 * x.abs() { short } else { x }
}

/// The point nearest to `cursor_in_view_px` within [`PICK_RADIUS_PX`] among the editable
/// `grids` (each with its function's index), as (function, point); the first wins a tie.
pub fn nearest_point(
    view: &SplatView,
    grids: impl IntoIterator<Item = (usize, FunctionGrid)>,
    cursor_in_view_px: Vec2,
) -> Option<(usize, usize)> {
    let mut best: Option<(f32, usize, usize)> = None;
    for (f, grid) in grids {
        if !grid.editable {
            continue;
        }
        for (i, p) in grid.points.iter().enumerate() {
            if let Some(q) = project(view, *p) {
                let d = q.distance(cursor_in_view_px);
                if d <= PICK_RADIUS_PX && best.is_none_or(|b| d < b.0) {
                    best = Some((d, f, i));
                }
            }
        }
    }
    best.map(|(_, f, i)| (f, i))
}

/// Index pairs of the grid's lines: neighbours along x, y and z.
pub fn grid_lines(dims: [usize; 3]) -> Vec<(usize, usize)> {
    let [nx, ny, nz] = dims;
    let index = |x: usize, y: usize, z: usize| (x * ny + y) * nz + z;
    let mut lines = Vec::new();
    for x in 0..nx {
        for y in 0..ny {
            for z in 0..nz {
                let i = index(x, y, z);
                if x + 1 < nx {
                    lines.push((i, index(x + 1, y, z)));
                }
                if y + 1 < ny {
                    lines.push((i, index(x, y + 1, z)));
                }
                if z + 1 < nz {
                    lines.push((i, index(x, y, z + 1)));
                }
            }
        }
    }
    lines
}
