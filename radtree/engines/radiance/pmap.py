"""Radiance's forward method: a photon map (``mkpmap``) read by ``rtrace -ap``.

With ``[engine] pmap_photons = N`` every hour gets, after its octree,

    mkpmap -fo -apg pmaps/HHMM.gpm N [-apc pmaps/HHMM.cpm M] octrees/HHMM.oct

(global photons: every photon stored at its diffuse hits after at least one scattering event;
caustic photons, ``pmap_caustic_photons = M``: photons that reached a diffuse surface through
specular events only, e.g. the slats' undeviated transmission — a scene without specular
materials stores none and mkpmap stops: leave it unset there), and ``rtrace`` reads them with
``-ap pmaps/HHMM.gpm B`` (and ``-ap pmaps/HHMM.cpm B``), B = ``pmap_bandwidth`` photons per
density estimate. ``rtrace`` then computes the direct light and one ambient bounce itself
(``-ab 1``: final gathering) and takes everything beyond that bounce from the global map —
photons launched forward from the sun (and sky) instead of backward paths. Without ports the
distant sources emit their photons over the whole scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from radtree.config import EngineParams

#: the ambient bounces rtrace computes itself before the global photon map takes over
FINAL_GATHER_AB = 1


@dataclass(frozen=True)
class PhotonMap:
    """Photon counts per hour (``global_photons`` ≥ 1; ``caustic_photons`` None = no caustic
    map) and photons per density estimate (``bandwidth``)."""

    global_photons: int
    caustic_photons: int | None
    bandwidth: int

    @classmethod
    def from_params(cls, params: EngineParams) -> PhotonMap | None:
        """The project's photon map, or None when ``pmap_photons`` is unset (the counts were
        checked, ≥ 1, when the project was read)."""
        if params.radiance.pmap_photons is None:
            return None
        return cls(int(params.radiance.pmap_photons), params.radiance.pmap_caustic_photons,
                   int(params.radiance.pmap_bandwidth))

    def files(self, hour: str) -> list[tuple[str, str]]:
        """(option, photon map file) pairs of ``hour`` (label HHMM), relative to the folder."""
        out = [("-apg", f"pmaps/{hour}.gpm")]
        if self.caustic_photons is not None:
            out.append(("-apc", f"pmaps/{hour}.cpm"))
        return out

    def mkpmap_command(self, hour: str) -> list[str]:
        counts = [self.global_photons, self.caustic_photons]
        argv = ["mkpmap", "-fo"]
        for (opt, path), n in zip(self.files(hour), counts):
            argv += [opt, path, str(n)]
        return argv + [f"octrees/{hour}.oct"]

    def rtrace_args(self, hour: str) -> list[str]:
        argv: list[str] = []
        for _, path in self.files(hour):
            argv += ["-ap", path, str(self.bandwidth)]
        return argv

    def describe(self) -> str:
        caustic = f", {self.caustic_photons} caustic" if self.caustic_photons else ""
        return (f"photon map: {self.global_photons} global photons{caustic}, "
                f"{self.bandwidth} per estimate, -ab {FINAL_GATHER_AB} final gathering")
