"""The small projects the verify checks trace, built from shared parts: the reference site
(Mendoza, −32.89° / −68.83°, 750 m, UTC−3, the summer solstice) and one free-standing crown
leafed from October 15 to June 1 (SPEC's reference case). Each check module adds its own
tables (light, crown size, louvers, engine, scenarios) to :func:`mendoza_site`."""

from __future__ import annotations


def mendoza_site(*, date: str, hour: str, name: str | None = None) -> str:
    """The ``[site]`` table of the reference site at one ``hour`` of ``date`` (TOML text)."""
    head = f'[site]\nname = "{name}"\n' if name else "[site]\n"
    return (head + "latitude = -32.89\nlongitude = -68.83\nelevation_m = 750\n"
            f'utc_offset_hours = -3\ndate = "{date}"\nhours = ["{hour}"]\n')


#: a free-standing crown of the reference tree's leaf season (``[tree]``, TOML text)
FREE_TREE = '[tree]\nleaf_on = "10-15"\nleaf_off = "06-01"\nform = "free"\n'

#: a 20 m street facing north, 40 m long (``[street]``, TOML text)
SHORT_STREET = ("[street]\nwidth_m = 20.0\nlength_m = 40.0\nfacade_azimuth_deg = 0.0\n"
                "ground_reflectance = 0.15\n")

#: one round crown of 3 m radius, its base 2.5 m up, its trunk 3.5 m from the façade
#: (``[tree.crown]``, TOML text)
SMALL_CROWN = ("[tree.crown]\ncount = 1\nradius_m = 3.0\nvertical_radius_m = 3.0\n"
               "base_height_m = 2.5\ntrunk_distance_m = 3.5\n")
