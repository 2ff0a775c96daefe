"""From a project to scenes, build folders and the one results table.

``assemble``: a scenario's scene and its one ``-ab`` rule; ``realisations``: random crowns
traced as ``<name>@k`` and averaged back; ``build``: the inspectable Radiance build folders;
``simulate``: every scenario × hour on one engine, resumable (plan → execute → publish, with
``options`` — :class:`RunOptions` —, ``jobs``, ``executor`` — a thread pool or Dask behind one
interface — and ``publish``); ``trace``: the same rows in memory
(calibration, diagnosis, convergence); ``results``: the results table's schema, read and write;
``crown_bsdf``: a scenario's crown BSDF (computed once, cached) and the BSDF crown.
"""
