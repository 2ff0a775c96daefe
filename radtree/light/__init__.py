"""The light of an hour or a year: sun, sky, weather and the ground-reflected term.

One concept per module (layer 3: imports only ``errors``, ``fileio``, ``config``, ``scene``,
``site`` and its own modules — never an engine; the Radiance text of skies lives in
:mod:`radtree.engines.radiance.sky`):

* :mod:`~radtree.light.units` — ``WHITE_EFFICACY`` (179 lm/W) and the photopic RGB weights;
* :mod:`~radtree.light.sun` — sun position (NREL SPA), the sun's disc and solid angle, clock times;
* :mod:`~radtree.light.sky` — :class:`~radtree.light.sky.SkyState` (the light of one hour) and
  the analytic test skies;
* :mod:`~radtree.light.perez` — the Perez all-weather sky as ``gendaylit`` computes it, and
  the Perez (1990) luminous-efficacy models (one table);
* :mod:`~radtree.light.weather` — EPW files (one reader, ``pvlib.iotools.read_epw``) and the
  EPW a project uses;
* :mod:`~radtree.light.clearsky` — the generated clear-sky year (a labelled GENERATED EPW);
* :mod:`~radtree.light.tables` — the small CSV inputs (direct normal illuminance per hour,
  ground reflectance per sun altitude);
* :mod:`~radtree.light.ground` — the street's reflectance and the calculated ground-reflected
  term;
* :mod:`~radtree.light.hours` — :func:`~radtree.light.hours.hour_states`, the project's hours.
"""
