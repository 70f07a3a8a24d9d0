#!/usr/bin/env bash
# Fresh Debian → installed, built, and the test suite run with ctest.
# Tests that need ../shared (weights, third-party scenes) skip with a message when it is absent;
# LATENTPT_SHARED=/path/to/shared points them elsewhere.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 900
