#!/bin/sh
# Regenerate the mesh figures of docs/mesh.md from the corpus (../shared/corpus/meshes, or
# $MRA_CORPUS/meshes).
# Usage: sh docs/figures/make_mesh_figures.sh   (from the repository root, after cargo build --release)
set -e
MRA=./target/release/mra
C=${MRA_CORPUS:-../shared/corpus}/meshes
T=$(mktemp -d)
OUT=docs/figures
R="--size 400x300"
$MRA mesh render $C/spot_control_mesh.obj -o $OUT/mesh_spot_control.png $R --view 60,20 --wireframe
$MRA mesh subdivide $C/spot_control_mesh.obj -o $T/cc.obj --scheme catmull-clark --steps 3
$MRA mesh render $T/cc.obj -o $OUT/mesh_spot_catmull_clark3.png $R --view 60,20
$MRA mesh subdivide $C/spot_control_mesh.obj -o $T/ds.obj --scheme doo-sabin --steps 3
$MRA mesh render $T/ds.obj -o $OUT/mesh_spot_doo_sabin3.png $R --view 60,20
$MRA mesh subdivide $C/spot_control_mesh.obj -o $T/ad.obj --scheme catmull-clark --steps 3 --box=-1,0,-1,1,1,1
$MRA mesh render $T/ad.obj -o $OUT/mesh_spot_adaptive_cc3.png $R --view 60,20 --wireframe
$MRA mesh simplify $C/bunny.ply -o $T/b.ply --faces 600
$MRA mesh render $T/b.ply -o $OUT/mesh_bunny_simplified600.png $R --view 0,10 --wireframe
$MRA mesh subdivide $T/b.ply -o $T/bl.ply --scheme loop --steps 2
$MRA mesh render $T/bl.ply -o $OUT/mesh_bunny600_loop2.png $R --view 0,10
$MRA mesh subdivide $T/b.ply -o $T/bb.ply --scheme butterfly --steps 2
$MRA mesh render $T/bb.ply -o $OUT/mesh_bunny600_butterfly2.png $R --view 0,10
$MRA mesh subdivide $C/hand_lowres.obj -o $T/h.obj --scheme loop --steps 2
$MRA mesh render $T/h.obj -o $OUT/mesh_hand_loop2_boundary.png $R --view 20,10
# a box with sharp edges (dihedral angle > 60°) and one without tags
printf 'v 0 0 0\nv 2 0 0\nv 0 1 0\nv 2 1 0\nv 0 0 1\nv 2 0 1\nv 0 1 1\nv 2 1 1\nf 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n' > $T/box.obj
$MRA mesh subdivide $T/box.obj -o $T/box_s.obj --scheme catmull-clark --steps 3 --crease-angle 60
$MRA mesh render $T/box_s.obj -o $OUT/mesh_box_cc3_creases.png $R --view 35,25 --wireframe
$MRA mesh subdivide $T/box.obj -o $T/box_r.obj --scheme catmull-clark --steps 3
$MRA mesh render $T/box_r.obj -o $OUT/mesh_box_cc3_smooth.png $R --view 35,25 --wireframe
rm -rf $T
ls -la $OUT/mesh_*.png
