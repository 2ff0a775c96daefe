#!/bin/sh
# An airborne laser scanning tile to a daylight study: trees from the tile, footprints beside;
# then one tree's crown built from its own points. Runs in a copy of this folder alone
# (radtree on PATH). Writes trees.geojson, study/, tree.laz and one-tree/.
set -e
cd "$(dirname "$0")"
radtree lidar segment data/street_tile.laz --species morus_alba --out trees.geojson
radtree new study --trees trees.geojson --buildings data/buildings.geojson
radtree build study
radtree simulate study
radtree report study
echo "report: $(pwd)/study/report/index.html"
# one crown from its points: its leaf-area profile and the crown beside its points in the report
radtree lidar clip data/street_tile.laz --tree L001 --out tree.laz
radtree new one-tree --lat -32.8936 --lon -68.8459 --tz America/Argentina/Mendoza
cp tree.laz one-tree/data/
sed -i 's|^# points = (unset).*|points = "data/tree.laz"|; s|^species = .*|species = "morus_alba"|' one-tree/radtree.toml
radtree build one-tree -s trees
radtree simulate one-tree -s trees --engine numpy --hour 13:00
radtree report one-tree
echo "report: $(pwd)/one-tree/report/index.html"
