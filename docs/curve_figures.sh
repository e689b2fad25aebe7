#!/bin/sh
# Regenerate the curve and surface figures of docs/curve.md with the project's own commands.
# Run from the repository root after `cargo build --release`.
set -e
M=${MRA:-target/release/mra}
F=docs/figures
T=${TMPDIR:-/tmp}
C=corpus/curves
$M curve plot --order 4 $C/wave.csv -o $F/curve_bspline.png --size 480x320
$M curve plot --order 4 $C/wave.csv -o $F/curve_bspline.svg --size 480x320
$M curve plot --kind nurbs --order 3 --knots $C/circle_knots.txt $C/circle.csv -o $F/curve_nurbs_circle.png --size 320x320
$M curve insert-knot --order 3 --midpoints --knots-out $T/mra_fine_knots.txt $C/wave.csv -o $T/mra_fine.csv
$M curve plot --order 3 --knots $T/mra_fine_knots.txt $T/mra_fine.csv -o $F/curve_midpoint_insertion.png --size 480x320
$M surface patch --kind bezier --resolution 40,40 $C/patch44.csv -o $T/mra_patch.obj
$M surface primitive --shape torus --radius 2 --minor 0.6 -o $T/mra_torus.obj
$M surface coons --kind bezier --p0 $C/coons_p0.csv --p1 $C/coons_p1.csv --q0 $C/coons_q0.csv --q1 $C/coons_q1.csv -o $T/mra_coons.obj
$M surface revolve --order 3 --exact --resolution 64,48 $C/profile.csv -o $T/mra_vase.obj
$M surface sweep --order 3 --resolution 200,24 --profile $C/section.csv --path $C/helix.csv -o $T/mra_sweep.obj
$M surface rotational-blend --order 4 --left $C/left.csv --right $C/right.csv -o $T/mra_pear.obj
$M surface cross-blend --order 4 --mirror --left $C/left.csv --right $C/right.csv --section $C/section_leaf.csv -o $T/mra_leaf.obj
for s in patch torus coons vase sweep pear leaf; do
  $M surface render $T/mra_$s.obj -o $F/surface_$s.png --size 320x240
done
