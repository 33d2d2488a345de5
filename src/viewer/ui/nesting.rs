//! The nesting view in the viewer (the paper's plates 5 and 7): a panel section choosing k and
//! the fill, and the overlay drawing W^k of the grid box (`crate::model::nesting`) over the
//! points, each box in the colour of its word's outermost function, projected with the same
//! [`SplatView`] as the grid overlay so the boxes sit on the splatted points.
//!
//! W^k is mapped on the CPU in f64 when the IFS at the playhead or k changes, and kept in egui's
//! temporary memory between frames (the UI only reads the state).

use std::sync::Arc;

use crate::model::Ifs;
use crate::model::nesting::{self, NestedBox};
use crate::splat::SplatView;

use super::super::command::{Command, NestingView};
use super::super::picking::project;
use super::super::state::ViewerState;
use super::grid_edit::srgb;

/// The panel section: show, k (up to what the box budget allows), outline or translucent.
pub fn nesting_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Nesting W^k").default_open(false).show(ui, |ui| {
        let mut view: NestingView = state.nesting;
        let enabled = state.scene.functions.iter().filter(|f| f.enabled).count();
        let max_level = nesting::max_level(enabled);
        ui.checkbox(&mut view.shown, "show W^k of the grid box")
            .on_hover_text("The images of the initial grid's box under every composition of k functions, as in the paper's plates 5 and 7: k = 1 shows where each function puts its copy; larger k close in on the attractor.");
        ui.add_enabled_ui(view.shown, |ui| {
            ui.add(egui::Slider::new(&mut view.level, 0..=max_level).text("k"))
                .on_hover_text(format!("{enabled} functions: W^k has {enabled}^k boxes; the view draws at most {}.", nesting::MAX_NESTED_BOXES));
            ui.checkbox(&mut view.translucent, "translucent faces");
        });
        view.level = view.level.min(max_level);
        if view != state.nesting {
            commands.push(Command::SetNestingView(view));
        }
    });
}

/// What the overlay last mapped: the IFS and k it was made for, and W^k (or why not).
#[derive(Clone)]
struct Mapped {
    ifs: Arc<Ifs>,
    level: u32,
    boxes: Arc<Result<Vec<NestedBox>, String>>,
}

fn mapped_boxes(ctx: &egui::Context, ifs: Ifs, level: u32) -> Arc<Result<Vec<NestedBox>, String>> {
    let id = egui::Id::unique("nlifs_nesting_boxes");
    if let Some(m) = ctx.data(|d| d.get_temp::<Mapped>(id))
        && m.level == level
        && *m.ifs == ifs
    {
        return m.boxes;
    }
    let boxes = Arc::new(nesting::nested_boxes(&ifs, level).map_err(|e| e.to_string()));
    ctx.data_mut(|d| d.insert_temp(id, Mapped { ifs: Arc::new(ifs), level, boxes: boxes.clone() }));
    boxes
}

/// Draws W^k over the view (clipped to `clip`); `ppp`: pixels per egui point.
pub fn nesting_overlay_ui(ctx: &egui::Context, clip: egui::Rect, state: &ViewerState, ppp: f32) {
    if !state.nesting.shown {
        return;
    }
    let ifs = state.scene.at(state.t_secs);
    let colors: Vec<[f32; 3]> = ifs.functions.iter().map(|f| f.color).collect();
    let boxes = mapped_boxes(ctx, ifs, state.nesting.level);
    let painter = ctx
        .layer_painter(egui::LayerId::new(egui::Order::Background, egui::Id::unique("nlifs_nesting_overlay")))
        .with_clip_rect(clip);
    let boxes = match boxes.as_ref() {
        Ok(boxes) => boxes,
        Err(why) => {
            painter.text(
                clip.left_bottom() + egui::vec2(8.0, -8.0),
                egui::Align2::LEFT_BOTTOM,
                why,
                egui::FontId::proportional(14.0),
                egui::Color32::from_rgb(255, 200, 80),
            );
            return;
        }
    };
    let view: SplatView = state.splat_view();
    let origin = state.view_origin_px;
    let to_egui = |p| project(&view, p).map(|q| egui::pos2((q.x + origin[0]) / ppp, (q.y + origin[1]) / ppp));
    // Thinner, fainter lines as the boxes multiply, so deep levels do not drown the points.
    let crowd = (boxes.len().max(1) as f32).log(8.0);
    let (width, alpha) = ((1.6 - 0.25 * crowd).max(0.6), (0.95 - 0.12 * crowd).max(0.35));
    let triangles = nesting::face_triangles();
    let mut mesh = egui::Mesh::default();
    for b in boxes {
        let color = b.outer_function.and_then(|i| colors.get(i).copied()).unwrap_or([1.0; 3]);
        let stroke = egui::Stroke::new(width, srgb(color, alpha));
        for face in &b.faces {
            let outline: Option<Vec<egui::Pos2>> = nesting::face_outline(face).into_iter().map(to_egui).collect();
            if let Some(outline) = outline {
                painter.add(egui::Shape::line(outline, stroke));
            }
            if state.nesting.translucent {
                let Some(points) = face.iter().map(|&p| to_egui(p)).collect::<Option<Vec<_>>>() else { continue };
                let fill = srgb(color, 0.08);
                let base = mesh.vertices.len() as u32;
                for p in points {
                    mesh.colored_vertex(p, fill);
                }
                for t in &triangles {
                    mesh.add_triangle(base + t[0] as u32, base + t[1] as u32, base + t[2] as u32);
                }
            }
        }
    }
    if !mesh.is_empty() {
        painter.add(egui::Shape::mesh(mesh));
    }
}
