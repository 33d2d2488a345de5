#!/bin/sh
# cargo's runner for wasm32 test binaries: wasm-bindgen-test-runner started in web/, where it
# finds webdriver.json (headless Chromium with WebGPU on SwiftShader).
set -eu
cd "$(dirname "$0")"
exec wasm-bindgen-test-runner "$@"
