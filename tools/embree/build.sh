#!/bin/sh
# Builds the Embree comparison program (not part of the cargo build): needs Embree 3's headers
# and library, e.g. Debian's libembree-dev. -ffp-contract=off keeps the shading's arithmetic
# unfused, as nlifs's, so the pictures can be compared byte for byte.
set -e
cd "$(dirname "$0")"
mkdir -p ../../target/embree
g++ -O3 -march=native -ffp-contract=off -std=c++17 -Wall -Wextra -o ../../target/embree/trace trace.cpp -lembree3 -pthread
echo "built target/embree/trace"
