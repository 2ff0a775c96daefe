"""Point clouds: trees from laser scanning tiles and leaf area from a tree's points.

* :mod:`~radtree.lidar.tile` reads LAS/LAZ (laspy, lazrs) and checks it;
* :mod:`~radtree.lidar.ground` heights above ground (classification 2, a stated simple filter,
  or already normalised);
* :mod:`~radtree.lidar.segment` canopy height model, tree tops, crowns (watershed);
* :mod:`~radtree.lidar.geojson` the inventory GeoJSON ``radtree new --trees`` reads;
* :mod:`~radtree.lidar.clip` one tree's points to a file (and points to LAS/LAZ);
* :mod:`~radtree.lidar.evaluate` detected trees against reference trees;
* :mod:`~radtree.lidar.voxels` plant area density of one tree on voxels (Beer–Lambert), which
  :mod:`radtree.trees.points_crown` fills with slats (``[tree] points``);
* :mod:`~radtree.lidar.beams` the same inversion along each beam's own path (tilted airborne
  beams, terrestrial scans);
* :mod:`~radtree.lidar.scanner` a synthetic airborne scanner (ray casting) and
  :mod:`~radtree.lidar.tls` a synthetic terrestrial one, for round trips
  (:mod:`radtree.trees.synthetic_scan` scans radtree's own crowns).

Units: metres, x east, y north, z up.
"""
