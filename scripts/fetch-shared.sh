#!/usr/bin/env bash
# Downloads the data latentpt reads from ../shared (or $1) from its public origins and checks
# sha256 sums. The project never commits these files. Provenance details: the SOURCE/README
# files that ship with the team's copy, summarised here.
# Needs network access and curl; run from anywhere: bash scripts/fetch-shared.sh [target-dir]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dest="${1:-$root/../shared}"
mkdir -p "$dest"
gh() { echo "https://raw.githubusercontent.com/$1/$2/$3"; }

fetch() {  # url path sha256|-
    local url="$1" path="$dest/$2" sum="$3"
    if [ -f "$path" ] && { [ "$sum" = - ] || echo "$sum  $path" | sha256sum -c --quiet - 2>/dev/null; }; then return; fi
    mkdir -p "$(dirname "$path")"
    echo "fetch: $2"
    curl -fL --retry 3 -o "$path.part" "$url"
    if [ "$sum" != - ]; then echo "$sum  $path.part" | sha256sum -c --quiet - || { echo "fetch: checksum mismatch for $2" >&2; exit 1; }; fi
    mv "$path.part" "$path"
}

# TAESD3 (MIT, Ollin Boer Bohan): safetensors export mirrored in ComfyUI's vae_approx folder.
comfy=joshellis625/ComfyUI; comfy_rev=9360bbca8af3fcc01b4f23ed494d127f609442ab
fetch "$(gh $comfy $comfy_rev models/vae_approx/taesd3_encoder.safetensors)" models/taesd3/taesd3_encoder.safetensors e5c96f3476bd26fe73e96d701a694f40d7ab48a290494cbbf70a3697d09cab4a
fetch "$(gh $comfy $comfy_rev models/vae_approx/taesd3_decoder.safetensors)" models/taesd3/taesd3_decoder.safetensors e940e227e2a41919f0735ec423129724666f8b949c8bbce7a04b78ecfb4667de
fetch "$(gh $comfy $comfy_rev models/vae_approx/taef1_encoder.safetensors)" models/taef1/taef1_encoder.safetensors 19f5a854ce575fd0a1c0a52938410cf5fb4dc4b8ae71c8887533646d8fe47030
fetch "$(gh $comfy $comfy_rev models/vae_approx/taef1_decoder.safetensors)" models/taef1/taef1_decoder.safetensors bb41500b646d5b8b592b7f3ca5d20d888c3075e209d178d99af609cd7e02a1d4

# LPIPS v0.1 linear heads and example triplet (BSD-2, richzhang/PerceptualSimilarity).
lp=richzhang/PerceptualSimilarity
fetch "$(gh $lp master lpips/weights/v0.1/squeeze.pth)" models/lpips/official_v0.1_lin/squeeze.pth -
for img in ex_ref ex_p0 ex_p1; do fetch "$(gh $lp master imgs/$img.png)" models/lpips/test_images/$img.png -; done
# The combined SqueezeNet backbone + heads file (lpips_squeeze_v0.1.safetensors) was converted by
# the team from a Jittor port; its public pickle is gone upstream, so it cannot be re-fetched here.

# Scenes: the paper's XMLs (MIT, trinity-graphics/latent-rendering) and Bitterli's scenes.
paper=trinity-graphics/latent-rendering; paper_rev=ec26d54d3ab78059f4be79d4606dc155264c1bbc
fetch "$(gh $paper $paper_rev scenes/cbox_specular.xml)" scenes/cbox/cbox_specular.xml -
tut=mitsuba-renderer/mitsuba-tutorials; tut_rev=a8dbee7e81b1039a983770ce1042f2d78688d0ae
fetch "$(gh $tut $tut_rev scenes/cbox.xml)" scenes/cbox/cbox.xml -
for m in back ceiling floor greenwall redwall luminaire; do
    fetch "$(gh $tut $tut_rev scenes/meshes/cbox_$m.obj)" scenes/cbox/meshes/cbox_$m.obj -
done
ppg=takkasila/practical_path_guiding_lab; ppg_rev=1555ae46d8f1f27234a59d8ec0427d2523f2cb4a
for f in TungstenRender.exr TungstenRender.png; do fetch "$(gh $ppg $ppg_rev scenes/cornell-box/$f)" scenes/cornell-box/$f -; done
echo "fetch-shared: done. Bitterli's scene_v3.xml files were edited by the team (see their SOURCE.txt); copy them from a team checkout."
