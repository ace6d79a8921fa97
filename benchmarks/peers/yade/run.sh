#!/usr/bin/env bash
# Ours vs YADE on the same packing file, same law (A-Table 1 / CohFrictMat), same Δt and
# number of steps, on the same machine, alternating runs, on a loaded case: a bonded lattice
# (plane and 3D, `dem_peer write-lattice ... APART`) pulled apart along y at SPEED m/s at each
# end (`dem_peer run-pull`, `yade_cohesive.py ... SPEED`), so that stress waves run, bonds
# break in tension and shear and new contacts form within the timed steps. Prints, per round,
# particle-steps per second, the broken bonds, the kinetic energy of the spheres not held and
# the force on the top grip after the timed steps (the same physics on both sides; ours also
# its neighbour-list builds) and the CPU other processes used meanwhile; then the medians and
# their ratio. A round in which other processes used more than LOAD_MAX of a core is repeated
# (see ../common.sh). Not run in CI. Installs Debian's python3-yade (needs root/sudo and
# network to Debian).
#
#   benchmarks/peers/yade/run.sh [N=10000] [STEPS=3000] [ROUNDS=3] [SPEED=1.0]
#   LOAD_MAX=0.05 REPEATS=3 KEEP_WORK=1 as in ../common.sh
set -euo pipefail
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
N=${1:-10000}; STEPS=${2:-3000}; ROUNDS=${3:-3}; SPEED=${4:-1.0}; DT=1e-7
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../../.." && pwd)
# shellcheck source-path=SCRIPTDIR/.. source=common.sh
. "$here/../common.sh"
make_work

command -v yade >/dev/null || { $SUDO apt-get update && $SUDO apt-get install -y yade python3-yade; }
(cd "$root" && cargo build --release -p thm-benchmarks --bin dem_peer)
# CARGO_TARGET_DIR (relative to the workspace root, as cargo reads it) is honoured.
target=$(cd "$root" && realpath -m -- "${CARGO_TARGET_DIR:-target}")
peer="$target/release/dem_peer"

"$peer" write-lattice "$work/plane.csv" "$N" PLANE APART
"$peer" write-lattice "$work/3d.csv" "$N" 3D APART

for case in plane 3d; do
  for threads in 1 2; do
    : > "$work/ours"; : > "$work/yade"
    for r in $(seq "$ROUNDS"); do
      quiet_run "$case, $threads, round $r, ours" "$work/out" \
        "$peer" run-pull "$work/$case.csv" "$STEPS" "$DT" "$threads" "$SPEED"
      o=$(rate "$work/out"); ob=$(field "$work/out" neighbour_builds)
      oe=$(field "$work/out" free_kinetic_energy); obb=$(field "$work/out" broken_bonds)
      of_=$(field "$work/out" top_grip_force_y); oo=$QUIET_OTHERS; of=$QUIET_FLAG
      quiet_run "$case, $threads, round $r, YADE" "$work/out" \
        env OMP_NUM_THREADS="$threads" yade -n -j "$threads" -x "$here/yade_cohesive.py" \
        "$work/$case.csv" "$STEPS" "$DT" "$SPEED"
      y=$(rate "$work/out"); ye=$(field "$work/out" free_kinetic_energy)
      ybb=$(field "$work/out" broken_bonds); yf=$(field "$work/out" top_grip_force_y)
      echo "$o" >> "$work/ours"; echo "$y" >> "$work/yade"
      printf '%-6s %d thread(s), round %d: ours %.4g/s, %s builds, %s broken, free KE %s J, grip %s N, others %s cores%s | YADE %.4g/s, %s broken, free KE %s J, grip %s N, others %s cores%s\n' \
        "$case" "$threads" "$r" "$o" "$ob" "$obb" "$oe" "$of_" "$oo" "${of:+, DISTURBED}" \
        "$y" "$ybb" "$ye" "$yf" "$QUIET_OTHERS" "${QUIET_FLAG:+, DISTURBED}"
    done
    om=$(median < "$work/ours"); ym=$(median < "$work/yade"); ratio=$(ratio "$om" "$ym")
    printf '%-6s %d thread(s): median ours %.4g, YADE %.4g particle-steps/s, ratio %s\n' \
      "$case" "$threads" "$om" "$ym" "$ratio"
  done
done
echo "(medians of $ROUNDS rounds of $STEPS steps, dt $DT s, ends pulled at $SPEED m/s; others = cores used by other processes"
echo " during a run, DISTURBED if still over $LOAD_MAX after $REPEATS repeats)"
if ((DISTURBED_TOTAL > 0)); then
  echo "WARNING: $DISTURBED_TOTAL run(s) stayed disturbed; the figures do not describe a quiet machine" >&2
fi
