#!/usr/bin/env bash
# Ours vs GeoTaichi 0.2.6 (CPU backend) on the same Drucker–Prager uGIMP granular column
# collapse, 1 and 2 threads, alternating runs; prints, per round, point-steps per second (wall
# and per CPU second) and the CPU other processes used meanwhile, then the medians and the ratio
# ours/GeoTaichi. A run in which other processes used more than LOAD_MAX of a core is repeated
# (see ../common.sh). Not run in CI. Installs Debian's libgeos-dev
# (needs root/sudo and network to Debian) and GeoTaichi from PyPI into a virtual environment.
#
#   benchmarks/peers/geotaichi/run.sh [STEPS=200] [ROUNDS=3]
#   LOAD_MAX=0.05 REPEATS=3 KEEP_WORK=1 as in ../common.sh
#
# The columns are those of `cargo run --release -p thm-benchmarks --example mpm_rate -- STEPS`:
# 40 000 points for STEPS steps and 99 856 points for STEPS/4 steps.
# GEOTAICHI_VENV (default target/peers/geotaichi-venv) and PYTHON (default python3) override.
set -euo pipefail
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
STEPS=${1:-200}; ROUNDS=${2:-3}
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../../.." && pwd)
venv=$(realpath -m -- "${GEOTAICHI_VENV:-$root/target/peers/geotaichi-venv}")
# shellcheck source-path=SCRIPTDIR/.. source=common.sh
. "$here/../common.sh"
make_work

if ! "$venv/bin/python" -c 'import src.mpm.mainMPM' >/dev/null 2>&1; then
  # Shapely 1.8.0 (pinned by GeoTaichi) builds from source against GEOS.
  dpkg -s libgeos-dev >/dev/null 2>&1 || { $SUDO apt-get update && $SUDO apt-get install -y libgeos-dev; }
  "${PYTHON:-python3}" -m venv "$venv"
  # 0.2.6 declares Requires-Python <= 3.11, which excludes 3.11.x patch releases and newer.
  "$venv/bin/pip" install --ignore-requires-python geotaichi==0.2.6 >&2
fi
(cd "$root" && cargo build --release -p thm-benchmarks --example mpm_rate)
# CARGO_TARGET_DIR (relative to the workspace root, as cargo reads it) is honoured.
target=$(cd "$root" && realpath -m -- "${CARGO_TARGET_DIR:-target}")
ours="$target/release/examples/mpm_rate"

# GeoTaichi's point counts, steps and the matching lines of mpm_rate.
cases="40000:100:$STEPS 99856:158:$((STEPS / 4))"
# GeoTaichi writes its output next to the working directory.
cd "$work"
for r in $(seq "$ROUNDS"); do
  # One run of ours gives every (size, threads) figure; then GeoTaichi on each.
  quiet_run "round $r, ours (all cases)" "$work/ours.txt" "$ours" "$STEPS"
  ours_others=$QUIET_OTHERS; ours_flag=$QUIET_FLAG
  for c in $cases; do
    IFS=: read -r n side steps <<< "$c"
    for t in 1 2; do
      # "drucker_prager    40000 pts 1t:   3.10 M pt-steps/s wall,   3.20 M pt-steps per CPU-s"
      o=$(awk -v n="$n" -v t="${t}t:" '$1 == "drucker_prager" && $2 == n && $4 == t \
        {print $5 * 1e6, $9 * 1e6; found = 1} END {exit !found}' "$work/ours.txt") \
        || { echo "no drucker_prager $n ${t}t line in mpm_rate's output" >&2; exit 1; }
      quiet_run "round $r, $n points, $t thread(s), GeoTaichi" "$work/geo.txt" \
        "$venv/bin/python" "$here/geotaichi_column.py" "$side" "$t" "$steps"
      g=$(awk '$1 == "RESULT" {print $4, $5; found = 1} END {exit !found}' "$work/geo.txt") \
        || { echo "no RESULT line in GeoTaichi's output:" >&2; cat "$work/geo.txt" "$work/geo.txt.err" >&2; exit 1; }
      echo "$o" >> "$work/ours-$n-$t"; echo "$g" >> "$work/geo-$n-$t"
      read -r ow oc <<< "$o"; read -r gw gc <<< "$g"
      printf 'round %d, %6d points, %d thread(s): ours %.4g wall, %.4g per CPU-s, others %s cores%s | GeoTaichi %.4g wall, %.4g per CPU-s, others %s cores%s\n' \
        "$r" "$n" "$t" "$ow" "$oc" "$ours_others" "${ours_flag:+, DISTURBED}" \
        "$gw" "$gc" "$QUIET_OTHERS" "${QUIET_FLAG:+, DISTURBED}"
    done
  done
done

printf '%-8s %-3s %-28s %-28s %-14s\n' points thr 'ours wall | per CPU-s' 'GeoTaichi wall | per CPU-s' 'ratio wall|CPU'
for c in $cases; do
  IFS=: read -r n side steps <<< "$c"
  for t in 1 2; do
    ow=$(cut -d' ' -f1 "$work/ours-$n-$t" | median); oc=$(cut -d' ' -f2 "$work/ours-$n-$t" | median)
    gw=$(cut -d' ' -f1 "$work/geo-$n-$t" | median); gc=$(cut -d' ' -f2 "$work/geo-$n-$t" | median)
    rw=$(ratio "$ow" "$gw"); rc=$(ratio "$oc" "$gc")
    printf '%-8s %-3s %8.3g | %-17.3g %8.3g | %-17.3g %5.2f | %.2f\n' "$n" "$t" \
      "$ow" "$oc" "$gw" "$gc" "$rw" "$rc"
  done
done
echo "(point-steps per second; medians of $ROUNDS alternating runs; $STEPS steps at 40 000 points, $((STEPS / 4)) at 99 856;"
echo " others = cores used by other processes during a run, DISTURBED if still over $LOAD_MAX after $REPEATS repeats)"
if ((DISTURBED_TOTAL > 0)); then
  echo "WARNING: $DISTURBED_TOTAL run(s) stayed disturbed; the figures do not describe a quiet machine" >&2
fi
