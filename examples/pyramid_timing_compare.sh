#!/bin/bash
# CPU time of one pyramid forward and back (symmetric unless BOUNDARY says, two threads) for
# every scheme, for each `pyramid_timing` build given, side by side in one run:
#   cargo build --release --example pyramid_timing
#   examples/pyramid_timing_compare.sh OLD/target/release/examples/pyramid_timing target/release/examples/pyramid_timing
# Each figure is (user + sys of REPS pyramids − that of 1) / (REPS − 1) in ms, the best of two
# interleaved rounds: CPU time rather than wall time, which on a shared machine moves
# with the other jobs more than with the engine. Prints `build scheme ms`.
# By default a 2048² image, 5 levels, REPS=31; `N=64 DIMS=3 REPS=401 BOUNDARY=interpolating`
# times a 64³ volume (3 levels) with open ends instead.
set -euo pipefail
schemes="chaikin cubic haar linear linear-wide chaikin-wide cubic-wide cdf97"
n=${N:-2048}
dims=${DIMS:-2}
reps=${REPS:-31}
boundary=${BOUNDARY:-symmetric}
cpu() { { /usr/bin/time -f "%U %S" "$@" >/dev/null; } 2>&1 | awk '{print $1 + $2}'; }
for round in 1 2; do
  for s in $schemes; do
    for b in "$@"; do
      many=$(cpu "$b" "$n" "$s" "$boundary" "$reps" "$dims")
      one=$(cpu "$b" "$n" "$s" "$boundary" 1 "$dims")
      echo "$b $s $(echo "($many - $one) * 1000 / ($reps - 1)" | bc -l)"
    done
  done
done | awk '{k=$1" "$2; if(!(k in m)||$3<m[k])m[k]=$3} END{for(k in m)printf "%s %.2f\n", k, m[k]}' | sort
