#!/usr/bin/env bash
# The side-by-side table of issue 16: the same charts run by MatIEC (iec2c, then gcc -O1) and by
# sfc (the engine, `sfc sim`, `sfc run`), and `sfc check` against `iec2c` on a 10,000-step ring.
#
#   MATIEC=path/to/matiec scripts/bench-matiec.sh
#
# MATIEC is a checkout of MatIEC's source (https://github.com/beremiz/matiec), built here once
# into target/matiec-build (autoreconf, configure, make: needs autoconf, automake, bison, flex,
# g++), or a directory where it is already built (it has `iec2c` and `lib/`). Without MATIEC the
# script says so and exits 0. SFC=path uses that `sfc` binary instead of building
# target/release/sfc; SCANS=N sets the scans of each timed run (default 20000).
# It takes several minutes: gcc needs most of them for the generated C of the 1,000 loops.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${MATIEC:-}" ]; then
  echo "bench-matiec: MATIEC is not set (MATIEC=path to MatIEC's source or build); nothing measured, skipped"
  exit 0
fi
if [ ! -d "$MATIEC" ]; then
  echo "bench-matiec: MATIEC=$MATIEC is not a directory" >&2
  exit 2
fi
for tool in gcc /usr/bin/time; do
  command -v "$tool" >/dev/null || { echo "bench-matiec: $tool is needed" >&2; exit 2; }
done
scans=${SCANS:-20000}

# MatIEC: built where it is, or built here once.
if [ -x "$MATIEC/iec2c" ] && [ -d "$MATIEC/lib" ]; then
  matiec=$(cd "$MATIEC" && pwd)
else
  matiec="$root/target/matiec-build"
  if [ ! -x "$matiec/iec2c" ]; then
    echo "bench-matiec: building MatIEC from $MATIEC into $matiec (once)" >&2
    rm -rf "$matiec"
    cp -r "$MATIEC" "$matiec"
    (cd "$matiec" && autoreconf -i && ./configure && make -j2) >"$root/target/matiec-build.log" 2>&1 || {
      echo "bench-matiec: building MatIEC failed; see target/matiec-build.log" >&2
      exit 2
    }
  fi
fi

sfc=${SFC:-$root/target/release/sfc}
if [ -z "${SFC:-}" ]; then
  echo "bench-matiec: building sfc (cargo build --release -p sfc-cli)" >&2
  (cd "$root" && cargo build --release -p sfc-cli --quiet)
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Charts in the shape both tools read: steps first, then transitions (MatIEC wants a step
# declared before a transition names it).
ring() { # ring N NAME [action]: a ring of N steps, one token moving every scan
  local n=$1 name=$2 action=${3:-}
  {
    printf 'PROGRAM %s\n  VAR\n    Go : BOOL := TRUE;\n    Count : DINT;\n  END_VAR\n' "$name"
    printf '  INITIAL_STEP S0:%s END_STEP\n' "${action:+ Tick(N);}"
    for ((i = 1; i < n; i++)); do printf '  STEP S%d: END_STEP\n' "$i"; done
    for ((i = 0; i < n; i++)); do printf '  TRANSITION FROM S%d TO S%d := Go; END_TRANSITION\n' "$i" $(((i + 1) % n)); done
    [ -n "$action" ] && printf '  ACTION Tick:\n    Count := Count + 1;\n  END_ACTION\n'
    printf 'END_PROGRAM\n'
  }
}
loops() { # loops K NAME: K two-step loops, every token moving every scan
  local k=$1 name=$2
  {
    printf 'PROGRAM %s\n  VAR\n    Go : BOOL := TRUE;\n  END_VAR\n' "$name"
    for ((i = 0; i < k; i++)); do
      printf '  INITIAL_STEP A%d: END_STEP\n  STEP B%d: END_STEP\n' "$i" "$i"
      printf '  TRANSITION FROM A%d TO B%d := Go; END_TRANSITION\n' "$i" "$i"
      printf '  TRANSITION FROM B%d TO A%d := Go; END_TRANSITION\n' "$i" "$i"
    done
    printf 'END_PROGRAM\n'
  }
}
configuration() { # configuration PROGRAM
  printf '\nCONFIGURATION Config0\n  RESOURCE Res0 ON PLC\n    TASK Main(INTERVAL := T#10ms, PRIORITY := 0);\n    PROGRAM Inst0 WITH Main : %s;\n  END_RESOURCE\nEND_CONFIGURATION\n' "$1"
}

ring 1000 Ring >"$work/ring.st"
loops 1000 Loops >"$work/loops.st"
{ ring 10000 Big action; configuration Big; } >"$work/big.st"

# MatIEC: iec2c, then a driver that calls the program's body once per scan (T#10ms apart) and
# prints ns per scan.
matiec_per_scan() { # matiec_per_scan CHART POU
  local chart=$1 pou=$2 out="$work/c-$2"
  mkdir -p "$out"
  timeout 120 "$matiec/iec2c" -I "$matiec/lib" -T "$out" "$chart" >"$out/iec2c.log" 2>&1 || {
    echo "nan"; echo "bench-matiec: iec2c refused $chart: $(grep -m1 error "$out/iec2c.log")" >&2; return
  }
  cat >"$out/driver.c" <<EOF
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "iec_std_lib.h"
#define __LOCATED_VAR(type, name, ...) type __loc_##name; type* name = &__loc_##name;
#include "LOCATED_VARIABLES.h"
#undef __LOCATED_VAR
TIME __CURRENT_TIME;
BOOL __DEBUG = 0;
#include "POUS.h"
#include "POUS.c"
static ${pou^^} data;
static double now_ns(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec * 1e9 + t.tv_nsec; }
int main(int argc, char **argv) {
  long n = atol(argv[1]), k = 0;
  __CURRENT_TIME = (TIME){0, 0};
  ${pou^^}_init__(&data, 0);
  double best = 1e300;
  for (int round = 0; round < 5; round++) {
    double t0 = now_ns();
    for (long i = 0; i < n; i++, k++) {
      __CURRENT_TIME = (TIME){k / 100, (k % 100) * 10000000};
      ${pou^^}_body__(&data);
    }
    double per = (now_ns() - t0) / n;
    if (per < best) best = per;
  }
  printf("%.1f\n", best);
  return 0;
}
EOF
  gcc -w -O1 -I "$out" -I "$matiec/lib/C" "$out/driver.c" -o "$out/driver" -lm
  "$out/driver" "$scans"
}

# Wall time of a command in seconds (µs resolution).
wall() {
  local t0=$EPOCHREALTIME
  "$@" >/dev/null 2>&1
  awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.6f", b - a }'
}

# sfc sim: (wall(2N) − wall(N)) / N, the best of 3 (the start-up cancels out).
sim_per_scan() { # sim_per_scan CHART N
  local best="" n=$2
  for _ in 1 2 3; do
    local t1 t2
    t1=$(wall "$sfc" sim "$1" --scans "$n")
    t2=$(wall "$sfc" sim "$1" --scans $((2 * n)))
    local per
    per=$(awk -v a="$t1" -v b="$t2" -v n="$n" 'BEGIN { printf "%.1f", (b - a) * 1e9 / n }')
    if [ -z "$best" ] || awk -v p="$per" -v b="$best" 'BEGIN { exit !(p < b) }'; then best=$per; fi
  done
  echo "$best"
}

# sfc run: the scan time p50 it reports, ns.
run_p50() { # run_p50 CHART
  "$sfc" run "$1" --period T#1ms --no-retain --scans 5000 2>&1 >/dev/null |
    sed -n 's/.*scan time p50 \([0-9.]*\) µs.*/\1/p' | awk '{ printf "%.0f", $1 * 1000 }'
}

# The engine: sfc-sim's scan benchmark (release).
engine=$(cd "$root" && cargo bench -q -p sfc-sim --bench scan -- ring-plain loops 2>/dev/null || true)
engine_ring=$(sed -n 's/^ring of *100 steps, one token, without actions: *\([0-9.]*\) ns.*/\1/p' <<<"$engine")
engine_loops=$(sed -n 's/^1000 parallel loops, all active, every token moving: *\([0-9.]*\) ns.*/\1/p' <<<"$engine")

echo "bench-matiec: $(uname -m), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
echo "ns per scan (the sfc engine figure for the ring is its 100-step ring: the cost does not depend on the ring's size)"
printf '| %-40s | %14s | %10s | %12s | %12s |\n' chart "MatIEC C (-O1)" "sfc sim" "sfc run p50" "engine"
printf '|%s|%s|%s|%s|%s|\n' "$(printf -- '-%.0s' {1..42})" "$(printf -- '-%.0s' {1..16})" "$(printf -- '-%.0s' {1..12})" "$(printf -- '-%.0s' {1..14})" "$(printf -- '-%.0s' {1..14})"
printf '| %-40s | %14s | %10s | %12s | %12s |\n' "ring of 1,000 steps, one token moving" \
  "$(matiec_per_scan "$work/ring.st" Ring)" "$(sim_per_scan "$work/ring.st" $((50 * scans)))" "$(run_p50 "$work/ring.st")" "${engine_ring:-?}"
printf '| %-40s | %14s | %10s | %12s | %12s |\n' "1,000 two-step loops, all moving" \
  "$(matiec_per_scan "$work/loops.st" Loops)" "$(sim_per_scan "$work/loops.st" "$scans")" "$(run_p50 "$work/loops.st")" "${engine_loops:-?}"

# sfc check against iec2c on the 10,000-step ring: wall time and peak memory, best of 3.
best_of_3() { # best_of_3 CMD…: "seconds, MB" (the fastest of 3 runs, the peak memory of the largest)
  local best="" mem=0
  for _ in 1 2 3; do
    local t
    t=$(wall "$@")
    if [ -z "$best" ] || awk -v a="$t" -v b="$best" 'BEGIN { exit !(a < b) }'; then best=$t; fi
  done
  /usr/bin/time -o "$work/time" -f '%M' "$@" >/dev/null 2>&1 || true
  mem=$(tail -1 "$work/time")
  awk -v s="$best" -v k="$mem" 'BEGIN { printf "%.3f s, %.0f MB", s, k / 1024 }'
}
mkdir -p "$work/c-big"
echo
echo "10,000-step ring ($(wc -l <"$work/big.st") lines, one N action, a CONFIGURATION):"
echo "  iec2c:     $(best_of_3 "$matiec/iec2c" -I "$matiec/lib" -T "$work/c-big" "$work/big.st")"
echo "  sfc check: $(best_of_3 "$sfc" check "$work/big.st")"
