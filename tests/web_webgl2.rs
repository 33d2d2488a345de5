//! The viewer in a real browser on WebGL2 (`?backend=webgl2`, as a browser without WebGPU gets
//! it): compiled to wasm32 and run by `wasm-bindgen-test-runner` in headless Chromium
//! (`web/test.sh`), a page of its own (a page has one event loop). WebGL2 has no compute
//! shaders: the chaos game runs on the CPU route and the picture is resolved on the CPU and
//! drawn as a texture (`src/gpu/picture.rs`). The viewer starts on the WebGL2 adapter, draws
//! plant2, a grid-point drag changes the picture and Undo brings it back, as on WebGPU
//! (`tests/web.rs`). On the desktop this file is empty.
#![cfg(target_arch = "wasm32")]

mod common;

use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};

use common::browser::the_viewer_draws_plant2_edits_it_and_undoes_at;

wasm_bindgen_test_configure!(run_in_browser);

#[wasm_bindgen_test]
async fn the_viewer_on_webgl2_draws_plant2_edits_it_and_undoes() {
    let (host, _canvas, _plant2) = the_viewer_draws_plant2_edits_it_and_undoes_at("?scene=plant2&backend=webgl2").await;
    let (adapter, route) = host.with(|h| (h.adapter.clone(), h.route.clone()));
    assert!(adapter.contains("(Gl)"), "the WebGL2 adapter: {adapter}");
    assert_eq!(route, "cpu", "the chaos game on the CPU route without compute shaders");
}
