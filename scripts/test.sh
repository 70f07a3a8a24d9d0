#!/usr/bin/env bash
# Fresh Debian → installed, built, and the test suite run with ctest.
# Tests that need ../shared (weights, third-party scenes) skip with a message when it is absent;
# LATENTPT_SHARED=/path/to/shared points them elsewhere.
# Then the fuzz corpus is replayed under AddressSanitizer + UndefinedBehaviorSanitizer
# (build-sanitize/, torch-free libraries only; docs/reliability.md). LATENTPT_NO_SANITIZE=1
# skips that part.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
(cd build && ctest --output-on-failure -j "$(nproc)" --timeout 900)
if [[ "${LATENTPT_NO_SANITIZE:-}" != 1 ]]; then
  bash scripts/build-sanitize.sh
  (cd build-sanitize && ctest --output-on-failure -j "$(nproc)" --timeout 900 -R '^fuzz\.replay\.')
fi
