#!/bin/sh
# Builds the browser page into web/dist/: index.html, nlifs_bg.wasm and its JS glue nlifs.js.
# Needs the wasm32-unknown-unknown target (rustup target add wasm32-unknown-unknown) and the
# wasm-bindgen command at the version of the `wasm-bindgen` crate in Cargo.lock
# (cargo install wasm-bindgen-cli --version <it>). Serve with any static server:
#   python3 -m http.server -d web/dist   then open http://localhost:8000/?scene=plant2
set -eu
cd "$(dirname "$0")/.."
want=$(sed -n '/^name = "wasm-bindgen"$/{n;s/^version = "\(.*\)"$/\1/p;}' Cargo.lock)
have=$(wasm-bindgen --version 2>/dev/null | cut -d' ' -f2 || true)
if [ "$have" != "$want" ]; then
    echo "web/build.sh: wasm-bindgen $want is needed (found: ${have:-none}): cargo install wasm-bindgen-cli --version $want" >&2
    exit 2
fi
target_dir=${CARGO_TARGET_DIR:-target}
# The library as a cdylib for the browser (the desktop build stays an rlib).
cargo rustc --lib --release --target wasm32-unknown-unknown --crate-type cdylib
rm -rf web/dist
mkdir -p web/dist
wasm-bindgen --target web --no-typescript --out-dir web/dist --out-name nlifs \
    "$target_dir/wasm32-unknown-unknown/release/nlifs.wasm"
cp web/index.html web/dist/
ls -l web/dist
