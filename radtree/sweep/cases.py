"""One case of a sweep: plain case data, its folder's hash, and :func:`run_case`, the function a
worker runs (build and simulate the case as an ordinary project in its folder, never raising).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import socket
import time
import traceback
from collections.abc import Iterable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import PATH_FIELDS
from radtree.errors import RadtreeError
from radtree.fileio import atomic_path, write_text
from radtree.log import ROOT
from radtree.sweep.design import Value

log = logging.getLogger(__name__)

CASE_COLUMNS = ["case_id", "case_hash"]


@dataclass(frozen=True)
class CaseSpec:
    """Everything a worker needs to run one case (plain, picklable data)."""

    case_id: str
    case_hash: str
    params: dict[str, Value]
    folder: str
    toml_text: str
    engine: str
    scenarios: tuple[str, ...] | None = None
    hours: tuple[str, ...] | None = None


@dataclass
class CaseResult:
    """What :func:`run_case` returns: ``status`` is ``done`` or ``failed``."""

    case_id: str
    case_hash: str
    params: dict[str, Value]
    status: str
    seconds: float = 0.0
    error: str = ""
    error_type: str = ""
    host: str = ""
    pid: int = 0
    table: pd.DataFrame | None = field(default=None, repr=False)


def _absolute(value: Any, root: Path) -> Any:
    if isinstance(value, str) and value and not Path(value).is_absolute():
        return str((root / value).resolve())
    return value


def _looks_like_path(value: str) -> bool:
    return ("/" in value or "\\" in value or Path(value).suffix != "") and "\n" not in value


def absolutise_paths(data: dict[str, Any], root: Path) -> dict[str, Any]:
    """Rewrite the relative data paths of project data to absolute ones (in place; returned).

    The known path fields always; any other relative text value that names an existing file
    of the project folder too (so fields added later keep working from the case folder).
    """
    for name in PATH_FIELDS:
        table: Any = data
        parts = name.split(".")
        for part in parts[:-1]:
            table = table.get(part) if isinstance(table, dict) else None
        if isinstance(table, dict) and isinstance(table.get(parts[-1]), str):
            table[parts[-1]] = _absolute(table[parts[-1]], root)
    for item in data.get("geometry", []) or []:
        if isinstance(item, dict) and isinstance(item.get("file"), str):
            item["file"] = _absolute(item["file"], root)

    def walk(obj: Any) -> Any:
        if isinstance(obj, dict):
            return {k: walk(v) for k, v in obj.items()}
        if isinstance(obj, list):
            return [walk(v) for v in obj]
        if (isinstance(obj, str) and obj and _looks_like_path(obj)
                and not Path(obj).is_absolute()):
            try:
                if (root / obj).is_file():
                    return str((root / obj).resolve())
            except (OSError, ValueError):
                return obj
        return obj

    walked = walk(data)
    data.clear()
    data.update(walked)
    return data


def case_hash(data: dict[str, Any], engine: str, scenarios: Iterable[str] | None,
              hours: Iterable[str] | None) -> str:
    """12-hex hash of the case's project data, engine, scenarios and hours."""
    payload = {"project": data, "engine": engine,
               "scenarios": list(scenarios) if scenarios else None,
               "hours": list(hours) if hours else None}
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def case_header(source: Path, case_id: str, params: dict[str, Value]) -> str:
    """The comment heading a case's ``radtree.toml``: its source and overrides."""
    lines = [f"radtree sweep case, generated from {source}",
             "(relative data paths rewritten to absolute ones; [sweep] table removed)",
             "overrides:"]
    lines += [f"  {k} = {v!r}" for k, v in params.items()]
    del case_id  # the case id depends on the design order; the file must not
    return "\n".join(lines)


@contextlib.contextmanager
def case_log(path: Path) -> Iterator[None]:
    """radtree's messages (INFO and above) appended to ``path`` while inside: a case's
    ``case.log``, written in whichever process runs the case."""
    root = logging.getLogger(ROOT)
    handler = logging.FileHandler(path, encoding="utf-8")
    handler.setLevel(logging.INFO)
    handler.setFormatter(logging.Formatter("%(message)s"))
    level = root.level
    if level == logging.NOTSET or level > logging.INFO:   # a worker process: quiet by default
        root.setLevel(logging.INFO)
    root.addHandler(handler)
    try:
        yield
    finally:
        root.removeHandler(handler)
        handler.close()
        root.setLevel(level)


def run_case(spec: CaseSpec) -> CaseResult:
    """Build and simulate one case as an ordinary project in its folder; never raises.

    Writes ``radtree.toml`` (if it differs), runs :func:`radtree.pipeline.simulate.simulate_project`
    (after building with pictures off for Radiance), then ``result.csv`` atomically and
    ``case.json``. Any exception becomes a ``failed`` result carrying its message.
    """
    t0 = time.perf_counter()
    folder = Path(spec.folder)
    result = CaseResult(spec.case_id, spec.case_hash, dict(spec.params), "failed",
                        host=socket.gethostname(), pid=os.getpid())
    try:
        folder.mkdir(parents=True, exist_ok=True)
        toml = folder / "radtree.toml"
        if not toml.exists() or toml.read_text(encoding="utf-8") != spec.toml_text:
            write_text(toml, spec.toml_text)
        with case_log(folder / "case.log"):
            log.info("--- case %s on %s pid %s at %s", spec.case_hash, result.host, result.pid,
                     time.strftime("%Y-%m-%d %H:%M:%S"))
            table = _simulate_case(folder, spec)
        scenarios, hours = spec.scenarios, spec.hours
        if scenarios:
            table = table[table["scenario"].astype(str).isin(scenarios)]
        if hours:
            table = table[table["time"].astype(str).isin(hours)]
        table = table.reset_index(drop=True)
        with atomic_path(folder / "result.csv") as tmp:
            table.to_csv(tmp, index=False)
        result.status = "done"
        result.table = table
    except Exception as exc:  # noqa: BLE001 - a case must fail alone, with its message
        result.error = str(exc) or type(exc).__name__
        result.error_type = type(exc).__name__
        if not isinstance(exc, RadtreeError):
            result.error += "\n" + traceback.format_exc(limit=6)
    result.seconds = time.perf_counter() - t0
    try:
        meta = {k: v for k, v in asdict(result).items() if k != "table"}
        write_text(folder / "case.json", json.dumps(meta, indent=2, default=str))
    except OSError:
        pass
    return result


def _simulate_case(folder: Path, spec: CaseSpec) -> pd.DataFrame:
    """Build (Radiance: without model pictures) and simulate the case's project; its table."""
    from radtree.config import load_project
    from radtree.engines.registry import get_engine
    from radtree.pipeline.build import build_project
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    project = load_project(folder)
    if get_engine(spec.engine).uses_build_folder:
        build_project(project, list(spec.scenarios) if spec.scenarios else None,
                      pictures=False)
    return simulate_project(project, options=RunOptions(
        engine=spec.engine, scenarios=spec.scenarios, hours=spec.hours, workers=1)).table
