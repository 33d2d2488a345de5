//! The browser's side of the platform seam: downloads in place of written files, and the page's
//! canvas as the viewer's window.

use std::io::Write;

use wasm_bindgen::JsCast;

/// The id of the canvas the viewer draws into.
pub const CANVAS_ID: &str = "nlifs";

fn document() -> Option<web_sys::Document> {
    web_sys::window()?.document()
}

/// Offers the bytes that `write` writes as a download named `file_name`.
pub fn download(file_name: &str, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> std::io::Result<()> {
    let mut bytes = Vec::new();
    write(&mut bytes)?;
    let failed = |what: &str| std::io::Error::other(format!("cannot offer {file_name} as a download: {what}"));
    let document = document().ok_or_else(|| failed("no page"))?;
    let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(bytes.as_slice()));
    let options = web_sys::BlobPropertyBag::new();
    options.set_type(if file_name.ends_with(".png") { "image/png" } else { "application/octet-stream" });
    let blob = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options)
        .map_err(|_| failed("the browser refused the data"))?;
    let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(|_| failed("no object URL"))?;
    let link: web_sys::HtmlAnchorElement =
        document.create_element("a").map_err(|_| failed("no link"))?.dyn_into().map_err(|_| failed("no link"))?;
    link.set_href(&url);
    link.set_download(file_name);
    link.click();
    // The download has taken the data; the URL can go.
    let _ = web_sys::Url::revoke_object_url(&url);
    Ok(())
}

/// `attributes` set to draw into the canvas `#nlifs`, made if the page has none.
/// The page's style gives the canvas its size (the desktop's window size is dropped).
pub fn canvas_attributes(mut attributes: winit::window::WindowAttributes) -> winit::window::WindowAttributes {
    use winit::platform::web::WindowAttributesExtWebSys;
    attributes.inner_size = None;
    let canvas = document()
        .and_then(|d| d.get_element_by_id(CANVAS_ID))
        .and_then(|e| e.dyn_into::<web_sys::HtmlCanvasElement>().ok());
    match canvas {
        Some(canvas) => attributes.with_canvas(Some(canvas)),
        None => attributes.with_append(true),
    }
}

/// Makes the viewer's canvas's WebGL2 context with `preserveDrawingBuffer`, before wgpu asks
/// for it (the browser then hands wgpu this context; wgpu asks only for no antialiasing, which
/// is the default here too). Without it the browser clears the canvas after showing a frame,
/// and the page's picture reads back blank (`drawImage`, "save image") between the viewer's
/// frames, which come only when something changes.
pub fn keep_webgl2_pixels(window: &winit::window::Window) {
    use winit::platform::web::WindowExtWebSys;
    let Some(canvas) = window.canvas() else { return };
    let options = js_sys::Object::new();
    let _ = js_sys::Reflect::set(&options, &"preserveDrawingBuffer".into(), &wasm_bindgen::JsValue::TRUE);
    let _ = js_sys::Reflect::set(&options, &"antialias".into(), &wasm_bindgen::JsValue::FALSE);
    let _ = canvas.get_context_with_context_options("webgl2", &options);
}

/// The id of the page's file input, which Open clicks.
pub const FILE_INPUT_ID: &str = "nlifs-open";

/// Clicks the page's element `id` (a file input: opens the browser's file chooser).
pub fn click(id: &str) -> Result<(), String> {
    let element = document()
        .and_then(|d| d.get_element_by_id(id))
        .and_then(|e| e.dyn_into::<web_sys::HtmlElement>().ok())
        .ok_or_else(|| format!("the page has no element #{id}"))?;
    element.click();
    Ok(())
}
