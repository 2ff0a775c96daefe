"""Photometric units shared by every part of radtree (the one home of Radiance's 179 lm/W).

Radiance's "visible" radiance is in W/(sr·m²) of an equal-energy white; luminance (cd/m²) and
illuminance (lux) are that radiance/irradiance times the white luminous efficacy
:data:`WHITE_EFFICACY` (Radiance's ``WHTEFFICACY``). An RGB triple is reduced to one photopic
value with the weights :data:`PHOTOPIC_RGB` (Radiance's ``bright()``: 0.265 R + 0.670 G +
0.065 B), so lux = 179 · (0.265 R + 0.670 G + 0.065 B).
"""

from __future__ import annotations

WHITE_EFFICACY = 179.0  # lm/W, Radiance's white-light luminous efficacy (WHTEFFICACY)
PHOTOPIC_RGB = (0.265, 0.670, 0.065)  # photopic weights of Radiance R, G, B (sum 1)
