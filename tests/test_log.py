"""One way to talk to the user (issue 42): library quiet by default, the CLI prints."""

from __future__ import annotations

import io
import logging

from click.testing import CliRunner

from radtree import log
from radtree.cli import main


def test_library_is_quiet_until_enabled() -> None:
    stream = io.StringIO()
    lg = logging.getLogger("radtree.some.module")
    log.disable()
    lg.info("built 3 scenarios")
    assert not log.enabled()
    assert log.progress([1, 2], desc="x") == [1, 2]
    bar = log.progress(desc="x", total=3)
    bar.update(1)
    bar.close()
    log.enable(stream=stream, progress=False)
    try:
        lg.info("built 3 scenarios")
        lg.debug("not shown at INFO")
        lg.warning("EPW header says UTC+0")
    finally:
        log.disable()
    lg.info("quiet again")
    assert stream.getvalue() == "built 3 scenarios\nwarning: EPW header says UTC+0\n"


def test_enable_twice_prints_once() -> None:
    stream = io.StringIO()
    log.enable(stream=stream, progress=False)
    log.enable(logging.DEBUG, stream=stream, progress=False)
    try:
        logging.getLogger("radtree.x").debug("detail")
    finally:
        log.disable()
    assert stream.getvalue() == "detail\n"
    assert [h for h in logging.getLogger("radtree").handlers
            if not isinstance(h, logging.NullHandler)] == []


def test_cli_installs_and_removes_the_handler(tmp_path) -> None:
    res = CliRunner().invoke(main, ["-q", "new", str(tmp_path / "p"), "--lat", "40.42",
                                    "--lon", "-3.70", "--tz", "Europe/Madrid"])
    assert res.exit_code == 0, res.output
    assert not log.enabled()
