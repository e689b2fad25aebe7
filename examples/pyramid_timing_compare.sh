#!/bin/bash
# CPU time of one 2048² pyramid forward and back (5 levels, symmetric, two threads) for
# every scheme, for each `pyramid_timing` build given, side by side in one run:
#   cargo build --release --example pyramid_timing
#   examples/pyramid_timing_compare.sh OLD/target/release/examples/pyramid_timing target/release/examples/pyramid_timing
# Each figure is (user + sys of 31 pyramids − that of 1) / 30 in ms, the best of two
# interleaved rounds: CPU time rather than wall time, which on a shared machine moves
# with the other jobs more than with the engine. Prints `build scheme ms`.
set -euo pipefail
schemes="chaikin cubic haar linear linear-wide chaikin-wide cubic-wide cdf97"
cpu() { { /usr/bin/time -f "%U %S" "$@" >/dev/null; } 2>&1 | awk '{print $1 + $2}'; }
for round in 1 2; do
  for s in $schemes; do
    for b in "$@"; do
      many=$(cpu "$b" 2048 "$s" symmetric 31)
      one=$(cpu "$b" 2048 "$s" symmetric 1)
      echo "$b $s $(echo "($many - $one) * 1000 / 30" | bc -l)"
    done
  done
done | awk '{k=$1" "$2; if(!(k in m)||$3<m[k])m[k]=$3} END{for(k in m)printf "%s %.1f\n", k, m[k]}' | sort
