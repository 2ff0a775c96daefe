"""radtree — daylight through urban street trees onto façades and into rooms.

Conventions used everywhere in the package:

* coordinates in metres, x east, y north, z up;
* azimuths in degrees clockwise from north (compass), altitudes in degrees above the horizon;
* illuminance in lux, luminance in cd/m²;
* local clock times as ``HH:MM`` strings.
"""

__version__ = "0.1.0"
