"""The light of each hour of a project: sun position, DNI/DHI, ground reflectance → SkyState.

Inputs (``[light] weather``, :func:`radtree.light.weather.hour_weather`): the clear sky of the
site at the hour (:mod:`radtree.light.clearsky`), an EPW file checked against ``[site]``, or a DNI
table (``time,direct_normal_lux`` in lux, :mod:`radtree.light.tables`); the ground
reflectance is a constant or a table ``angle_deg,reflectance`` against the sun altitude
(interpolated, clamped at the ends, :func:`radtree.light.ground.ground_reflectance_at`).
"""

from __future__ import annotations

from dataclasses import replace

from radtree.config import Project, Scenario, effective_project
from radtree.errors import ConfigError
from radtree.light.ground import ground_reflectance_at
from radtree.light.sky import SkyState
from radtree.light.sun import local_datetime, sun_position
from radtree.light.weather import hour_weather


def hour_states(project: Project, scenario: Scenario | None = None,
                hours: list[str] | None = None) -> list[SkyState]:
    """One SkyState per project hour (or the given subset), as the scenario lights it.

    The sky is the scenario's ``sky`` (else the project's ``light.sky``); with ``reflection =
    calculated`` the traced ground is black and there is no ground glow (the reflected part is
    added analytically afterwards, see :mod:`radtree.light.ground`).
    """
    if scenario is not None:
        project = effective_project(project, scenario)
    site = project.site
    wanted = list(hours) if hours is not None else list(site.hours)
    unknown = [h for h in wanted if h not in site.hours]
    if unknown:
        raise ConfigError(f"unknown hour(s) {', '.join(unknown)}; the project has "
                          f"{', '.join(site.hours)}", source=str(project.source), field="site.hours")
    weather = hour_weather(project, wanted)
    sky = (scenario.sky if scenario is not None and scenario.sky else project.light.sky)
    calculated = scenario is not None and scenario.reflection == "calculated"
    states = []
    for h in wanted:
        w = weather[h]
        when = local_datetime(site.date, h, site.tzinfo)
        sun = sun_position(when, site.latitude, site.longitude, site.elevation_m)
        if not sun.above_horizon:
            raise ConfigError(f"at {h} on {site.date} the sun is below the horizon "
                              f"(altitude {sun.altitude_deg:.2f}°): not a daylight hour",
                              source=str(project.source), field="site.hours")
        rho = ground_reflectance_at(project, sun.altitude_deg)
        st = SkyState(
            time=h, datetime=when, sun=sun, direct_normal_lux=w.direct_normal_lux,
            diffuse_horizontal_lux=((project.light.diffuse_horizontal_lux
                                     if w.diffuse_horizontal_lux is None
                                     else w.diffuse_horizontal_lux) if sky == "perez" else 0.0),
            sky_model=sky, ground_reflectance=rho, ground_glow=True,
        )
        if calculated:
            st = replace(st, ground_reflectance=0.0, ground_glow=False)
        states.append(st)
    return states
