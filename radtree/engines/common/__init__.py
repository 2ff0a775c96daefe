"""What the in-process engines (NumPy backward, forward) share: the scene's triangles and
optics per hour (:mod:`.geometry`), the ray casters (:mod:`.raycast`, Embree or a NumPy BVH,
with the optional compiled kernel :mod:`.kernel`), direction sampling (:mod:`.sampling`) and
the engine-interface base class (:mod:`.inprocess`). No engine's private module is imported by
another engine: what two engines need lives here."""
