"""Crown BSDFs (``radtree bsdf``) and the three-phase annual method built on them.

* :mod:`~radtree.bsdf.klems` — read a Klems XML back; reciprocity and energy checks;
* :mod:`~radtree.bsdf.run` — leaf-on and leaf-off BSDFs of a scenario's crown layer
  (:func:`compute_crown_bsdfs`), their summary;
* :mod:`~radtree.bsdf.threephase` — ``radtree annual --method 3phase``.

The planar samples are :mod:`radtree.trees.slab`; the Radiance runs
:mod:`radtree.engines.radiance.bsdf`; the cached leaf-on XML and the BSDF crown
:mod:`radtree.pipeline.crown_bsdf`. The command is :mod:`radtree.cli.bsdf`.
"""
