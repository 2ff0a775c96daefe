"""Crown BSDFs (``radtree bsdf``).

* :mod:`~radtree.bsdf.klems` — read a Klems XML back; reciprocity and energy checks;
* :mod:`~radtree.bsdf.run` — leaf-on and leaf-off BSDFs of a scenario's crown layer
  (:func:`~radtree.bsdf.run.compute_crown_bsdfs`), their summary.

The planar samples are :mod:`radtree.trees.slab`; the Radiance runs
:mod:`radtree.engines.radiance.bsdf`; the cached leaf-on XML and the BSDF crown
(``[tree] representation = "bsdf"``) :mod:`radtree.pipeline.crown_bsdf` and
:mod:`radtree.trees.bsdf_shell`. The command is :mod:`radtree.cli.bsdf`.
"""
