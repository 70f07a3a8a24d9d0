#!/usr/bin/env bash
# A fuzzing campaign: each harness of tests/fuzz under libFuzzer + ASan + UBSan for SECONDS
# (default 600), JOBS at a time (default 1). Needs clang (its libclang-rt-14-dev carries
# libFuzzer); installed here with apt-get when missing, since only fuzzing needs it.
# Seeds: tests/fuzz/corpus/<harness> plus small files of the same kind from ../shared (scenes,
# meshes, textures). A crash, leak, hang or rejection without a file name is copied into
# tests/fuzz/corpus/<harness>/finding-<sha1>, so the replay test keeps it.
# Inputs that add coverage join tests/fuzz/corpus/<harness> (libFuzzer's -merge=1).
# Prints one row per harness (executions, executions/s, findings); build-fuzz/summary.tsv.
#   scripts/fuzz.sh [--seconds N] [--jobs J] [harness ...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=600
jobs=1
harnesses=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    -h|--help) sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
if ! command -v clang++ >/dev/null; then
  echo "fuzz.sh: clang++ not found; installing Debian's clang (only fuzzing needs it)"
  SUDO=""; [[ "$(id -u)" == 0 ]] || SUDO=sudo
  $SUDO apt-get install -y -qq --no-install-recommends clang
fi
[[ ${#harnesses[@]} -gt 0 ]] || harnesses=($(ls tests/fuzz/corpus))
[[ "${LPT_FUZZ_NO_BUILD:-}" == 1 ]] || bash scripts/build-sanitize.sh --fuzz
shared="${LATENTPT_SHARED:-$PWD/../shared}"

shared_seeds() {  # harness -> small files of its kind from ../shared
  local pattern
  case "$1" in
    scene_xml) pattern='*.xml' ;; obj) pattern='*.obj' ;; ply) pattern='*.ply' ;;
    image) pattern='*.png -o -name *.jpg -o -name *.exr -o -name *.hdr' ;; gltf) pattern='*.gltf -o -name *.glb' ;;
    *) return 0 ;;
  esac
  [[ -d "$shared/scenes" ]] || return 0
  # shellcheck disable=SC2086
  find "$shared/scenes" -type f \( -name $pattern \) -size -64k | head -200
}

run_one() {
  local h="$1" work="build-fuzz/work/$1" log="build-fuzz/logs/$1.log"
  rm -rf "$work" && mkdir -p "$work/corpus" "$work/artifacts" build-fuzz/logs
  cp tests/fuzz/corpus/"$h"/* "$work/corpus/"
  shared_seeds "$h" | while read -r f; do cp "$f" "$work/corpus/shared-$(sha1sum "$f" | cut -c1-12)"; done
  local max_len=8192
  [[ "$h" == fit_state ]] && max_len=131072
  set +e
  # Slow unwinding shows the frames of uninstrumented libraries, which lsan.supp names; only the
  # image harness needs it (OpenImageIO), and it costs the others most of their speed.
  local unwind=1
  [[ "$h" == image ]] && unwind=0
  ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=$unwind LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan.supp \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    build-fuzz/tests/fuzz/fuzz_"$h" "$work/corpus" -max_total_time="$seconds" -max_len="$max_len" \
    -timeout=20 -rss_limit_mb=3072 -print_final_stats=1 -artifact_prefix="$work/artifacts/" \
    -close_fd_mask=1 >"$log" 2>&1
  local rc=$?
  set -e
  # Keep what raised coverage: inputs that add features to the saved corpus join it (named by
  # their SHA-1), so fuzz.replay.* replays them. Not for fit_state, whose inputs are ~30 kB, and
  # not where ../shared seeded the run: its third-party files (and near copies) stay out of git.
  if [[ "$h" != fit_state && -z "$(shared_seeds "$h")" ]]; then
    ASAN_OPTIONS=detect_leaks=0 build-fuzz/tests/fuzz/fuzz_"$h" -merge=1 -max_len="$max_len" \
      tests/fuzz/corpus/"$h" "$work/corpus" >"build-fuzz/logs/$h.merge.log" 2>&1 || true
  fi
  local execs rate findings=0
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  for a in "$work"/artifacts/*; do
    [[ -f "$a" ]] || continue
    cp "$a" tests/fuzz/corpus/"$h"/finding-"$(sha1sum "$a" | cut -c1-12)"
    findings=$((findings + 1))
  done
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$h" "$seconds" "${execs:-0}" "${rate:-0}" "$findings" "$rc" >>build-fuzz/summary.tsv
  printf '%-12s %6ss %10s runs %7s/s  findings %s  (exit %s, log %s)\n' "$h" "$seconds" "${execs:-0}" "${rate:-0}" "$findings" "$rc" "$log"
}

printf 'harness\tseconds\texecutions\texec_per_s\tfindings\texit\n' >build-fuzz/summary.tsv
running=0
for h in "${harnesses[@]}"; do
  run_one "$h" &
  running=$((running + 1))
  if [[ $running -ge $jobs ]]; then wait -n; running=$((running - 1)); fi
done
wait
