#!/usr/bin/env bash
# Installs every Debian package latentpt needs (idempotent). Run as root or with sudo.
# Package choices and pitfalls: ../shared/BUILD-NOTES.md
#  - openimageio-tools: OpenImageIO's CMake config fails without its binaries.
#  - libopenblas0-pthread: otherwise libtorch matrix products fall back to reference BLAS.
#  - python3-torch: only for tools/export_*.py (TorchScript VAEs) and the test that exports
#    TAESD3 and checks the TorchScript path against the native one.
#  - clang-format-14: the format check in ctest (.clang-format).
#  - pybind11-dev, python3-dev, python3-numpy: `import latentpt` (python/, docs/python.md).
#  - libopenexr-dev, libpng-dev: EXR and PNG are written directly (OpenImageIO only reads, from
#    a plugin opened on demand: docs/performance.md, start-up).
#  - snakemake: the experiment workflow (workflow/Snakefile, scripts/experiment.py). Slurm
#    (slurm-wlm, munge) only for tests/slurm/test_quick_on_slurm.sh, which installs it on demand.
#  - The test suite's sanitizer replay of the fuzz corpus builds with g++; clang (for libFuzzer)
#    is installed on demand by scripts/fuzz.sh, which alone needs it (docs/reliability.md).
set -euo pipefail
pkgs=(
  build-essential cmake ninja-build ccache pkg-config
  libembree-dev libeigen3-dev libtbb-dev
  libtorch-dev libopenblas0-pthread
  libopenimageio-dev openimageio-tools libopenexr-dev libpng-dev
  libtinygltf-dev nlohmann-json3-dev libpugixml-dev libtinyobjloader-dev libcli11-dev
  libgtest-dev libbenchmark-dev
  python3-torch
  clang-format-14
  pybind11-dev python3-dev python3-numpy
  snakemake
)
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
