#!/usr/bin/env bash
# Ours vs GeoTaichi 0.2.6 (CPU backend) on the same Drucker–Prager uGIMP granular column
# collapse, 1 and 2 threads, alternating runs; prints point-steps per second (wall and per CPU
# second) and the ratio of medians ours/GeoTaichi. Not run in CI. Installs Debian's libgeos-dev
# (needs root/sudo and network to Debian) and GeoTaichi from PyPI into a virtual environment.
#
#   benchmarks/peers/geotaichi/run.sh [STEPS=200] [ROUNDS=3]
#
# The columns are those of `cargo run --release -p thm-benchmarks --example mpm_rate -- STEPS`:
# 40 000 points for STEPS steps and 99 856 points for STEPS/4 steps.
# GEOTAICHI_VENV (default target/peers/geotaichi-venv) and PYTHON (default python3) override.
set -euo pipefail
SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
STEPS=${1:-200}; ROUNDS=${2:-3}
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../../.." && pwd)
venv=${GEOTAICHI_VENV:-$root/target/peers/geotaichi-venv}
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

if ! "$venv/bin/python" -c 'import src.mpm.mainMPM' >/dev/null 2>&1; then
  # Shapely 1.8.0 (pinned by GeoTaichi) builds from source against GEOS.
  dpkg -s libgeos-dev >/dev/null 2>&1 || { $SUDO apt-get update && $SUDO apt-get install -y libgeos-dev; }
  "${PYTHON:-python3}" -m venv "$venv"
  # 0.2.6 declares Requires-Python <= 3.11, which excludes 3.11.x patch releases and newer.
  "$venv/bin/pip" install --ignore-requires-python geotaichi==0.2.6 >&2
fi
(cd "$root" && cargo build --release -p thm-benchmarks --example mpm_rate)
ours="$root/target/release/examples/mpm_rate"

# GeoTaichi's point counts, steps and the matching lines of mpm_rate.
cases="40000:100:$STEPS 99856:158:$((STEPS / 4))"
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
for r in $(seq "$ROUNDS"); do
  # One run of ours gives every (size, threads) figure; then GeoTaichi on each.
  "$ours" "$STEPS" > "$work/ours.txt"
  for c in $cases; do
    IFS=: read -r n side steps <<< "$c"
    for t in 1 2; do
      # "drucker_prager    40000 pts 1t:   3.10 M pt-steps/s wall,   3.20 M pt-steps per CPU-s"
      awk -v n="$n" -v t="${t}t:" '$1 == "drucker_prager" && $2 == n && $4 == t \
        {print $5 * 1e6, $9 * 1e6}' "$work/ours.txt" >> "$work/ours-$n-$t"
      (cd "$work" && "$venv/bin/python" "$here/geotaichi_column.py" "$side" "$t" "$steps" 2>/dev/null) \
        | awk '$1 == "RESULT" {print $4, $5}' >> "$work/geo-$n-$t"
    done
  done
  echo "round $r of $ROUNDS done" >&2
done

printf '%-8s %-3s %-28s %-28s %-14s\n' points thr 'ours wall | per CPU-s' 'GeoTaichi wall | per CPU-s' 'ratio wall|CPU'
for c in $cases; do
  IFS=: read -r n side steps <<< "$c"
  for t in 1 2; do
    ow=$(cut -d' ' -f1 "$work/ours-$n-$t" | median); oc=$(cut -d' ' -f2 "$work/ours-$n-$t" | median)
    gw=$(cut -d' ' -f1 "$work/geo-$n-$t" | median); gc=$(cut -d' ' -f2 "$work/geo-$n-$t" | median)
    printf '%-8s %-3s %8.3g | %-17.3g %8.3g | %-17.3g %5.2f | %.2f\n' "$n" "$t" \
      "$ow" "$oc" "$gw" "$gc" "$(echo "$ow / $gw" | bc -l)" "$(echo "$oc / $gc" | bc -l)"
  done
done
echo "(point-steps per second; medians of $ROUNDS alternating runs; $STEPS steps at 40 000 points, $((STEPS / 4)) at 99 856)"
