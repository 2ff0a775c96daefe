"""Crown models (homogeneous, perforated, louvers) in two forms (sensor dome, free-standing).

Entry point: :func:`radtree.trees.build.build_tree`.
"""
