//! Fuzz target for the scene parser: any bytes must either load as a scene or give a located
//! error, never a panic; a scene that loads must also resolve and report (the contractivity
//! and containment that every command computes). Run as docs/testing.md describes.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match nlifs::scene::Scene::parse(text, "fuzz.toml") {
        Err(e) => assert!(e.line >= 1 && e.column >= 1, "{e}"),
        Ok(scene) => {
            let ifs = scene.at(0.0);
            let _ = ifs.report();
            let _ = ifs.probabilities();
            let _ = scene.camera_at(0.0);
            let _ = scene.render_at(0.0);
        }
    }
});
