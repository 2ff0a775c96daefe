"""Calibrating crowns on the measured canopy permeability (never on the hourly façade data).

``direct``: the crown's direct (straight-ray) permeability at the façade sensors → louvers cover /
perforated openness (``radtree calibrate``); ``permeability``: the global permeability as the
study measured it (every light path, traced like ``simulate``) → louvers layers or volume
crossings (``radtree calibrate --global``); ``scan``: scenario A's fit against the crown's
permeability (``radtree permeability``).
"""
