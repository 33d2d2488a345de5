//! What the viewer shows over the view: the warning banner says which function may not be
//! contractive (with its bound) or leaves the grid (with how many points), with a sign the
//! bundled fonts draw; the shortcuts overlay lists every key; the panels and overlays lay out
//! headless without sending commands.

mod common;

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::Command;
use nlifs::viewer::jobs::JobView;
use nlifs::viewer::state::ViewerState;
use nlifs::viewer::ui::overlay::{SHORTCUTS, WARNING_SIGN};

const BAD: &str = r#"
version = 1
name = "bad"

[grid]
x = [0, 1]
y = [0, 1]

[[function]]
name = "shrinks"
kind = "affine"
matrix = [[0.5, 0], [0, 0.5]]
offset = [0, 0]

[[function]]
name = "grows"
kind = "affine"
matrix = [[1.25, 0], [0, 0.5]]
offset = [0, 0.5]
"#;

/// Lays the panels and overlays out once, headless; returns the commands they sent.
fn run_ui(ctx: &egui::Context, state: &ViewerState) -> Vec<Command> {
    let mut commands = Vec::new();
    let input = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1280.0, 720.0))),
        ..Default::default()
    };
    let _ = ctx.run_ui(input, |ui| {
        nlifs::viewer::ui::panels_ui(ui, state, &JobView::default(), 1.0, &mut commands);
    });
    commands
}

#[test]
fn the_banner_names_the_function_its_factor_and_the_points_outside() {
    let scene = Scene::parse(BAD, "bad.toml").unwrap();
    let s = ViewerState::new(scene, None, LiveSettings::default());
    let warnings = s.warnings();
    assert!(
        warnings.iter().any(|w| w.contains("grows") && w.contains("contractive") && w.contains("1.250")),
        "{warnings:?}"
    );
    assert!(
        warnings.iter().any(|w| w.contains("grows") && w.contains("leaves the grid") && w.contains("2 of 4")),
        "{warnings:?}"
    );
    assert!(!warnings.iter().any(|w| w.contains("shrinks")), "{warnings:?}");
    // A disabled function warns no more.
    let mut s = s;
    s.apply([Command::SetFunctionEnabled { function: 1, enabled: false }]);
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
    // Paper scenes are quiet.
    let plant = ViewerState::new(common::load_scene("plant2"), None, LiveSettings::default());
    assert!(plant.warnings().is_empty(), "{:?}", plant.warnings());
}

#[test]
fn the_warnings_and_the_keys_use_only_glyphs_the_bundled_font_draws() {
    let ctx = egui::Context::default();
    let s = ViewerState::new(Scene::parse(BAD, "bad.toml").unwrap(), None, LiveSettings::default());
    run_ui(&ctx, &s);
    let font = egui::FontId::proportional(14.0);
    let mut texts: Vec<String> = s.warnings();
    texts.push(WARNING_SIGN.to_string());
    texts.extend(SHORTCUTS.iter().flat_map(|(k, a)| [k.to_string(), a.to_string()]));
    for text in texts {
        let missing: String = text.chars().filter(|&c| !ctx.fonts_mut(|f| f.has_glyph(&font, c))).collect();
        assert!(missing.is_empty(), "{text:?}: no glyph for {missing:?} (it would draw as an empty box)");
    }
    // The banner is on screen (its area exists).
    assert!(ctx.memory(|m| m.area_rect(egui::Id::unique("nlifs_banner")).is_some()));
}

#[test]
fn overlays_and_dialogs_lay_out_without_sending_anything() {
    let ctx = egui::Context::default();
    let mut s = ViewerState::new(common::load_scene("twist-anim"), None, LiveSettings::default());
    for _ in 0..3 {
        assert_eq!(run_ui(&ctx, &s), Vec::new());
    }
    s.apply([Command::SetShortcutsShown(true), Command::SetToast(Some("saved x.png".into()))]);
    s.apply([Command::SetFunctionEnabled { function: 0, enabled: false }, Command::RequestClose]);
    assert!(s.ui.close_dialog);
    for _ in 0..3 {
        assert_eq!(run_ui(&ctx, &s), Vec::new());
    }
    s.apply([Command::SetPanelShown(false)]);
    for _ in 0..3 {
        assert_eq!(run_ui(&ctx, &s), Vec::new());
    }
    // The question before a job on a scene that may not be contractive.
    let mut s = ViewerState::new(Scene::parse(BAD, "bad.toml").unwrap(), None, LiveSettings::default());
    s.apply([Command::StartRaytrace]);
    assert!(s.ui.job_confirm.is_some());
    for _ in 0..3 {
        assert_eq!(run_ui(&ctx, &s), Vec::new());
    }
}

#[test]
fn the_shortcuts_overlay_and_the_readme_list_the_same_keys() {
    let readme = std::fs::read_to_string(common::repo_path("README.md")).unwrap();
    for (key, _) in SHORTCUTS {
        for part in key.split([',', '/']).map(str::trim).filter(|p| {
            // Keys, not mouse words ("wheel", "left drag").
            p.len() <= 12 && !p.contains(' ') && p.chars().next().is_some_and(|c| !c.is_lowercase())
        }) {
            assert!(readme.contains(&format!("`{part}`")), "the README's viewer tour lacks `{part}`");
        }
    }
}
