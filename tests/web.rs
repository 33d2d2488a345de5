//! The viewer in a real browser: compiled to wasm32 and run by `wasm-bindgen-test-runner` in
//! headless Chromium (`web/test.sh`, which `.ci/run` calls; docs/testing.md). On the desktop
//! this file is empty.
//!
//! - The page: the viewer starts in a canvas with `?scene=plant2`, draws the attractor (pixels
//!   read back from the canvas differ from the background), a grid-point drag changes the
//!   picture and Undo brings it back; a bad scene dropped on the page is shown located in the
//!   banner's text while plant2 stays.
//! - The address: unknown names and oversized or broken links are refused with the reason.
//! - The GPU chaos game on the browser's WebGPU: its density agrees with the CPU chaos game's
//!   within the 6σ bound of `tests/gpu_vs_cpu.rs` (`densities_match_cpu`).
//!
//! One page runs all tests and a page has one event loop, so the viewer's checks are one test.
#![cfg(target_arch = "wasm32")]

mod common;

use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};

use nlifs::chaos_game::{self, CompiledIfs};
use nlifs::gpu::GpuContext;
use nlifs::live::LiveView;
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::SplatView;
use nlifs::viewer::Command;
use nlifs::web::scene_from_query;

use common::browser::{frames, sleep_ms, the_viewer_draws_plant2_edits_it_and_undoes_at, wait_for};
use common::{assert_gpu_density_matches_cpu, raw_density_settings};

wasm_bindgen_test_configure!(run_in_browser);

#[wasm_bindgen_test]
async fn the_viewer_draws_plant2_edits_it_and_undoes() {
    let (host, _canvas, plant2) = the_viewer_draws_plant2_edits_it_and_undoes_at("?scene=plant2").await;
    let adapter = host.with(|h| h.adapter.clone());
    assert!(adapter.contains("BrowserWebGpu"), "WebGPU where the browser has it: {adapter}");

    // F12's screenshot: read back when its copy maps, encoded with the scene inside, and
    // offered as a download.
    host.send(Command::ScreenshotNextToScene);
    frames(&host, 3).await;
    // The copy maps when the browser's GPU process gets to it: seconds on a busy SwiftShader.
    let saved = |h: &nlifs::viewer::host::HostState| h.message.as_deref().is_some_and(|m| m.starts_with("saved"));
    wait_for(&host, 60.0, saved).await;
    let message = host.with(|h| h.message.clone()).unwrap_or_default();
    assert!(message.starts_with("saved the screenshot ") && message.ends_with(".png"), "{message}");

    // A bad scene dropped on the page: its error located in the banner, plant2 stays.
    let bad = "name = \"bad\"\n[grid]\nnx = \"three\"\n";
    host.send(Command::OpenBytes { name: "bad.toml".into(), bytes: bad.as_bytes().to_vec() });
    frames(&host, 5).await;
    sleep_ms(600).await;
    let error = host.with(|h| h.error.clone()).expect("the bad scene's error");
    assert!(error.contains("bad.toml:"), "{error}");
    assert_eq!(host.with(|h| h.scene_name.clone()), plant2.name);
    let banner = web_sys::window().unwrap().document().unwrap().get_element_by_id(nlifs::web::BANNER_ID).unwrap();
    assert_eq!(banner.text_content().as_deref(), Some(error.as_str()));
}

#[wasm_bindgen_test]
fn the_address_names_a_bundled_scene_or_carries_one() {
    let (name, bytes) = scene_from_query("?scene=plant2").unwrap().unwrap();
    assert_eq!((name.as_str(), bytes.as_slice()), ("plant2.toml", include_bytes!("../scenes/plant2.toml").as_slice()));
    let unknown = scene_from_query("?scene=plant9").unwrap().unwrap_err();
    assert!(unknown.contains("plant9") && unknown.contains("plant2"), "{unknown}");
    let text = include_str!("../scenes/twisting.toml");
    let query = format!("?toml={}", nlifs::scene::url::encode(text));
    assert_eq!(scene_from_query(&query).unwrap().unwrap().1, text.as_bytes());
    let long = format!("?toml={}", "A".repeat(nlifs::scene::url::MAX_PARAM_CHARS + 5));
    let refused = scene_from_query(&long).unwrap().unwrap_err();
    assert!(refused.contains(&format!("{} characters", nlifs::scene::url::MAX_PARAM_CHARS + 5)), "{refused}");
    assert!(scene_from_query("").is_none());
}

#[wasm_bindgen_test]
async fn webgpu_chaos_game_densities_match_cpu() {
    let instance =
        wgpu::util::new_instance_with_webgpu_detection(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
            .await;
    let ctx = GpuContext::request(instance, None).await.expect("a WebGPU adapter (Chromium's SwiftShader)");
    let info = ctx.adapter.get_info();
    assert_eq!(info.backend, wgpu::Backend::BrowserWebGpu, "{}", ctx.describe());
    // As `densities_match_cpu` in tests/gpu_vs_cpu.rs, for plant2.
    let (width, height) = (160u32, 120u32);
    let cells = (16usize, 12usize);
    let k = 4u32;
    let scene = Scene::parse(include_str!("../scenes/plant2.toml"), "plant2").unwrap();
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let camera = scene.camera_for(bounds);
    let bg = [0.0; 3];
    let gpu_orbits = 1u32 << 18;
    let settings = raw_density_settings(gpu_orbits, k);
    let mut live = LiveView::new(&ctx, settings, width, height).unwrap();
    live.set_ifs(&ctx, &compiled, bounds, true);
    live.set_camera(&camera);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    live.advance(&ctx, &mut encoder);
    ctx.queue.submit([encoder.finish()]);
    let accum = live.read_accum_async(&ctx).await.unwrap();
    let gpu_counts: Vec<u32> = accum.chunks(4).map(|a| a[3]).collect();

    let view = SplatView::new(&camera, width, height, bounds, SplatMode::Density, 0.0, bg);
    let found = assert_gpu_density_matches_cpu(
        "plant2 on WebGPU",
        "WebGPU",
        &gpu_counts,
        &compiled,
        view,
        (gpu_orbits, k),
        cells,
    );
    web_sys::console::log_1(
        &format!(
            "plant2: {} WebGPU / {} CPU samples, worst |Δ|/tolerance {:.3}",
            found.gpu_samples, found.cpu_samples, found.worst
        )
        .into(),
    );
}
