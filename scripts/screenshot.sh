#!/bin/bash
# Screenshots of an experiment's report and plots in a real browser (headless Chromium), to check
# every plot's axes, labels and units as a reader sees them (issue 16).
#
#   scripts/screenshot.sh <results-folder> [<out-folder>]
#
# Writes <out>/report.png (the whole report.html) and one PNG per SVG plot (default out:
# <results>/screenshots). Validation only: Chromium is not a build or test dependency; this
# script installs Debian's chromium package on demand (apt-get, needs root) and says so.
set -euo pipefail
results=${1:?usage: scripts/screenshot.sh <results-folder> [<out-folder>]}
out=${2:-$results/screenshots}
[ -f "$results/report.html" ] || { echo "screenshot: $results/report.html not found (run scripts/experiment.py first)" >&2; exit 1; }
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
    echo "screenshot: installing Debian's chromium (validation only, not needed to build or test)" >&2
    apt-get install -y -q chromium > /dev/null
    browser=$(command -v chromium)
fi
mkdir -p "$out"
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
# The flags keep Chromium off the network (this machine has none) and out of the user's profile.
shoot() {  # shoot <file> <png> <width> <height>
    "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --hide-scrollbars \
        --disable-background-networking --disable-component-update --disable-sync --user-data-dir="$profile" \
        --window-size="$3,$4" --screenshot="$2" "file://$(realpath "$1")" > /dev/null 2>&1
    [ -s "$2" ] || { echo "screenshot: Chromium wrote no $2" >&2; exit 1; }
}
shoot "$results/report.html" "$out/report.png" 1280 12000
n=0
for svg in "$results"/*.svg; do
    [ -e "$svg" ] || continue
    w=$(grep -o 'width="[0-9]*"' "$svg" | head -1 | tr -dc 0-9)
    h=$(grep -o 'height="[0-9]*"' "$svg" | head -1 | tr -dc 0-9)
    shoot "$svg" "$out/$(basename "$svg" .svg).png" "${w:-480}" "${h:-260}"
    n=$((n + 1))
done
echo "wrote $out/report.png and $n plot screenshots"
