#!/usr/bin/env bash
# The torch-free libraries and the fuzz harnesses' corpus replays, built with AddressSanitizer +
# UndefinedBehaviorSanitizer into ./build-sanitize (docs/reliability.md). With --fuzz: libFuzzer
# binaries instead, built by clang into ./build-fuzz (scripts/fuzz.sh runs them).
set -euo pipefail
cd "$(dirname "$0")/.."
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
if [[ "${1:-}" == "--fuzz" ]]; then
  dir=build-fuzz
  flags=(-DCMAKE_CXX_COMPILER=clang++ -DLATENTPT_FUZZ=ON)
else
  dir=build-sanitize
  flags=()
fi
cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DLATENTPT_WITH_TORCH=OFF \
  -DLATENTPT_SANITIZE=ON -DLATENTPT_BUILD_PYTHON=OFF "${flags[@]}" >/dev/null
cmake --build "$dir" -j "$(nproc)" --target lpt_fuzz_targets
