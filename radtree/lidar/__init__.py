"""Point clouds: trees from laser scanning tiles and leaf area from a tree's points.

* :mod:`~radtree.lidar.tile` reads LAS/LAZ (laspy, lazrs) and checks it;
* :mod:`~radtree.lidar.ground` heights above ground (classification 2, a stated simple filter,
  or already normalised);
* :mod:`~radtree.lidar.segment` canopy height model, tree tops, crowns (watershed);
* :mod:`~radtree.lidar.geojson` the inventory GeoJSON ``radtree new --trees`` reads;
* :mod:`~radtree.lidar.clip` one tree's points to a file;
* :mod:`~radtree.lidar.evaluate` detected trees against reference trees.

Units: metres, x east, y north, z up.
"""
