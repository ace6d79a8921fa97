#!/usr/bin/env bash
# Ours vs YADE on the same packing file, same law (A-Table 1 / CohFrictMat), same Δt and
# number of steps, on the same machine, alternating runs; prints the ratio of medians.
# Not run in CI. Installs Debian's python3-yade (needs root/sudo and network to Debian).
#
#   benchmarks/peers/yade/run.sh [N=10000] [STEPS=2000] [ROUNDS=3]
set -euo pipefail
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
N=${1:-10000}; STEPS=${2:-2000}; ROUNDS=${3:-3}; DT=1e-7
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../../.." && pwd)
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

command -v yade >/dev/null || { $SUDO apt-get update && $SUDO apt-get install -y python3-yade; }
(cd "$root" && cargo build --release -p thm-benchmarks --bin dem_peer)
peer="$root/target/release/dem_peer"

"$peer" write-lattice "$work/plane.csv" "$N" PLANE
"$peer" write-lattice "$work/3d.csv" "$N" 3D
"$peer" write-bar "$work/bar.csv" 1

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
for case in plane 3d bar; do
  for threads in 1 2; do
    : > "$work/ours"; : > "$work/yade"
    for _ in $(seq "$ROUNDS"); do
      "$peer" run-cohesive "$work/$case.csv" "$STEPS" "$DT" "$threads" | awk '{print $4}' >> "$work/ours"
      OMP_NUM_THREADS=$threads yade -n -j "$threads" -x "$here/yade_cohesive.py" "$work/$case.csv" "$STEPS" "$DT" \
        | tail -1 | awk '{print $4}' >> "$work/yade"
    done
    o=$(median < "$work/ours"); y=$(median < "$work/yade")
    printf '%-6s %d thread(s): ours %.3g, YADE %.3g particle-steps/s, ratio %.2f\n' \
      "$case" "$threads" "$o" "$y" "$(echo "$o / $y" | bc -l)"
  done
done
