#!/usr/bin/env bash
# Ours vs LIGGGHTS on the same settled frictional bed (10 000 and 100 000 spheres, linear
# springs + Coulomb), 1 and 2 MPI ranks vs 1 and 2 threads, alternating runs. Prints, per
# round, particle-steps per second, neighbour-list builds during the timed steps, the kinetic
# energy after them (same physics on both sides) and the CPU other processes used meanwhile;
# then the medians and their ratio. A round in which other processes used more than LOAD_MAX
# of a core is repeated (see ../common.sh). Not run in CI. Installs Debian's liggghts and
# openmpi-bin (needs root/sudo and network to Debian).
#
#   SIZES="10000 100000" benchmarks/peers/liggghts/run.sh [STEPS=2000] [ROUNDS=3]
#   LOAD_MAX=0.05 REPEATS=3 KEEP_WORK=1 as in ../common.sh
#   BED_DIR=DIR: take DIR/bedN.csv when it exists (written before by `dem_peer write-bed`;
#   the 100 000-sphere bed takes 15 CPU minutes to settle) instead of settling it again
#   ORDER=--locality-order (the default): ours renumbers the bed's spheres before the run
#   (Packing::in_locality_order), as LIGGGHTS sorts its atoms spatially in the set-up of every
#   run (atom_modify sort, on by default); ORDER= keeps the file's numbering
set -euo pipefail
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
as_root=()
if [ "$(id -u)" = 0 ]; then as_root=(--allow-run-as-root); fi
STEPS=${1:-2000}; ROUNDS=${2:-3}; DT=5e-7; ORDER=${ORDER---locality-order}
order=(); if [ -n "$ORDER" ]; then order=("$ORDER"); fi
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../../.." && pwd)
# shellcheck source-path=SCRIPTDIR/.. source=common.sh
. "$here/../common.sh"
make_work

command -v liggghts >/dev/null || { $SUDO apt-get update && $SUDO apt-get install -y liggghts openmpi-bin; }
(cd "$root" && cargo build --release -p thm-benchmarks --bin dem_peer)
# CARGO_TARGET_DIR (relative to the workspace root, as cargo reads it) is honoured.
target=$(cd "$root" && realpath -m -- "${CARGO_TARGET_DIR:-target}")
peer="$target/release/dem_peer"

# lig_figures OUT ATOMS: "rate builds kinetic_energy" from LIGGGHTS's screen output (the timed
# run is the last one: its "Loop time" and "Neighbor list builds"; in.bed prints the energy).
lig_figures() {
  awk -v n="$2" '/^Loop time of/ {t = $4; s = $9} /^Neighbor list builds/ {b = $NF}
    $1 == "kinetic_energy" {e = $2}
    END {
      if (t == "" || b == "" || e == "") {print "LIGGGHTS output incomplete: " FILENAME > "/dev/stderr"; exit 1}
      printf "%.1f %s %s\n", n * s / t, b, e
    }' "$1"
}

# show "rate builds energy others [disturbed]": the same, labelled.
show() {
  awk '{printf "%.4g/s, %s builds, KE %s J, others %s cores%s", $1, $2, $3, $4, ($5 == "" ? "" : ", DISTURBED")}' <<< "$1"
}

for n in ${SIZES:-10000 100000}; do
  if [ -n "${BED_DIR:-}" ] && [ -f "$BED_DIR/bed$n.csv" ]; then
    cp "$BED_DIR/bed$n.csv" "$work/bed$n.csv"
  else
    "$peer" write-bed "$work/bed$n.csv" "$n"
  fi
  python3 "$here/csv_to_data.py" "$work/bed$n.csv" 2500 "$work/bed$n.data"
  atoms=$(grep -c '^particle' "$work/bed$n.csv")
  for p in 1 2; do
    : > "$work/ours"; : > "$work/lig"
    for r in $(seq "$ROUNDS"); do
      quiet_run "bed $atoms, $p, round $r, ours" "$work/out" \
        "$peer" run-bed "$work/bed$n.csv" "$STEPS" "$DT" "$p" "${order[@]}"
      # One assignment per substitution: set -e sees only the last one's status.
      o=$(rate "$work/out"); ob=$(field "$work/out" neighbour_builds)
      oe=$(field "$work/out" kinetic_energy)
      o="$o $ob $oe $QUIET_OTHERS $QUIET_FLAG"
      quiet_run "bed $atoms, $p, round $r, LIGGGHTS" "$work/out" \
        mpirun "${as_root[@]}" --oversubscribe -np "$p" liggghts -in "$here/in.bed" -log none -echo none \
        -var datafile "$work/bed$n.data" -var zfloor -5e-4 -var dt "$DT" -var steps "$STEPS" -var warmup 1
      l=$(lig_figures "$work/out" "$atoms"); l="$l $QUIET_OTHERS $QUIET_FLAG"
      echo "$o" >> "$work/ours"; echo "$l" >> "$work/lig"
      os=$(show "$o"); lgs=$(show "$l")
      printf 'bed %6d, %d thread(s)/rank(s), round %d: ours %s | LIGGGHTS %s\n' "$atoms" "$p" "$r" "$os" "$lgs"
    done
    om=$(median < "$work/ours"); lm=$(median < "$work/lig"); ratio=$(ratio "$om" "$lm")
    printf 'bed %6d, %d thread(s)/rank(s): median ours %.4g, LIGGGHTS %.4g particle-steps/s, ratio %s\n' \
      "$atoms" "$p" "$om" "$lm" "$ratio"
  done
done
echo "(round lines: particle-steps/s, neighbour-list builds in the timed steps, kinetic energy"
echo " after them, cores used by other processes during the run, DISTURBED if still over $LOAD_MAX"
echo " after $REPEATS repeats; medians of $ROUNDS rounds of $STEPS steps, dt $DT s)"
if ((DISTURBED_TOTAL > 0)); then
  echo "WARNING: $DISTURBED_TOTAL run(s) stayed disturbed; the figures do not describe a quiet machine" >&2
fi
