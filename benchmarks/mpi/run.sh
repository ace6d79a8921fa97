#!/usr/bin/env bash
# The biaxial test's RVE stage (B-Sect. 5.3.1, the paper's 800 RVEs of 400 disks by default) on
# 1 rank x 1 thread, 2 ranks x 1 thread and 1 rank x 2 threads, alternated round by round on
# this machine; prints every round's per-step medians (the step, the MPM part every rank
# repeats, the RVE part, its block compute and its communication) and the CPU that other
# processes used meanwhile, then the medians over the rounds and the RVE part's speed-ups
# against 1 rank x 1 thread. A round in which other processes used more than LOAD_MAX of a
# core is repeated (see ../peers/common.sh). Not run in CI. Needs Open MPI (openmpi-bin,
# libopenmpi-dev) and libclang-dev to build.
#
#   benchmarks/mpi/run.sh [ROUNDS=3] [STEPS=4] [NX=10 NY=20 [DISKS=400]]
#   LOAD_MAX=0.05 REPEATS=3 KEEP_WORK=1 as in ../peers/common.sh
set -euo pipefail
ROUNDS=${1:-3}; STEPS=${2:-4}; NX=${3:-10}; NY=${4:-20}; DISKS=${5:-400}
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../.." && pwd)
# shellcheck source-path=SCRIPTDIR/../peers source=../peers/common.sh
. "$here/../peers/common.sh"
make_work

(cd "$root" && cargo build --release -p thm-benchmarks --features mpi --bin mpi_rve_stage)
target=$(cd "$root" && realpath -m -- "${CARGO_TARGET_DIR:-target}")
bin="$target/release/mpi_rve_stage"
root_flag=()
[ "$(id -u)" = 0 ] && root_flag=(--allow-run-as-root)

# value OUT KEY: the number after KEY on the result line.
value() {
  awk -v k="$2" '{for (i = 1; i < NF; i++) if ($i == k) {print $(i + 1); found = 1}}
    END {if (!found) {print "no " k " in " FILENAME > "/dev/stderr"; exit 1}}' "$1"
}

configs=("1 1" "2 1" "1 2")
for r in $(seq "$ROUNDS"); do
  for c in "${configs[@]}"; do
    read -r ranks threads <<< "$c"
    quiet_run "round $r, $ranks rank(s) x $threads thread(s)" "$work/out" \
      env RAYON_NUM_THREADS="$threads" mpirun "${root_flag[@]}" --oversubscribe --bind-to none \
      -np "$ranks" "$bin" "$STEPS" "$NX" "$NY" "$DISKS"
    key="${ranks}x${threads}"
    for k in step_ms mpm_ms rve_ms block_ms comm_ms; do
      value "$work/out" "$k" >> "$work/$key.$k"
    done
    printf 'round %d, %d rank(s) x %d thread(s): step %s ms, MPM %s ms, RVE part %s ms (block %s ms, communication %s ms) per step; others %s cores%s\n' \
      "$r" "$ranks" "$threads" "$(value "$work/out" step_ms)" "$(value "$work/out" mpm_ms)" \
      "$(value "$work/out" rve_ms)" "$(value "$work/out" block_ms)" \
      "$(value "$work/out" comm_ms)" "$QUIET_OTHERS" "${QUIET_FLAG:+, DISTURBED}"
  done
done
echo
echo "| ranks x threads | step [ms] | MPM part [ms] | RVE part [ms] | block [ms] | communication [ms] | RVE part speed-up vs 1 x 1 |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
base=$(median < "$work/1x1.rve_ms")
for c in "${configs[@]}"; do
  read -r ranks threads <<< "$c"
  key="${ranks}x${threads}"
  m() { median < "$work/$key.$1"; }
  printf '| %d x %d | %.1f | %.1f | %.1f | %.1f | %.3f | %s |\n' "$ranks" "$threads" \
    "$(m step_ms)" "$(m mpm_ms)" "$(m rve_ms)" "$(m block_ms)" "$(m comm_ms)" \
    "$(ratio "$base" "$(m rve_ms)")"
done
echo "(medians of $ROUNDS rounds, each the median of $STEPS steps after 1 warm-up; ${NX}x${NY} cells x 4 points, $DISKS disks per RVE;"
echo " others = cores used by other processes during a run, DISTURBED if still over $LOAD_MAX after $REPEATS repeats)"
if ((DISTURBED_TOTAL > 0)); then
  echo "WARNING: $DISTURBED_TOTAL run(s) stayed disturbed; the figures do not describe a quiet machine" >&2
fi
