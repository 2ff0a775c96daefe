"""Make this example's Honeybee model, ``model.hbjson``, with honeybee-core and honeybee-radiance.

Two offices side by side (4 m wide, 6 m deep, 3 m high) behind a north-looking façade in the
plane y = 0 (radtree's studied façade for ``street.facade_azimuth_deg = 0``), a window of 40 %
of each office's façade wall, an opposite building 20 m across the street as a context Shade,
the shared wall between them an interior pair (Surface boundary condition), and one work-plane
sensor grid per office (0.8 m above the floor, 0.5 m cells). Units: metres;
x east, y north, z up. Honeybee's default modifiers (walls 0.5, floor 0.2, ceiling 0.8,
glazing 0.64 visible transmittance, exterior shade 0.35).

    python examples/honeybee-office/make_model.py      # → examples/honeybee-office/model.hbjson
"""

from __future__ import annotations

from pathlib import Path

from honeybee.model import Model
from honeybee.room import Room
from honeybee.shade import Shade
from ladybug_geometry.geometry3d import Face3D, Point3D

HERE = Path(__file__).resolve().parent


def make_model() -> Model:
    rooms = []
    for i, x0 in enumerate((-4.0, 0.0)):
        room = Room.from_box(f"office_{i + 1}", 4.0, 6.0, 3.0, origin=Point3D(x0, -6.0, 0.0))
        room.display_name = f"Office {i + 1}"
        facade = [f for f in room.faces if f.normal.y > 0.99][0]   # the wall in the plane y = 0
        facade.apertures_by_ratio(0.4)
        rooms.append(room)
    Room.solve_adjacency(rooms, 0.01)   # the shared wall (x = 0) becomes one interior pair
    opposite = Shade("opposite_building", Face3D(
        [Point3D(-20, 20, 0), Point3D(20, 20, 0), Point3D(20, 20, 12), Point3D(-20, 20, 12)]))
    model = Model("honeybee_office", rooms, orphaned_shades=[opposite], units="Meters",
                  tolerance=0.01)
    grids = [r.properties.radiance.generate_sensor_grid(0.5, offset=0.8) for r in rooms]
    model.properties.radiance.add_sensor_grids(grids)
    return model


if __name__ == "__main__":
    path = make_model().to_hbjson("model", folder=str(HERE), indent=None)
    print(f"wrote {path}")
