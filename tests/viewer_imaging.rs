//! The viewer's imaging (`src/viewer/imaging.rs`): the live view takes the scene's tone, density
//! scale, spatial filter and density estimation at the current time, keyed values included; the render panel's
//! edits are scene edits that keep the accumulation, one undo step per drag, saved with the
//! scene and read back by `render` as the same style. Plain state: commands in, scene out, no
//! GPU.

mod common;

use nlifs::live::{Imaging, LiveSettings};
use nlifs::resolve::{ResolveStyle, Tone};
use nlifs::scene::Scene;
use nlifs::scene::spec::{DensityEstimation, DensityScale, PixelFilter, SplatMode};
use nlifs::viewer::command::Command;
use nlifs::viewer::state::ViewerState;

/// flam3's spatial filter, as the render panel's slider sets it.
const FILTER: PixelFilter = PixelFilter { radius_px: 0.8, shape: nlifs::flame::FilterShape::Gaussian };

fn density_state() -> ViewerState {
    let path = common::scene_path("plant2");
    let mut scene = Scene::load(&path).unwrap();
    scene.render.mode = SplatMode::Density;
    ViewerState::new(scene, Some(path), LiveSettings::default())
}

/// What `render` resolves the scene at `t_secs` with: its style's tone and its density
/// estimation.
fn render_imaging(scene: &Scene, t_secs: f64) -> Imaging {
    let render = scene.render_at(t_secs);
    let tone = ResolveStyle::of(&render, scene.domain.dimension()).tone;
    Imaging { tone, density_estimation: render.density_estimation }
}

#[test]
fn a_tone_drag_is_one_scene_edit_that_keeps_the_accumulation_and_saves() {
    let mut s = density_state();
    let original = s.scene.clone();
    assert_eq!(s.imaging(), Imaging { tone: Tone::NEUTRAL, density_estimation: None });
    let de = DensityEstimation { max_radius_px: 6.0, min_radius_px: 0.5, curve: 0.4 };
    // A drag: several values, then the gesture ends.
    for k in 1..=5 {
        let tone = Tone {
            exposure: 0.25 * k as f32,
            gamma: 2.2,
            highlight_power: 1.0,
            density_scale: DensityScale::Absolute,
            filter: Some(FILTER),
            ..Tone::NEUTRAL
        };
        let c = s.apply([Command::SetImaging(Imaging { tone, density_estimation: Some(de) })]);
        assert!(c.live_settings && !c.scene_edited && !c.scene_replaced, "step {k}: {c:?}");
        assert_eq!(s.live.draw.tone.exposure, 0.25 * k as f32);
    }
    s.apply([Command::EndGesture]);
    assert!(s.modified());
    assert_eq!(s.scene.render.exposure, 1.25);
    assert_eq!(s.scene.render.gamma, 2.2);
    assert_eq!(s.scene.render.density_estimation, Some(de));
    assert_eq!(s.scene.render.density_scale, DensityScale::Absolute);
    assert_eq!(s.scene.render.filter, Some(FILTER));
    assert_eq!(s.imaging(), render_imaging(&s.scene, s.t_secs), "the view shows what render draws");
    let edited = s.scene.clone();
    // One undo step restores the scene and the view's imaging exactly.
    let c = s.apply([Command::Undo]);
    assert!(c.live_settings);
    assert_eq!(s.scene, original);
    assert_eq!(s.imaging(), Imaging { tone: Tone::NEUTRAL, density_estimation: None });
    s.apply([Command::Redo]);
    assert_eq!(s.scene, edited);
    // Saved, the file gives render the same tone and filter.
    let dir = common::temp_dir("viewer-imaging");
    let path = dir.join("toned.toml");
    s.apply([Command::SaveScene(path.clone())]);
    assert!(s.error.is_none(), "{:?}", s.error);
    let loaded = Scene::load(&path).unwrap();
    assert_eq!(render_imaging(&loaded, 0.0), s.imaging());
}

#[test]
fn keyed_tone_follows_time_and_is_edited_in_the_key_at_the_playhead() {
    let mut s = density_state();
    s.apply([Command::AddOrUpdateKey, Command::SetDuration(4.0), Command::SetTime(2.0), Command::AddOrUpdateKey]);
    s.apply([Command::EndGesture]);
    let keys = &mut s.scene.timeline.as_mut().unwrap().keys;
    assert_eq!(keys.len(), 2);
    keys[0].render.tone[0] = Some(-1.0);
    keys[1].render.tone[0] = Some(2.0);
    assert_eq!(s.keyed_tone_fields(), [true, false, false, false, false]);
    for t_secs in [0.0, 0.5, 1.0, 2.0] {
        s.apply([Command::SetTime(t_secs)]);
        assert_eq!(s.imaging(), render_imaging(&s.scene, t_secs), "t = {t_secs}");
    }
    // On key 1 the keyed exposure goes into the key, the unkeyed gamma into [render].
    let tone = Tone { exposure: 3.0, gamma: 1.8, ..s.live.draw.tone };
    s.apply([Command::SetImaging(Imaging { tone, density_estimation: None }), Command::EndGesture]);
    let tl = s.scene.timeline.as_ref().unwrap();
    assert_eq!(tl.keys[1].render.tone[0], Some(3.0));
    assert_eq!(tl.keys[0].render.tone[0], Some(-1.0));
    assert_eq!(s.scene.render.exposure, 0.0);
    assert_eq!(s.scene.render.gamma, 1.8);
    assert_eq!(s.live.draw.tone.exposure, 3.0);
    // Between keys a keyed field is not edited (the panel disables it).
    s.apply([Command::SetTime(1.0)]);
    let before = s.scene.clone();
    let tone = Tone { exposure: 5.0, ..s.live.draw.tone };
    s.apply([Command::SetImaging(Imaging { tone, density_estimation: None }), Command::EndGesture]);
    assert_eq!(s.scene, before);
}

/// The blend space (`blend_space`, the tone panel's "blend"): the live view's colour table is
/// in the blend space of its mode, so choosing sRGB recolours the points (a scene edit that
/// clears the accumulation, saved, undone like any), and so does switching the view into or out
/// of closest mode while the scene blends in sRGB.
#[test]
fn the_blend_space_recolours_the_live_view() {
    use nlifs::scene::spec::{BlendSpace, ColorMode};
    let mut s = density_state();
    s.apply([Command::SetColorMode(ColorMode::Palette)]);
    let linear = s.compiled.as_ref().expect("compiled").colors.clone();
    let encoded: Vec<[f32; 3]> = linear.iter().map(|&c| BlendSpace::Srgb.of_linear(c)).collect();
    assert_ne!(linear, encoded);

    let tone = Tone { blend: BlendSpace::Srgb, ..s.live.draw.tone };
    let c = s.apply([Command::SetImaging(Imaging { tone, ..s.imaging() }), Command::EndGesture]);
    assert!(c.scene_edited && c.live_settings, "{c:?}");
    assert_eq!(s.scene.render.blend_space, BlendSpace::Srgb);
    assert_eq!(s.live.draw.tone.blend, BlendSpace::Srgb);
    assert_eq!(s.compiled.as_ref().unwrap().colors, encoded, "the colour table in sRGB values");
    assert!(Scene::to_toml(&s.scene).contains("blend_space = \"srgb\""));

    // Closest mode draws colours as they are: the table goes back to linear, and returns.
    let closest = LiveSettings {
        draw: nlifs::gpu::progressive::ProgressiveSettings { mode: SplatMode::Closest, ..s.live.draw },
        ..s.live
    };
    let c = s.apply([Command::SetLiveSettings(closest)]);
    assert!(c.scene_edited, "{c:?}");
    assert_eq!(s.compiled.as_ref().unwrap().colors, linear);
    let density = LiveSettings {
        draw: nlifs::gpu::progressive::ProgressiveSettings { mode: SplatMode::Density, ..s.live.draw },
        ..s.live
    };
    s.apply([Command::SetLiveSettings(density)]);
    assert_eq!(s.compiled.as_ref().unwrap().colors, encoded);

    s.apply([Command::Undo]);
    assert_eq!(s.scene.render.blend_space, BlendSpace::Linear);
    assert_eq!(s.live.draw.tone.blend, BlendSpace::Linear);
    assert_eq!(s.compiled.as_ref().unwrap().colors, linear);
}
