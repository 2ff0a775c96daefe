"""Crowns against their photographs: synthetic fisheye renderings of any crown model from the
photo point through the photo's lens (:mod:`.render`) and the ring × segment comparison with
the photo (:mod:`.check`; ``radtree hemi render`` / ``radtree hemi check``)."""
