"""The one executor interface of ``simulate`` and ``sweep`` and the run options (issue 42)."""

from __future__ import annotations

import pytest

from radtree.errors import ConfigError
from radtree.pipeline.executor import (
    DaskExecutor,
    SequentialExecutor,
    ThreadExecutor,
    make_executor,
)
from radtree.pipeline.options import RunOptions


def _square(x: int) -> int:
    if x == 3:
        raise ValueError("three")
    return x * x


@pytest.mark.parametrize("executor", [SequentialExecutor(), ThreadExecutor(3)])
def test_every_job_finishes_once_with_its_result_or_error(executor):
    done = list(executor.run(_square, [1, 2, 3, 4], label="test"))
    assert sorted(d.job for d in done) == [1, 2, 3, 4]
    by_job = {d.job: d for d in done}
    assert {j: by_job[j].value() for j in (1, 2, 4)} == {1: 1, 2: 4, 4: 16}
    assert all(by_job[j].seconds >= 0 and by_job[j].error is None for j in (1, 2, 4))
    assert isinstance(by_job[3].error, ValueError) and by_job[3].result is None
    with pytest.raises(ValueError, match="three"):
        by_job[3].value()


def test_an_interrupt_is_raised_not_recorded():
    def stop(x: int) -> int:
        raise KeyboardInterrupt

    for executor in (SequentialExecutor(), ThreadExecutor(2)):
        with pytest.raises(KeyboardInterrupt):
            list(executor.run(stop, [1, 2]))


def test_make_executor_kinds():
    assert isinstance(make_executor(None, 4), ThreadExecutor)
    assert make_executor(None, 4).workers == 4 and not make_executor(None, 4).remote
    assert isinstance(make_executor("sequential", None), SequentialExecutor)
    local = make_executor("local", 2)
    assert isinstance(local, DaskExecutor) and local.remote and local.workers == 2
    assert make_executor("tcp://127.0.0.1:8786", None).scheduler == "tcp://127.0.0.1:8786"
    with pytest.raises(ConfigError, match="scheduler 'bogus': expected 'local', 'sequential'"):
        make_executor("bogus", None)


def test_a_dask_scheduler_without_dask_names_the_extra(monkeypatch):
    """``make demo`` installs radtree without its extras: ``--scheduler local`` then says how
    to add dask, as a ConfigError (exit 2), not an ImportError's traceback."""
    import radtree.pipeline.executor as executor

    monkeypatch.setattr(executor, "find_spec", lambda name: None)
    for scheduler in ("local", "tcp://127.0.0.1:8786"):
        with pytest.raises(ConfigError, match=r"field 'scheduler': scheduler '.+' runs on dask, "
                           r"which is not installed: pip install 'radtree\[sweep\]' \(in a "
                           r"source checkout: make install\)"):
            RunOptions(scheduler=scheduler)
    assert isinstance(make_executor("sequential", None), SequentialExecutor)


def test_run_options_are_checked_on_creation():
    o = RunOptions(scenarios=["A", "B", "A"], hours=["10:30"], workers=2)
    assert o.scenarios == ("A", "B") and o.hours == ("10:30",) and o.resume
    assert RunOptions(scenarios=[]).scenarios is None and RunOptions(fresh=True).resume is False
    with pytest.raises(AttributeError):
        o.workers = 3  # type: ignore[misc]
    with pytest.raises(ConfigError, match=r"field 'hours': hour '1:30': expected HH:MM"):
        RunOptions(hours=["1:30"])
    with pytest.raises(ConfigError, match=r"field 'workers': workers 0"):
        RunOptions(workers=0)
    with pytest.raises(ConfigError, match=r"field 'scheduler'"):
        RunOptions(scheduler="bogus")
    with pytest.raises(ConfigError, match=r"field 'engine'"):
        RunOptions(engine=3)
    # no scheduler: a thread pool of workers (else the default given); a LocalCluster's
    # workers stay None (one per core) unless set
    assert RunOptions().executor(5).workers == 5
    assert RunOptions(workers=2).executor(5).workers == 2
    assert RunOptions(scheduler="local").executor(5).workers is None
