#!/bin/sh
# An airborne laser scanning tile to a daylight study: trees from the tile, footprints beside.
# Runs in a copy of this folder alone (radtree on PATH). Writes trees.geojson and study/.
set -e
cd "$(dirname "$0")"
radtree lidar segment data/street_tile.laz --species morus_alba --out trees.geojson
radtree new study --trees trees.geojson --buildings data/buildings.geojson
radtree build study
radtree simulate study
radtree report study
echo "report: $(pwd)/study/report/index.html"
