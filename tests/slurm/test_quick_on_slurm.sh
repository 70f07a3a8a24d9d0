#!/usr/bin/env bash
# The --quick experiment through a real single-node Slurm (started on localhost by cluster.sh,
# stopped afterwards) gives the summary.json of the same run done locally (issue 20). Too slow
# for CI's default suite (two quick runs; time in docs/workflow.md); run it by hand:
#   tests/slurm/test_quick_on_slurm.sh [build/apps/latentpt] [outdir]
# Needs root (munged, slurmctld, slurmd) and Debian's slurm-wlm and munge, installed here with
# apt-get when missing (only this test uses them), and snakemake (scripts/install-deps.sh).
set -euo pipefail
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  echo "test_quick_on_slurm: installing Debian's slurm-wlm and munge (only this test needs them)" >&2
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge >&2
fi
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="${1:-$root/build/apps/latentpt}"
out="${2:-$root/build/slurm-quick}"
state="/tmp/lpt-slurm-$$"  # Unix socket paths must stay short
rm -rf "$out" && mkdir -p "$out"
trap 'bash "$here/cluster.sh" stop "$state" >&2 || true; rm -rf "$state"' EXIT
eval "$(bash "$here/cluster.sh" start "$state")"
export SLURM_CONF
# CI=true: Snakemake's cluster mode then checks job status without its 10 s sleep.
t0=$(date +%s)
CI=true python3 "$root/scripts/experiment.py" --quick --slurm --bin "$bin" --out "$out/slurm" >"$out/slurm.log" 2>&1
t1=$(date +%s)
python3 "$root/scripts/experiment.py" --quick --bin "$bin" --out "$out/local" >"$out/local.log" 2>&1
t2=$(date +%s)
jobs=$(ls "$out"/slurm/.snakemake/slurm-*.out 2>/dev/null | wc -l)
echo "Slurm run: $((t1 - t0)) s, $jobs jobs through sbatch; local run: $((t2 - t1)) s"
if cmp -s "$out/slurm/summary.json" "$out/local/summary.json" && [[ $jobs -gt 0 ]]; then
  echo "test_quick_on_slurm: summary.json of the Slurm run equals the local run's"
else
  echo "test_quick_on_slurm: FAILED (summary.json differs or no job went through Slurm)"
  diff "$out/slurm/summary.json" "$out/local/summary.json" | head -20
  exit 1
fi
