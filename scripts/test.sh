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
# LeakSanitizer's exit-time tracer now and then crashes by itself ("Tracer caught signal 11",
# google/sanitizers#1353) after every input replayed cleanly: seen once in ~20 replays here. Such
# a run, and only such a run (no sanitizer report in the log), is replayed once more.
lsan_tracer_crash_only() {
  local log=Testing/Temporary/LastTest.log
  grep -q 'Tracer caught signal' "$log" && grep -q 'LeakSanitizer has encountered a fatal error' "$log" &&
    ! grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer: detected)|runtime error:' "$log"
}
if [[ "${LATENTPT_NO_SANITIZE:-}" != 1 ]]; then
  bash scripts/build-sanitize.sh
  (cd build-sanitize && { ctest --output-on-failure -j "$(nproc)" --timeout 900 -R '^fuzz\.replay\.' ||
    { lsan_tracer_crash_only && echo "test.sh: LeakSanitizer's tracer crashed (no finding); replaying the failed corpus once more" &&
      ctest --output-on-failure --timeout 900 --rerun-failed; }; })
fi
