#!/usr/bin/env bash
# Fresh Debian → installed, built, and the bundled Cornell box rendered to demo-out/
# (float EXR, sRGB PNG preview, and AOVs).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p demo-out
./build/apps/latentpt render scenes/cornell-box/scene.json --spp 64 --res 256x256 --aov --out demo-out/cornell-box.exr
# Stage 1 of latent rendering on a synthetic target (random latent parameters rendered by the
# latent renderer itself) until the VAE lands: reduced iterations, about ten seconds.
./build/apps/latentpt fit scenes/cornell-box/scene.json --synthetic-res 32x32 --iterations 600 --spp 4 --lr 0.05 \
    --lr-period 600 --final-spp 64 -D integrator.max_depth=4 --out demo-out/fit
echo "demo: open demo-out/cornell-box.png (RGB render), demo-out/fit/{target,render,diff}.png (16 latent channels:"
echo "      green positive, red negative), demo-out/fit/loss.csv and params.json"
