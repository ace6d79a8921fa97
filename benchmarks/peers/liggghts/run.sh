#!/usr/bin/env bash
# Ours vs LIGGGHTS on the same settled frictional bed (10 000 and 100 000 spheres, linear
# springs + Coulomb), 1 and 2 MPI ranks vs 1 and 2 threads, alternating runs; prints
# particle-steps per second and the ratio of medians. Not run in CI. Installs Debian's
# liggghts and openmpi-bin (needs root/sudo and network to Debian).
#
#   benchmarks/peers/liggghts/run.sh [STEPS=2000] [ROUNDS=3]
set -euo pipefail
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
STEPS=${1:-2000}; ROUNDS=${2:-3}; DT=2e-6
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../../.." && pwd)
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

command -v liggghts >/dev/null || { $SUDO apt-get update && $SUDO apt-get install -y liggghts openmpi-bin; }
(cd "$root" && cargo build --release -p thm-benchmarks --bin dem_peer)
peer="$root/target/release/dem_peer"

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
for n in 10000 100000; do
  "$peer" write-bed "$work/bed$n.csv" "$n"
  python3 "$here/csv_to_data.py" "$work/bed$n.csv" 2500 "$work/bed$n.data"
  atoms=$(grep -c '^particle' "$work/bed$n.csv")
  for p in 1 2; do
    : > "$work/ours"; : > "$work/lig"
    for _ in $(seq "$ROUNDS"); do
      "$peer" run-bed "$work/bed$n.csv" "$STEPS" "$DT" "$p" | awk '{print $4}' >> "$work/ours"
      mpirun --oversubscribe -np "$p" liggghts -in "$here/in.bed" -log none -echo none \
        -var datafile "$work/bed$n.data" -var zfloor -5e-4 -var dt "$DT" -var steps "$STEPS" \
        | awk -v n="$atoms" '/^Loop time of/ {t=$4; s=$(NF-3)} END {printf "%.1f\n", n*s/t}' >> "$work/lig"
    done
    o=$(median < "$work/ours"); l=$(median < "$work/lig")
    printf 'bed %6d, %d thread(s)/rank(s): ours %.3g, LIGGGHTS %.3g particle-steps/s, ratio %.2f\n' \
      "$atoms" "$p" "$o" "$l" "$(echo "$o / $l" | bc -l)"
  done
done
