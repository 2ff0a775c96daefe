"""Crown models (homogeneous, perforated, louvers) in two forms (sensor dome, free-standing),
registered by name in :mod:`radtree.trees.registry`.

Entry point: :func:`radtree.trees.build.build_tree` (``build_tree(project, scenario, frame)``
→ :class:`TreeModel`). Also: :func:`radtree.trees.build.build_crown` (a model/form without a
scenario), :func:`radtree.calibrate.direct.calibrate` (the ``radtree calibrate`` command lives in
:mod:`radtree.cli.calibrate`), :func:`radtree.trees.picture.render_model_png`, and
:class:`radtree.trees.raycast.DirectTracer` (straight-ray direct transmission).
"""

from radtree.trees.build import TreeModel, apply_switches, build_crown, build_tree

__all__ = ["TreeModel", "apply_switches", "build_crown", "build_tree"]
