//! The browser page's entry point (`wasm32-unknown-unknown`, built by `web/build.sh`): the
//! viewer, the same as on the desktop, drawing into the page's canvas, with the scene from the
//! page's address, a file input and drops for opening files, and a banner for errors.
//!
//! The address: `?scene=plant2` opens a bundled scene (the files of `scenes/`, compiled in);
//! `?toml=…` a whole scene carried in the link (`scene::url`: zlib in URL-safe base64, with its
//! size bounded). A bad scene in the address or in a dropped file is shown in the banner with
//! its location (file:line:column), and the scene on screen stays. Where the browser has no
//! WebGPU the viewer draws with WebGL2, its chaos game and resolve on the CPU (`?backend=webgl2`
//! asks for that where WebGPU exists); where it has neither the banner says so. Leaving the
//! page with unsaved edits asks first.
//!
//! The page and the viewer share a [`Host`]: the page sends opened files as commands, and reads
//! the viewer's error and state for the banner, four times a second.

use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;

use crate::scene::url;
use crate::viewer::host::Host;
use crate::viewer::{Command, ViewerOptions};

/// The scenes a link can name (`?scene=NAME`): the files of `scenes/`.
pub const BUNDLED_SCENES: &[(&str, &str)] = &[
    ("bent4", include_str!("../../scenes/bent4.toml")),
    ("builders", include_str!("../../scenes/builders.toml")),
    ("fantasy", include_str!("../../scenes/fantasy.toml")),
    ("julia", include_str!("../../scenes/julia.toml")),
    ("linear4", include_str!("../../scenes/linear4.toml")),
    ("plant1", include_str!("../../scenes/plant1.toml")),
    ("plant2", include_str!("../../scenes/plant2.toml")),
    ("sierpinski-nonlinear", include_str!("../../scenes/sierpinski-nonlinear.toml")),
    ("sierpinski", include_str!("../../scenes/sierpinski.toml")),
    ("tapering", include_str!("../../scenes/tapering.toml")),
    ("twist-anim", include_str!("../../scenes/twist-anim.toml")),
    ("twisting", include_str!("../../scenes/twisting.toml")),
];

/// The id of the page's banner.
pub const BANNER_ID: &str = "nlifs-banner";

/// What the page's address asks to open: a file name for messages and the file's bytes, or why
/// it cannot be opened. None: nothing asked (the built-in scene).
pub fn scene_from_query(query: &str) -> Option<Result<(String, Vec<u8>), String>> {
    let params = web_sys::UrlSearchParams::new_with_str(query).ok()?;
    if let Some(name) = params.get("scene") {
        return Some(match BUNDLED_SCENES.iter().find(|(n, _)| *n == name) {
            Some((n, text)) => Ok((format!("{n}.toml"), text.as_bytes().to_vec())),
            None => Err(format!(
                "no bundled scene `{}`; the bundled scenes are {}",
                crate::io::printable(&name, false),
                BUNDLED_SCENES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            )),
        });
    }
    let param = params.get("toml")?;
    Some(url::decode(&param).map(|text| ("link.toml".to_string(), text.into_bytes())).map_err(|e| e.to_string()))
}

/// The graphics API the page's address asks for (`?backend=webgpu` or `webgl2`); None: WebGPU
/// where the browser has an adapter, WebGL2 otherwise.
pub fn backends_from_query(query: &str) -> Result<Option<wgpu::Backends>, String> {
    let Some(name) = web_sys::UrlSearchParams::new_with_str(query).ok().and_then(|p| p.get("backend")) else {
        return Ok(None);
    };
    match name.as_str() {
        "webgpu" => Ok(Some(wgpu::Backends::BROWSER_WEBGPU)),
        "webgl2" => Ok(Some(wgpu::Backends::GL)),
        _ => Err(format!("no backend `{}`; the backends are webgpu and webgl2", crate::io::printable(&name, false))),
    }
}

/// Starts the viewer in the page (called by `index.html`), with the scene its address names.
#[wasm_bindgen]
pub fn start() {
    let query = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
    start_with_query(&query);
}

/// The `toml` parameter that carries `toml_text` in a link (for the page's "link" button).
#[wasm_bindgen]
pub fn scene_link_param(toml_text: &str) -> String {
    url::encode(toml_text)
}

/// Starts the viewer in the page with the scene `query` (an address's `?…`) names, and returns
/// the handle the page and the tests share with it.
pub fn start_with_query(query: &str) -> Host {
    console_panics();
    let host = Host::default();
    match scene_from_query(query) {
        Some(Ok((name, bytes))) => host.send(Command::OpenBytes { name, bytes }),
        Some(Err(e)) => host.with(|h| h.error = Some(e)),
        None => {}
    }
    let backends = backends_from_query(query).unwrap_or_else(|e| {
        host.with(|h| h.error = Some(e));
        None
    });
    let early_error = host.with(|h| h.error.clone());
    watch_files(&host);
    watch_banner(&host, early_error);
    watch_leaving(&host);
    // As on the desktop, the chaos game's route is chosen for the adapter (`auto`).
    let live = crate::live::LiveSettings { chaos_backend: crate::live::ChaosBackend::Auto, ..Default::default() };
    let options = ViewerOptions { host: host.clone(), backends, live, ..ViewerOptions::default() };
    if let Err(e) = crate::viewer::run(options) {
        host.with(|h| h.fatal = Some(e.to_string()));
    }
    host
}

/// Panics go to the browser's console with their message (instead of "unreachable").
fn console_panics() {
    std::panic::set_hook(Box::new(|info| {
        web_sys::console::error_1(&JsValue::from_str(&format!("nlifs: {info}")));
    }));
}

fn document() -> Option<web_sys::Document> {
    web_sys::window()?.document()
}

/// The element `id`, made as a `tag` child of the body if the page has none.
fn element(id: &str, tag: &str) -> Option<web_sys::HtmlElement> {
    let document = document()?;
    if let Some(e) = document.get_element_by_id(id) {
        return e.dyn_into().ok();
    }
    let e = document.create_element(tag).ok()?;
    e.set_id(id);
    document.body()?.append_child(&e).ok()?;
    e.dyn_into().ok()
}

/// Reads `file` and sends it to the viewer as [`Command::OpenBytes`].
fn open_file(host: &Host, file: web_sys::File) {
    let host = host.clone();
    wasm_bindgen_futures::spawn_local(async move {
        let name = file.name();
        match wasm_bindgen_futures::JsFuture::from(file.array_buffer()).await {
            Ok(buffer) => {
                let bytes = js_sys::Uint8Array::new(&buffer).to_vec();
                host.send(Command::OpenBytes { name, bytes });
            }
            Err(_) => host.with(|h| h.error = Some(format!("cannot read {name}"))),
        }
    });
}

/// The file input that Open clicks, and drops anywhere on the page.
fn watch_files(host: &Host) {
    if let Some(input) = element(crate::platform::web::FILE_INPUT_ID, "input") {
        let _ = input.set_attribute("type", "file");
        let _ = input.set_attribute("accept", ".toml,.png");
        let _ = input.style().set_property("display", "none");
        let input: web_sys::HtmlInputElement = input.unchecked_into();
        let chosen = input.clone();
        let host = host.clone();
        let on_change = Closure::<dyn FnMut()>::new(move || {
            if let Some(file) = chosen.files().and_then(|f| f.get(0)) {
                open_file(&host, file);
            }
            // The same file chosen again is a change too.
            chosen.set_value("");
        });
        let _ = input.add_event_listener_with_callback("change", on_change.as_ref().unchecked_ref());
        on_change.forget();
    }
    let Some(document) = document() else { return };
    let on_drag_over = Closure::<dyn FnMut(web_sys::DragEvent)>::new(|e: web_sys::DragEvent| e.prevent_default());
    let _ = document.add_event_listener_with_callback("dragover", on_drag_over.as_ref().unchecked_ref());
    on_drag_over.forget();
    let host = host.clone();
    let on_drop = Closure::<dyn FnMut(web_sys::DragEvent)>::new(move |e: web_sys::DragEvent| {
        e.prevent_default();
        if let Some(file) = e.data_transfer().and_then(|d| d.files()).and_then(|f| f.get(0)) {
            open_file(&host, file);
        }
    });
    let _ = document.add_event_listener_with_callback("drop", on_drop.as_ref().unchecked_ref());
    on_drop.forget();
}

/// Leaving or reloading the page with unsaved edits asks first (the browser's own question:
/// a page cannot word it, and the browser asks only after the user has used the page).
fn watch_leaving(host: &Host) {
    let Some(window) = web_sys::window() else { return };
    let host = host.clone();
    let on_leave = Closure::<dyn FnMut(web_sys::BeforeUnloadEvent)>::new(move |e: web_sys::BeforeUnloadEvent| {
        if host.with(|h| h.modified) {
            e.prevent_default();
            // Older browsers ask only when the event carries a text.
            e.set_return_value("the scene has unsaved edits");
        }
    });
    let _ = window.add_event_listener_with_callback("beforeunload", on_leave.as_ref().unchecked_ref());
    on_leave.forget();
}

/// What the banner says: why the viewer cannot run, else the error on screen, else nothing.
fn banner_text(fatal: Option<&str>, error: Option<&str>) -> Option<String> {
    match (fatal, error) {
        (Some(f), _) => Some(format!(
            "nlifs cannot draw in this browser: {f}. It needs WebGPU or WebGL2, which every current browser has \
             unless hardware acceleration is turned off."
        )),
        (None, Some(e)) => Some(e.to_string()),
        (None, None) => None,
    }
}

/// Keeps the banner saying what [`banner_text`] gives, four times a second.
fn watch_banner(host: &Host, early_error: Option<String>) {
    let Some(window) = web_sys::window() else { return };
    let host = host.clone();
    let mut early_error = early_error;
    let mut shown: Option<String> = None;
    let update = Closure::<dyn FnMut()>::new(move || {
        let text = host.with(|h| {
            // An error of the address stays until the viewer shows one of its own.
            if h.started && h.error.is_some() {
                early_error = None;
            }
            banner_text(h.fatal.as_deref(), h.error.as_deref().or(early_error.as_deref()))
        });
        if text == shown {
            return;
        }
        if let Some(banner) = element(BANNER_ID, "div") {
            banner.set_text_content(text.as_deref());
            let _ = banner.style().set_property("display", if text.is_some() { "block" } else { "none" });
        }
        shown = text;
    });
    let _ = window.set_interval_with_callback_and_timeout_and_arguments_0(update.as_ref().unchecked_ref(), 250);
    update.forget();
}
