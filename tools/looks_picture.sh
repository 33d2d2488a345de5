#!/bin/sh
# Writes docs/images/looks-paper-solid-traced.png: tapering, plant2 and fantasy in the paper look,
# the solid look and ray-traced (the initial grid's surface W^n(grid), same camera through
# `snapshot --framing points`), one row per scene. Needs a release build and ImageMagick.
# Usage: tools/looks_picture.sh [path/to/nlifs]
set -eu
nlifs=${1:-target/release/nlifs}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
size="--width 400 --height 300"
for scene in tapering plant2 fantasy; do
    "$nlifs" render "scenes/$scene.toml" $size --look paper -o "$dir/$scene-paper.png"
    "$nlifs" render "scenes/$scene.toml" $size -o "$dir/$scene-solid.png"
    "$nlifs" snapshot "scenes/$scene.toml" $size --framing points --initial grid --depth 6 --spp 4 \
        -o "$dir/$scene-traced.png"
    convert "$dir/$scene-paper.png" "$dir/$scene-solid.png" "$dir/$scene-traced.png" +append "$dir/$scene-row.png"
done
convert "$dir/tapering-row.png" "$dir/plant2-row.png" "$dir/fantasy-row.png" -append \
    -strip -define png:compression-level=9 docs/images/looks-paper-solid-traced.png
echo "wrote docs/images/looks-paper-solid-traced.png"
