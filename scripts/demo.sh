#!/usr/bin/env bash
# Fresh Debian → installed, built, and the bundled Cornell box rendered to demo-out/
# (float EXR, sRGB PNG preview, and AOVs).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p demo-out
./build/apps/latentpt render scenes/cornell-box/scene.json --spp 64 --res 256x256 --aov --out demo-out/cornell-box.exr
echo "demo: open demo-out/cornell-box.png (float data in demo-out/cornell-box.exr)"
