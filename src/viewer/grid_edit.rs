//! Grid display and direct manipulation: the initial grid and every function's transformed
//! grid drawn as lines over the view (the paper's plates 5 and 7), picking a grid point near
//! the cursor, and turning a cursor drag into a new position in the view plane.
//!
//! Everything projects with the [`SplatView`] that the live view uses (the same `OrbitCamera`
//! matrices, window size and bounds), so lines sit exactly on the splatted points. A drag keeps
//! the point's view distance: the start point is projected to clip space, moved by the cursor's
//! pixel delta and unprojected. With an axis lock the pixel delta
//! is projected onto the screen image of that world axis instead.

use glam::{DVec3, Vec2};

use crate::splat::SplatView;

use super::state::{FunctionGrid, ViewerState, definition_grid};

/// How near (window pixels) the cursor must be to a grid point to pick it.
pub const PICK_RADIUS_PX: f32 = 12.0;

/// The live view's projection for the viewer's current camera and window size.
pub fn view_of(state: &ViewerState) -> SplatView {
    let (w, h) = (state.width_px.max(1.0) as u32, state.height_px.max(1.0) as u32);
    SplatView::new(&state.camera, w, h, state.bounds, state.live.mode, state.live.depth_cue, state.live.background)
}

/// View pixel position of a world point (add `state.view_origin_px` for the window); None
/// behind the camera.
pub fn project(view: &SplatView, p: DVec3) -> Option<Vec2> {
    let q = view.pixel_from_world * p.as_vec3().extend(1.0);
    (q.w > 1e-6 && q.is_finite()).then(|| Vec2::new(q.x, q.y) / q.w)
}

/// Where a point that started at `start` goes when the cursor moved `delta_px` since the press.
pub fn dragged_position(state: &ViewerState, start: DVec3, delta_px: [f32; 2]) -> DVec3 {
    let view = view_of(state);
    let delta = Vec2::from(delta_px);
    let dim = state.scene.domain.dimension();
    let moved = match state.edit.axis_lock {
        Some(axis) => {
            // Along the axis: the pixel delta projected onto the axis' screen direction, scaled
            // by pixels per world unit there.
            let extent = (state.scene.domain.max() - state.scene.domain.min()).max_element().max(1e-9);
            let step = 1e-3 * extent;
            let (Some(a), Some(b)) = (project(&view, start), project(&view, start + step * DVec3::AXES[axis])) else {
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
            let (near, far) = state.camera.depth_range(state.bounds);
            let clip_from_world = state.camera.clip_from_view(view.width as f32 / view.height as f32, near, far)
                * state.camera.view_from_world();
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
    if dim == 2 { DVec3::new(moved.x, moved.y, start.z) } else { moved }
}

/// The editable grid point nearest to `cursor_px` (window pixels) within [`PICK_RADIUS_PX`]: among the selected
/// function's points, or every enabled grid function's when none is selected.
pub fn pick_point(state: &ViewerState, cursor_px: [f32; 2]) -> Option<(usize, usize)> {
    if !state.edit.grid_overlay {
        return None;
    }
    let view = view_of(state);
    let cursor = Vec2::from(cursor_px) - Vec2::from(state.view_origin_px);
    let candidates: Vec<usize> = match state.edit.selected_function {
        Some(f) => vec![f],
        None => (0..state.scene.functions.len()).filter(|&f| state.scene.functions[f].enabled).collect(),
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for f in candidates {
        let Some(grid) = state.function_grid(f).filter(|g| g.editable) else { continue };
        for (i, p) in grid.points.iter().enumerate() {
            if let Some(q) = project(&view, *p) {
                let d = q.distance(cursor);
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

fn srgb(color: [f32; 3], alpha: f32) -> egui::Color32 {
    let c = color.map(|v| (crate::color::linear_to_srgb(v).clamp(0.0, 1.0) * 255.0).round() as u8);
    egui::Color32::from_rgba_unmultiplied(c[0], c[1], c[2], (alpha * 255.0).round() as u8)
}

/// egui position (points) of view pixel `q` in a view whose corner is at window pixel `origin`.
fn to_egui(q: Vec2, origin: [f32; 2], ppp: f32) -> egui::Pos2 {
    egui::pos2((q.x + origin[0]) / ppp, (q.y + origin[1]) / ppp)
}

fn draw_grid(
    painter: &egui::Painter,
    view: &SplatView,
    origin: [f32; 2],
    grid: &FunctionGrid,
    ppp: f32,
    stroke: egui::Stroke,
) {
    let projected: Vec<Option<egui::Pos2>> =
        grid.points.iter().map(|p| project(view, *p).map(|q| to_egui(q, origin, ppp))).collect();
    for (a, b) in grid_lines(grid.dims) {
        if let (Some(Some(pa)), Some(Some(pb))) = (projected.get(a), projected.get(b)) {
            painter.line_segment([*pa, *pb], stroke);
        }
    }
}

/// Draws the initial grid, every enabled function's grid, the selected function's points
/// (the selected one ringed) and, with a timeline, faint ghosts of the selected function's grid
/// at the neighbouring keys. `ppp`: egui points per window pixel inverse (pixels per point).
pub fn grid_overlay_ui(ctx: &egui::Context, clip: egui::Rect, state: &ViewerState, ppp: f32) {
    if !state.edit.grid_overlay {
        return;
    }
    let painter = ctx
        .layer_painter(egui::LayerId::new(egui::Order::Background, egui::Id::unique("nlifs_grid_overlay")))
        .with_clip_rect(clip);
    let view = view_of(state);
    let initial =
        FunctionGrid { dims: state.scene.domain.dims(), points: state.scene.domain.points(), editable: false };
    draw_grid(
        &painter,
        &view,
        state.view_origin_px,
        &initial,
        ppp,
        egui::Stroke::new(1.0, egui::Color32::from_white_alpha(110)),
    );
    let selected = state.edit.selected_function;
    if let (Some(f), Some(tl)) = (selected, &state.scene.timeline) {
        let t = state.playhead_secs();
        let tol = crate::scene::timeline::KEY_TIME_TOL_SECS;
        let with_f: Vec<_> = tl.keys.iter().filter(|k| k.function(f).is_some()).collect();
        let before = with_f.iter().rev().find(|k| k.t_secs < t - tol);
        let after = with_f.iter().find(|k| k.t_secs > t + tol);
        for key in [before, after].into_iter().flatten() {
            if let Some(grid) = key.function(f).and_then(|d| definition_grid(&state.scene, d)) {
                draw_grid(
                    &painter,
                    &view,
                    state.view_origin_px,
                    &grid,
                    ppp,
                    egui::Stroke::new(1.0, srgb(state.scene.functions[f].color, 0.25)),
                );
            }
        }
    }
    for (f, spec) in state.scene.functions.iter().enumerate() {
        if !spec.enabled && selected != Some(f) {
            continue;
        }
        let Some(grid) = state.function_grid(f) else { continue };
        let (width, alpha) = if selected == Some(f) {
            (2.0, 1.0)
        } else if selected.is_some() {
            (1.0, 0.35)
        } else {
            (1.2, 0.8)
        };
        draw_grid(&painter, &view, state.view_origin_px, &grid, ppp, egui::Stroke::new(width, srgb(spec.color, alpha)));
        if selected == Some(f) || (selected.is_none() && grid.editable) {
            for (i, p) in grid.points.iter().enumerate() {
                let Some(q) = project(&view, *p) else { continue };
                let pos = to_egui(q, state.view_origin_px, ppp);
                let is_selected = selected == Some(f) && state.edit.selected_point == Some(i);
                if is_selected {
                    painter.circle_stroke(pos, 6.0, egui::Stroke::new(2.0, egui::Color32::WHITE));
                }
                let fill = if grid.editable { srgb(spec.color, 1.0) } else { egui::Color32::from_gray(150) };
                painter.circle_filled(pos, if is_selected { 4.0 } else { 2.5 }, fill);
            }
        }
    }
}
