"""``radtree annual``'s coefficients repeat exactly: the sensor points are split into fixed
chunks, one single-process ``rcontrib`` each (``rcontrib -n 2`` let its children take rays as
they came free, so two fresh runs of the honeybee-office example differed by up to 4 pp of sDA).
"""

from __future__ import annotations

import numpy as np

from radtree.annual.coefficients import CoefficientRunner, TraceParams

from .conftest import needs_radiance
from .test_annual import _tiny_scene


@needs_radiance
def test_two_processes_give_the_same_coefficients_every_time(tmp_path):
    scene = _tiny_scene(room=True)
    params = TraceParams(ab=2, ad=64, lw=1e-3, nproc=2)
    runs = [CoefficientRunner(scene, ["g"], tmp_path / f"run{i}", 0.2).sky(1, params)
            for i in range(2)]
    one = CoefficientRunner(scene, ["g"], tmp_path / "one", 0.2).sky(
        1, TraceParams(ab=2, ad=64, lw=1e-3, nproc=1))
    assert runs[0].shape == one.shape == (8, 146, 3)
    assert np.array_equal(runs[0], runs[1])               # bit for bit, fresh runs
    assert runs[0][:, 1:].sum() > 0
    # the first chunk is the single process's first points: the same sample sequence
    assert np.array_equal(runs[0][:4], one[:4])
