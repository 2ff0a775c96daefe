import numpy as np
import pytest

from radtree.engines.radiance.binaries import run
from radtree.engines.radiance.sky import gendaylit_command
from radtree.light.sky import SkyState
from radtree.light.sun import (
    angular_separation_deg,
    compass_to_radiance_azimuth,
    direction_vector,
    local_datetime,
    sun_position,
)

from .conftest import needs_radiance

# NREL SPA, Mendoza, 22 December, 750 m (SPEC.md): time → (altitude, compass azimuth)
SPA = {"10:30": (48.67, 88.96), "11:30": (61.18, 78.88), "12:30": (73.02, 60.26),
       "13:30": (80.50, 5.85), "14:30": (74.52, 304.09), "15:30": (62.90, 282.95),
       "16:30": (50.43, 272.24)}


def mendoza_sun(t):
    return sun_position(local_datetime("2024-12-22", t, -3), -32.89, -68.83, 750)


@pytest.mark.parametrize("t", list(SPA))
def test_sun_matches_nrel_spa(t):
    sun = mendoza_sun(t)
    ref = direction_vector(*SPA[t])
    assert angular_separation_deg(sun.vector, ref) < 0.05


@pytest.mark.parametrize("when,lat,lon,elev", [
    ("2024-12-22T10:30:00-03:00", -32.89, -68.83, 750.0),
    ("2023-06-21T06:15:00+02:00", 52.52, 13.40, 34.0),
    ("2025-03-20T17:45:30-05:00", 40.71, -74.01, 10.0),
    ("2024-09-01T12:00:00+10:00", -33.87, 151.21, 0.0)])
def test_sun_is_pvlibs_spa_python_to_the_bit(when, lat, lon, elev):
    """The SPA module loaded on its own, with spa_python's defaults, gives exactly what
    ``pvlib.solarposition.spa_python`` gives (apparent elevation and azimuth)."""
    from datetime import datetime

    import pandas as pd
    from pvlib.solarposition import spa_python

    t = datetime.fromisoformat(when)
    ref = spa_python(pd.DatetimeIndex([pd.Timestamp(t)]), lat, lon, altitude=elev)
    sun = sun_position(t, lat, lon, elev)
    assert sun.altitude_deg == float(ref["apparent_elevation"].iloc[0])
    assert sun.azimuth_deg == float(ref["azimuth"].iloc[0])


def test_radiance_azimuth_convention():
    assert compass_to_radiance_azimuth(180.0) == 0.0     # south
    assert compass_to_radiance_azimuth(270.0) == 90.0    # west
    assert compass_to_radiance_azimuth(90.0) == -90.0    # east
    assert compass_to_radiance_azimuth(0.0) == -180.0    # north


def test_sun_vector_axes():
    np.testing.assert_allclose(direction_vector(0, 90), [1, 0, 0], atol=1e-12)  # east = +x
    np.testing.assert_allclose(direction_vector(0, 0), [0, 1, 0], atol=1e-12)   # north = +y
    np.testing.assert_allclose(direction_vector(90, 0), [0, 0, 1], atol=1e-12)


@needs_radiance
@pytest.mark.parametrize("t", ["10:30", "13:30", "16:30"])
def test_gendaylit_sun_points_where_the_sun_is(t):
    sun = mendoza_sun(t)
    st = SkyState(t, local_datetime("2024-12-22", t, -3), sun, 109170.0,
                  diffuse_horizontal_lux=12000.0, sky_model="perez")
    text = run(gendaylit_command(st)).decode()
    lines = text.split("solar source sun")[1].split("\n")
    vec = np.array([float(v) for v in lines[3].split()[1:4]])
    assert angular_separation_deg(vec, sun.vector) < 0.01
    # the sun must be in front of the north-looking façade (y > 0) in the morning/noon
    assert vec[1] > 0
