"""The Radiance side of the three-phase method: rfluxmtx view and daylight matrices, a crown
BSDF turned round for light leaving a closed crown, and ``dctimestep``.

Conventions are those of the Radiance matrix tutorials (the window's normal points *into the
room*; the view matrix's receiver is ``#@rfluxmtx h=kf``, the daylight matrix's sender the same
polygons with ``h=-kf``), with the crown shell's facets in the role of the window. The "room"
is the sensors' side of the shell: inside for the sensor dome, outside for free crowns.

* view matrix ``V`` — ``rfluxmtx -I+ -y N - receivers.rad -i scene.oct < points``: receivers
  are every facet group of the shell (Klems ``kf``, one modifier per group, its normal the
  mean of its facets', rfluxmtx's default up: +Z unless the normal is within 45° of vertical,
  then +Y) *and* the sky (``h=u`` ground glow + ``h=r<MF> u=+Y`` Reinhart sky: the columns of
  ``gendaymtx``) — so ``V`` also holds the light that reaches a sensor without crossing the
  shell (the by-pass, ``Vsky``).
* daylight matrix ``D`` of group g — ``rfluxmtx -c N sender_g.rad sky.rad -i scene.oct``: the
  group's facets, moved ``SENDER_OFFSET_M`` to the shell's far side so that their own crossing
  is not traced twice, send rays away from the room; whatever else the scene holds (the far
  side of a free crown's shell as a ``BSDF`` material, trunks, streets, rooms) is traced.
* ``rmtxop V_g T.xml D_g`` — the daylight coefficients through group g (rmtxop and
  dctimestep load the XML alike, ``cm_loadBTDF``: its "Transmission Front", WINDOW's
  exterior → room); their sum times the sky matrix is ``dctimestep``'s product, done in NumPy
  for the 8760 hours. Light leaves a free crown from its inside (the XML's back) to
  the sensors (its front): :func:`turned_xml` swaps the XML's front and back blocks.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from radtree.engines.radiance.binaries import run
from radtree.errors import EngineError
from radtree.fileio import write_text

#: a daylight-matrix sender sits this far behind its facets (on the shell's far side)
SENDER_OFFSET_M = 0.002
#: Klems receivers per rfluxmtx run of a view matrix: rfluxmtx stops at "too many
#: arguments" (it passes rcontrib some 8 per receiver; 1 172 groups failed, 320 ran)
VIEW_CHUNK = 400
_REFLECT = {"Reflection Back": "Transmission Front", "Reflection Front": "Transmission Back",
            "Transmission Front": "Reflection Back", "Transmission Back": "Reflection Front"}
_SWAP = {"Transmission Front": "Transmission Back", "Transmission Back": "Transmission Front",
         "Reflection Front": "Reflection Back", "Reflection Back": "Reflection Front"}


def default_up(normal: np.ndarray) -> str:
    """rfluxmtx's default up vector for a hemisphere of ``normal`` (as its source does)."""
    return "+Y" if abs(float(normal[2])) >= 0.7 else "+Z"


def up_text(normal: np.ndarray, up: tuple[float, float, float] | None) -> str:
    """rfluxmtx's ``u=`` of a hemisphere of ``normal``: ``up`` (a world vector, e.g. the
    ``BSDF`` material's, so that the Klems patches of the matrices are the material's) or,
    when None or within 0.1° of ``normal``, :func:`default_up`."""
    if up is None:
        return default_up(normal)
    u = np.asarray(up, float)
    n = np.asarray(normal, float)
    if np.linalg.norm(np.cross(u, n)) < 2e-3 * np.linalg.norm(u) * np.linalg.norm(n):
        return default_up(normal)
    return ",".join(f"{v:.6g}" for v in u)


def _polygons(modifier: str, name: str, triangles: np.ndarray) -> str:
    out = []
    for i, t in enumerate(triangles):
        coords = " ".join(f"{v:.5f}" for v in t.ravel())
        out.append(f"{modifier} polygon {name}.{i}\n0\n0\n9 {coords}\n")
    return "\n".join(out)


def sky_receivers_text(mf: int) -> str:
    """Ground (``h=u``) then the Reinhart sky of subdivision ``mf`` (``h=r<mf> u=+Y``):
    1 + 145·mf² columns in ``gendaymtx``'s order (0 = ground)."""
    return ("#@rfluxmtx h=u\nvoid glow tp_ground\n0\n0\n4 1 1 1 0\n\n"
            "tp_ground source tp_ground_src\n0\n0\n4 0 0 -1 180\n\n"
            f"#@rfluxmtx h=r{mf} u=+Y\nvoid glow tp_sky\n0\n0\n4 1 1 1 0\n\n"
            "tp_sky source tp_sky_src\n0\n0\n4 0 0 1 180\n")


def group_receivers_text(groups: list[tuple[np.ndarray, np.ndarray]],
                         ups: list[tuple[float, float, float] | None] | None = None) -> str:
    """One Klems receiver per facet group: ``(triangles (k, 3, 3), mean normal)``, each
    triangle wound so its normal points to the room (the sensors' side); ``ups``: each
    group's up vector (:func:`up_text`)."""
    out = []
    ups = ups if ups is not None else [None] * len(groups)
    for g, ((tri, normal), up) in enumerate(zip(groups, ups)):
        out.append(f"#@rfluxmtx h=kf u={up_text(normal, up)}\nvoid glow tp_win{g}\n0\n0\n"
                   f"4 1 1 1 0\n\n" + _polygons(f"tp_win{g}", f"tp_win{g}", tri))
    return "\n".join(out)


def blocker_text(triangles: list[np.ndarray]) -> str:
    """Facets that absorb every ray (a ``glow`` of radiance 0): the groups of a view matrix
    traced in another rfluxmtx run (:data:`VIEW_CHUNK`)."""
    return "void glow tp_block\n0\n0\n4 0 0 0 0\n\n" + "\n".join(
        _polygons("tp_block", f"tp_block{k}", t) for k, t in enumerate(triangles))


def sender_text(triangles: np.ndarray, normal: np.ndarray, room_side: bool = False,
                up: tuple[float, float, float] | None = None, *,
                material_faces_room: bool = True) -> str:
    """The daylight-matrix sender of one group (``triangles`` wound to the room, ``normal``
    towards it): its facets moved :data:`SENDER_OFFSET_M` away from the room (rays leave
    away from the room: the light the group transmits); ``room_side``: moved towards the
    room and wound the other way (rays leave into the room: the light the group reflects
    back into it).

    rfluxmtx sends a sender's rays to the side its polygons' normal points *away* from,
    whatever the sign of ``h=±kf`` (measured: a polygon under a uniform sky, normal down,
    ``h=+kf`` and ``h=-kf`` both see the sky, normal up neither; the Radiance tutorials'
    window sender, normal into the room, ``h=-kf``, sends its rays out), so the room side is
    the winding turned round, not ``h=+kf`` (issue 40: with ``h=+kf`` and the room's winding
    the "room-side" rays went back into the crown and read the light the crown sends into
    the room, ≈ 5 × the light arriving at the office's wall cap from the room's side).

    The sign of ``h=±kf`` sets the Klems x axis: ±(up × polygon normal) for ``h=±kf``
    (``rfluxmtx.c`` ``prepare_sampler``), while rtrace applies the XML in one frame for
    incident and outgoing patches with x = material normal × up (``bsdf_m.c``; measured by
    ``benchmarks/klems_handedness.py``) and the view matrix's ``h=kf`` receiver has
    x = up × n. ``material_faces_room`` False (free crowns: the shell's normals point into
    the crown): the outward sender is ``h=+kf`` so that T's incident patches are in the
    frame of the receiver and of rtrace (with ``h=-kf`` the chain mirrored T left/right:
    the office closure read 0.991 / 0.950, now 1.009 / 1.014). True (the dome, a window
    whose material normal faces the room): the tutorial's ``h=-kf``, unchanged (there the
    receiver's x is the mirrored one; not fixed)."""
    n = np.asarray(normal, float)
    tri = np.asarray(triangles, float)
    if room_side:     # towards the room, its normal away from it
        moved, n = tri[:, ::-1] + SENDER_OFFSET_M * n, -n
    else:
        moved = tri - SENDER_OFFSET_M * n
    sign = "-" if room_side or material_faces_room else "+"
    return f"#@rfluxmtx h={sign}kf u={up_text(n, up)}\n\n" + _polygons("void", "tp_sender", moved)


def read_matrix(data: bytes, what: str) -> np.ndarray:
    """An rfluxmtx/dctimestep ``-ff`` matrix (header, then float32 RGB) → (rows, cols, 3)."""
    end = data.find(b"\n\n")
    if end < 0:
        raise EngineError(f"{what}: no header end in the output")
    head = dict(line.split("=", 1) for line in data[:end].decode(errors="replace").splitlines()
                if "=" in line)
    try:
        rows, cols = int(head["NROWS"]), int(head["NCOLS"])
    except (KeyError, ValueError) as exc:
        raise EngineError(f"{what}: no NROWS/NCOLS in the header {head}") from exc
    body = np.frombuffer(data[end + 2:], dtype="<f4")
    if body.size != rows * cols * 3:
        raise EngineError(f"{what}: {body.size} values, expected {rows} × {cols} × 3")
    return body.reshape(rows, cols, 3).copy()


def view_matrix(folder: Path, octree: Path, points: str, n_points: int,
                receivers: str, ambient: list[str], nproc: int) -> np.ndarray:
    """(sensors, columns, 3) ``V``: sensor points (ASCII, ``-faf``) → the receivers of
    ``receivers`` text."""
    rec = folder / "view_receivers.rad"
    write_text(rec, receivers)
    cmd = ["rfluxmtx", "-I+", "-y", str(n_points), "-faf", "-n", str(nproc), *ambient, "-",
           str(rec), "-i", str(octree)]
    return read_matrix(run(cmd, stdin=points.encode(), cwd=folder), "rfluxmtx (view)")


def daylight_matrix(folder: Path, octree: Path, name: str, sender: str, mf: int,
                    samples: int, ambient: list[str], nproc: int) -> Path:
    """``D`` of one sender (145 Klems rows × sky columns) written to ``folder/<name>.dmx``."""
    snd, sky = folder / f"{name}_sender.rad", folder / "sky_receivers.rad"
    write_text(snd, sender)
    write_text(sky, sky_receivers_text(mf))
    out = folder / f"{name}.dmx"
    cmd = ["rfluxmtx", "-ff", "-n", str(nproc), "-c", str(samples), *ambient, str(snd),
           str(sky), "-i", str(octree)]
    tmp = out.with_name(out.name + ".tmp")
    run(cmd, cwd=folder, stdout_path=tmp)
    tmp.replace(out)
    return out


def octree(folder: Path, name: str, scene_text: str) -> Path:
    """``oconv`` of ``scene_text`` (written to ``folder/<name>.rad``) → ``<name>.oct``."""
    rad = folder / f"{name}.rad"
    write_text(rad, scene_text)
    out = folder / f"{name}.oct"
    run(["oconv", str(rad)], stdout_path=out)
    return out


def write_matrix(path: Path, m: np.ndarray) -> Path:
    """(rows, cols, 3) float32 as a Radiance matrix file (``-ff``) for dctimestep/rmtxop."""
    m = np.ascontiguousarray(m, dtype="<f4")
    head = (f"#?RADIANCE\nNROWS={m.shape[0]}\nNCOLS={m.shape[1]}\nNCOMP=3\n"
            "FORMAT=float\n\n").encode()
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(head + m.tobytes())
    tmp.replace(path)
    return path


def multiply(view: Path, xml: Path, daylight: Path) -> np.ndarray:
    """``rmtxop -ff V T.xml D`` → (sensors, sky patches, 3): the daylight coefficients of
    the light through one facet group (rmtxop reads the XML as dctimestep does, its
    "Transmission Front", ``cm_loadBTDF``)."""
    cmd = ["rmtxop", "-ff", str(view), str(xml), str(daylight)]
    return read_matrix(run(cmd), "rmtxop")


def _relabel(xml: Path, dest: Path, mapping: dict[str, str]) -> Path:
    text = Path(xml).read_text()
    pattern = re.compile(r"(<WavelengthDataDirection>)\s*(" + "|".join(mapping) + r")\s*(<)")
    write_text(dest, pattern.sub(lambda m: m.group(1) + mapping[m.group(2)] + m.group(3), text))
    return dest


def turned_xml(xml: Path, dest: Path) -> Path:
    """``xml`` with its front and back data blocks swapped (the same layer, light crossing it
    the other way): for light leaving a closed crown from the inside."""
    return _relabel(xml, dest, _SWAP)


def room_reflection_xml(xml: Path, dest: Path) -> Path:
    """``xml`` (front = away from the room, back = the room's side) relabelled so that its
    "Transmission Front" block — what rmtxop/dctimestep read — holds its "Reflection Back":
    the layer's reflection of light arriving from the room's side back into it."""
    return _relabel(xml, dest, _REFLECT)
