# shellcheck shell=bash
# Shared by the peer scripts in benchmarks/peers/*/run.sh (source it; needs bash, awk and a
# Linux /proc). Each timed run goes through `quiet_run`, which records how much CPU time
# processes other than the timed one (and its descendants) used while it ran, and repeats a run
# in which they used more than LOAD_MAX of a core.
#
# Environment:
#   LOAD_MAX=0.05   other processes' CPU use, in cores, above which a run counts as disturbed
#   REPEATS=3       how many times a disturbed run is repeated before its figure is kept,
#                   marked "disturbed"
#   KEEP_WORK=1     keep the work folder (its path is printed) instead of deleting it

# Set by quiet_run for its caller.
# shellcheck disable=SC2034
QUIET_OTHERS=''
QUIET_FLAG=''
LOAD_MAX=${LOAD_MAX:-0.05}
REPEATS=${REPEATS:-3}
# Number of rounds in the current measurement that stayed disturbed after every repeat.
DISTURBED_TOTAL=0

# make_work: creates the work folder in $work and arranges for its removal at exit unless
# KEEP_WORK=1.
make_work() {
  work=$(mktemp -d)
  if [ "${KEEP_WORK:-0}" = 1 ]; then
    trap 'echo "work folder kept: $work" >&2' EXIT
  else
    trap 'rm -rf "$work"' EXIT
  fi
}

# "busy total" CPU ticks of the whole machine since boot, total divided by the number of CPUs
# (so its difference is the wall time in ticks, over exactly the same window as busy's). Busy:
# user nice system irq softirq steal (guest time is already in user).
cpu_ticks() {
  awk '$1 == "cpu" {b = $2 + $3 + $4 + $7 + $8 + $9; t = b + $5 + $6; found = 1}
    $1 ~ /^cpu[0-9]+$/ {n++}
    END {if (!found || n == 0) exit 1; printf "%d %.2f\n", b, t / n}' /proc/stat
}

# CPU ticks of the waited-for children of process $1 (cutime + cstime of /proc/$1/stat; the
# command name in field 2 may hold spaces, so fields are counted after its closing bracket).
child_ticks() {
  sed 's/.*) //' "/proc/$1/stat" | awk '{print $14 + $15}'
}

# quiet_run LABEL OUT CMD... : runs CMD with stdout in OUT and stderr in OUT.err. Measures the
# CPU that other processes used meanwhile, in cores: machine busy ticks minus those of CMD and
# everything it started and waited for, over the machine's elapsed ticks per CPU (at least one).
# Prints one line per try to stderr, and repeats a disturbed try up to REPEATS times. Sets QUIET_OTHERS (cores used by others in the kept try)
# and QUIET_FLAG ("" or "disturbed"). Fails, showing the command's stderr, if CMD fails.
quiet_run() {
  local label=$1 out=$2
  shift 2
  local me=$BASHPID try b0 b1 w0 w1 c0 c1
  for ((try = 0; try <= REPEATS; try++)); do
    c0=$(child_ticks "$me"); read -r b0 w0 < <(cpu_ticks)
    if ! "$@" > "$out" 2> "$out.err"; then
      echo "$label: command failed: $*" >&2
      cat "$out.err" >&2
      return 1
    fi
    read -r b1 w1 < <(cpu_ticks); c1=$(child_ticks "$me")
    QUIET_OTHERS=$(awk -v b="$((b1 - b0))" -v c="$((c1 - c0))" -v w0="$w0" -v w1="$w1" \
      'BEGIN {w = w1 - w0; o = (b - c) / (w < 1 ? 1 : w); printf "%.3f", (o < 0 ? 0 : o)}')
    if awk -v o="$QUIET_OTHERS" -v m="$LOAD_MAX" 'BEGIN {exit !(o > m)}'; then
      QUIET_FLAG=disturbed
      if ((try < REPEATS)); then
        echo "$label: others used $QUIET_OTHERS cores (> $LOAD_MAX): disturbed, repeating" >&2
        continue
      fi
      echo "$label: others used $QUIET_OTHERS cores: still disturbed after $REPEATS repeats, kept and marked" >&2
      DISTURBED_TOTAL=$((DISTURBED_TOTAL + 1))
    else
      QUIET_FLAG=''
      echo "$label: others used $QUIET_OTHERS cores" >&2
    fi
    return 0
  done
}

# median < FILE: median of the first column, as a plain decimal (bc and awk read it back).
median() {
  sort -g | awk '{a[NR] = $1}
    END {
      if (NR == 0) {print "median: no values" > "/dev/stderr"; exit 1}
      printf "%.6f\n", (NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2)
    }'
}

# ratio A B: A / B as a plain decimal; fails on a zero or empty B.
ratio() {
  awk -v a="$1" -v b="$2" 'BEGIN {
    if (b == "" || b + 0 == 0) {print "ratio: bad denominator \"" b "\"" > "/dev/stderr"; exit 1}
    printf "%.3f\n", a / b
  }'
}

# field OUT KEY: the value after KEY on the line of OUT that starts with it; fails if absent.
field() {
  awk -v k="$2" '$1 == k {print $2; found = 1} END {if (!found) {print "no " k " in " FILENAME > "/dev/stderr"; exit 1}}' "$1"
}

# rate OUT: the particle-steps per second of a timing line "particles steps seconds rate" (the
# last such line of OUT, as dem_peer and yade_cohesive.py print it); fails if there is none.
rate() {
  awk 'NF == 4 && $1 ~ /^[0-9]+$/ && $2 ~ /^[0-9]+$/ {r = $4; found = 1}
    END {if (!found) {print "no timing line in " FILENAME > "/dev/stderr"; exit 1}; print r}' "$1"
}
