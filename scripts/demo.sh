#!/usr/bin/env bash
# Fresh Debian → installed, built, and the bundled Cornell box rendered to demo-out/
# (float EXR, sRGB PNG preview, and AOVs).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p demo-out
./build/apps/latentpt render scenes/cornell-box/scene.json --spp 64 --res 256x256 --aov --out demo-out/cornell-box.exr
# Latent rendering, the paper's way: path trace the box in RGB, encode it with TAESD3 (weights
# from ../shared, or LATENTPT_SHARED), fit the per-shape latent parameters (stage 1), train the
# refiner (stage 2), decode. Reduced iterations: about a minute.
./build/apps/latentpt fit scenes/cornell-box/scene.json --encode --encode-res 256x256 --ref-spp 256 \
    --iterations 600 --spp 4 --lr 0.05 --lr-period 600 --final-spp 64 -D integrator.max_depth=4 \
    --refiner-iterations 200 --out demo-out/fit
# Edits: orbit the camera, move the light, turn the tall block; latent frames decoded, next to
# path-traced references, with per-frame latent errors in demo-out/edit/metrics.csv.
./build/apps/latentpt render demo-out/fit --edit scenes/cornell-box/edits-demo.json --spp 64 --reference --ref-spp 64 --out demo-out/edit
echo "demo: demo-out/edit/frame_*.png (edited, refined, decoded), frame_*_rendered.png (unrefined)"
echo "      next to frame_*_reference.png (RGB path trace); errors per frame in metrics.csv"
echo "demo: demo-out/cornell-box.png is the RGB render; in demo-out/fit/: reference.png (RGB target),"
echo "      target_decoded.png (TAESD3 round trip), decoded.png (fitted latent rendering, decoded),"
echo "      decoded_refined.png (after the refiner), metrics.json (LPIPS / MSE x100 of each),"
echo "      target.png / render.png / diff.png (16 latent channels: green +, red -), loss.csv, params.json"
