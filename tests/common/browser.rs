//! The browser suites' helpers (`tests/web.rs`, `tests/web_webgl2.rs`; each test file is a page
//! of its own, and a page has one event loop, so one viewer): waiting on the page's event loop,
//! the canvas and its pixels, and the viewer's shared check, plant2 drawn, edited and undone.

use wasm_bindgen::JsCast;

use nlifs::scene::Scene;
use nlifs::viewer::Command;
use nlifs::viewer::host::Host;
use nlifs::web::BUNDLED_SCENES;

/// The canvas the viewer draws into, in CSS pixels.
pub const CANVAS_PX: (u32, u32) = (800, 500);

/// Waits `ms` milliseconds on the page's event loop (the viewer draws meanwhile).
pub async fn sleep_ms(ms: i32) {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        web_sys::window().unwrap().set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, ms).unwrap();
    });
    wasm_bindgen_futures::JsFuture::from(promise).await.unwrap();
}

/// Waits until `done` holds of the host's state (checked every 100 ms), at most `secs`;
/// whether it came.
pub async fn wait_for(host: &Host, secs: f64, done: impl Fn(&nlifs::viewer::host::HostState) -> bool) -> bool {
    for _ in 0..(secs * 10.0) as u32 {
        if host.with(|h| done(h)) {
            return true;
        }
        sleep_ms(100).await;
    }
    host.with(|h| done(h))
}

/// Waits for `n` more frames than now.
pub async fn frames(host: &Host, n: u64) {
    let target = host.with(|h| h.frames) + n;
    assert!(
        wait_for(host, 120.0, |h| h.frames >= target).await,
        "the viewer stopped drawing: {:?}",
        host.with(|h| h.frames)
    );
}

/// The test page's canvas `#nlifs` at [`CANVAS_PX`].
pub fn make_canvas() -> web_sys::HtmlCanvasElement {
    let document = web_sys::window().unwrap().document().unwrap();
    let canvas: web_sys::HtmlCanvasElement = document.create_element("canvas").unwrap().unchecked_into();
    canvas.set_id(nlifs::platform::web::CANVAS_ID);
    let style = canvas.style();
    style.set_property("width", &format!("{}px", CANVAS_PX.0)).unwrap();
    style.set_property("height", &format!("{}px", CANVAS_PX.1)).unwrap();
    document.body().unwrap().append_child(&canvas).unwrap();
    canvas
}

/// The canvas's pixels as RGBA bytes with its size, copied through a 2D canvas.
pub fn canvas_pixels(canvas: &web_sys::HtmlCanvasElement) -> (u32, u32, Vec<u8>) {
    let (w, h) = (canvas.width(), canvas.height());
    let document = web_sys::window().unwrap().document().unwrap();
    let copy: web_sys::HtmlCanvasElement = document.create_element("canvas").unwrap().unchecked_into();
    copy.set_width(w);
    copy.set_height(h);
    let ctx: web_sys::CanvasRenderingContext2d = copy.get_context("2d").unwrap().unwrap().unchecked_into();
    ctx.draw_image_with_html_canvas_element(canvas, 0.0, 0.0).unwrap();
    let data = ctx.get_image_data(0.0, 0.0, w as f64, h as f64).unwrap().data().0;
    (w, h, data)
}

/// Which pixels of the right half of the picture (the side panel covers the left) hold the
/// attractor: those farther than 24 levels in some channel from the half's most common colour,
/// the background.
pub fn attractor_mask((w, h, rgba): &(u32, u32, Vec<u8>)) -> Vec<bool> {
    let pixel = |x: u32, y: u32| {
        let i = 4 * (y * w + x) as usize;
        [rgba[i], rgba[i + 1], rgba[i + 2]]
    };
    let mut counts = std::collections::BTreeMap::new();
    for y in 0..*h {
        for x in w / 2..*w {
            *counts.entry(pixel(x, y)).or_insert(0u32) += 1;
        }
    }
    let background = counts.into_iter().max_by_key(|&(_, n)| n).map(|(c, _)| c).unwrap();
    let mut mask = Vec::new();
    for y in 0..*h {
        for x in w / 2..*w {
            let p = pixel(x, y);
            mask.push((0..3).any(|c| p[c].abs_diff(background[c]) > 24));
        }
    }
    mask
}

/// The fraction of pixels where two masks differ.
pub fn mask_difference(a: &[bool], b: &[bool]) -> f64 {
    assert_eq!(a.len(), b.len(), "pictures of different sizes");
    a.iter().zip(b).filter(|(x, y)| x != y).count() as f64 / a.len() as f64
}

/// Starts the viewer in a new canvas with the address `query` (it names plant2), and checks
/// that it draws plant2 (pixels read back from the canvas differ from the background), that a
/// grid-point drag changes the picture and that Undo brings it back; logs the adapter, the
/// chaos game's route and the frame rate while plant2 accumulates. Returns the viewer's host,
/// its canvas and plant2 for the page's further checks.
pub async fn the_viewer_draws_plant2_edits_it_and_undoes_at(query: &str) -> (Host, web_sys::HtmlCanvasElement, Scene) {
    let canvas = make_canvas();
    let host = nlifs::web::start_with_query(query);
    let started = wait_for(&host, 120.0, |h| h.started || h.fatal.is_some()).await;
    assert!(started, "the viewer did not start within 120 s");
    assert_eq!(host.with(|h| h.fatal.clone()), None, "the viewer could not start");
    let plant2 = Scene::parse(BUNDLED_SCENES.iter().find(|(n, _)| *n == "plant2").unwrap().1, "plant2").unwrap();
    frames(&host, 10).await;
    // The frame rate while plant2 accumulates (reported, not asserted: it is the machine's).
    let (frames_0, t0_ms) = (host.with(|h| h.frames), js_sys::Date::now());
    frames(&host, 10).await;
    let fps = (host.with(|h| h.frames) - frames_0) as f64 / ((js_sys::Date::now() - t0_ms) / 1000.0);
    assert_eq!(host.with(|h| (h.scene_name.clone(), h.error.clone())), (plant2.name.clone(), None));
    let (adapter, route) = host.with(|h| (h.adapter.clone(), h.route.clone()));
    web_sys::console::log_1(&format!("adapter {adapter}, chaos game on the {route}, {fps:.1} frames/s").into());

    let before = attractor_mask(&canvas_pixels(&canvas));
    let lit = before.iter().filter(|&&b| b).count() as f64 / before.len() as f64;
    // plant2 framed in the view covers a good part of it; an empty or blank-white view does not.
    assert!((0.02..0.9).contains(&lit), "attractor pixels: {:.2} % of the view", 100.0 * lit);

    // The two middle-left grid points of f2 (the crown, a quarter of the points; index
    // (x·4 + y)·2 + z) dragged 150 pixels to the right, each its own gesture as with the mouse
    // (without the grid overlay, whose lines would be in the picture).
    for point in [2, 3] {
        host.send(Command::BeginPointDrag { function: 1, point });
        host.send(Command::DragPoint { delta_px: [150.0, 0.0] });
        host.send(Command::EndGesture);
    }
    // As many frames as the picture before had accumulated.
    frames(&host, 20).await;
    assert!(host.with(|h| h.can_undo), "the drag made no undoable edit: {:?}", host.with(|h| h.error.clone()));
    let edited = attractor_mask(&canvas_pixels(&canvas));
    let changed = mask_difference(&before, &edited);

    host.send(Command::Undo);
    host.send(Command::Undo);
    frames(&host, 20).await;
    assert!(!host.with(|h| h.can_undo));
    let undone = attractor_mask(&canvas_pixels(&canvas));
    let left = mask_difference(&before, &undone);
    web_sys::console::log_1(
        &format!(
            "lit {lit:.4}, changed by the edit {changed:.4}, left after undo {left:.4}, undo against the edit {:.4}",
            mask_difference(&edited, &undone)
        )
        .into(),
    );
    // The edit moves a whole part of the attractor; after Undo only the stochastic edge of
    // the point cloud differs (a few per cent of the lit pixels at most).
    assert!(changed > 0.2 * lit, "the edit changed {:.2} % of the view", 100.0 * changed);
    assert!(
        left < 0.25 * changed,
        "after undo {:.2} % of the view still differs (the edit: {:.2} %)",
        100.0 * left,
        100.0 * changed
    );
    (host, canvas, plant2)
}
