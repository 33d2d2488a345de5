#!/bin/sh
# The browser tests (tests/web.rs) in headless Chromium through chromedriver; `.ci/run` calls
# this. Needs what web/build.sh needs, and Chromium with its driver (apt: chromium
# chromium-driver).
set -eu
cd "$(dirname "$0")/.."
export CHROMEDRIVER="${CHROMEDRIVER:-/usr/bin/chromedriver}"
# Chromium and chromedriver leave profile and scratch folders in the temporary folder: give
# them one of their own, removed afterwards.
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
trap 'exit 130' INT TERM
export TMPDIR="$scratch"
# SwiftShader is slow: a test may take minutes.
export WASM_BINDGEN_TEST_TIMEOUT="${WASM_BINDGEN_TEST_TIMEOUT:-600}"
export CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER="$PWD/web/test-runner.sh"
cargo test --release --target wasm32-unknown-unknown --test web --test web_webgl2 "$@"
