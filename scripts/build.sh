#!/usr/bin/env bash
# Configures and builds latentpt into ./build (Release, Ninja, ccache when installed).
set -euo pipefail
cd "$(dirname "$0")/.."
# Paths below the checkout enter ccache's keys relative to it, so two checkouts (a CI clone, a
# worktree) share cached objects.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)"
