"""The provenance section (results manifest, inputs, parameter hashes, every parameter) and the
crown-model pictures, as tables of formatted cells."""

from __future__ import annotations

import importlib.metadata
import json
import platform
from dataclasses import dataclass
from typing import Any

import radtree
from radtree.report.data import ReportData
from radtree.report.sections.results import BOOTSTRAP
from radtree.report.tables import Table, text


@dataclass
class ModelPicture:
    """A scenario's crown-model picture (``file`` relative to the report folder, or None with
    the reason in ``missing``), its build notes and its model facts."""

    scenario: str
    title: str
    file: str | None
    missing: str
    notes: list[str]
    info: Table | None


def _flatten(d: Any, prefix: str = "") -> list[tuple[str, str]]:
    if isinstance(d, dict):
        out = []
        for k, v in d.items():
            out += _flatten(v, f"{prefix}.{k}" if prefix else str(k))
        return out
    if isinstance(d, list) and d and any(isinstance(v, dict | list) for v in d):
        out = []
        for i, v in enumerate(d):
            out += _flatten(v, f"{prefix}[{i}]")
        return out
    return [(prefix, json.dumps(d, ensure_ascii=False, default=str)
             if not isinstance(d, str) else d)]


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "—"


def provenance_tables(data: ReportData, created: str) -> dict[str, Table]:
    mf = data.results_manifest or {}
    facts = Table("provenance", "Provenance of the results (results/manifest.json) and of this "
                  "report.", ["item", "value"], [False, False])
    facts.add("project file", str(data.project.source))
    for key, label in (("created", "results written"), ("engine", "engine"),
                       ("radtree_version", "radtree (simulation)"),
                       ("radiance_version", "Radiance"), ("radiance_origin", "Radiance from"),
                       ("python", "Python (simulation)")):
        facts.add(label, text(mf.get(key)))
    seeds = mf.get("seeds")
    if isinstance(seeds, dict):
        for k, v in seeds.items():
            facts.add(f"seed: {k}", text(v))
    facts.add("bootstrap", f"{BOOTSTRAP['n_boot']} resamples of the hours, "
              f"{int(BOOTSTRAP['level'] * 100)} % percentile interval, seed {BOOTSTRAP['seed']}")
    facts.add("report written", created)
    facts.add("radtree (report)", radtree.__version__)
    facts.add("Python (report)", platform.python_version())
    for dist in ("numpy", "pandas", "matplotlib", "jinja2", "pyradiance"):
        facts.add(dist, _version(dist))
    if not mf:
        facts.add("results manifest", "missing (results/manifest.json not found)")

    inputs = Table("inputs", "Input files and their SHA-256 (from results/manifest.json).",
                   ["input", "file", "sha256"], [False, False, False])
    raw_inputs = mf.get("inputs") if isinstance(mf.get("inputs"), dict) else {}
    for k, v in (raw_inputs or {}).items():
        fname, _, digest = str(v).partition(" sha256:")
        inputs.add(k, fname, digest or "—")

    hashes = Table("hashes", "Parameter hash per scenario: in the results table, in the build "
                   "folder's manifest, and from the project file now (they agree when the "
                   "results are current).",
                   ["scenario", "results", "build manifest", "project file now", "status"],
                   [False, False, False, False, False])
    for s in data.scenarios:
        built = text(s.build.get("params_hash")) if s.build_manifest_found else "no manifest"
        now = s.current_hash or "not in project"
        status = ("current" if s.current_hash and s.params_hash == s.current_hash
                  else "stale" if s.current_hash else "—")
        hashes.add(s.name, text(s.params_hash), built, now, status)
    return {"provenance": facts, "inputs": inputs, "hashes": hashes}


def parameters_table(data: ReportData) -> Table:
    mf = data.results_manifest or {}
    params = mf.get("parameters") if isinstance(mf.get("parameters"), dict) else None
    source = "results/manifest.json"
    if params is None:
        params, source = data.project.to_dict(), "the project file (no results manifest)"
    t = Table("parameters", f"Every parameter, from {source}.", ["parameter", "value"],
              [False, False])
    for k, v in _flatten(params):
        t.add(k, v)
    return t


def model_pictures(data: ReportData) -> list[ModelPicture]:
    out = []
    for s in data.scenarios:
        info = s.build.get("info") if isinstance(s.build.get("info"), dict) else {}
        table = None
        if info:
            numeric = all(isinstance(v, int | float) and not isinstance(v, bool)
                          for v in info.values())
            table = Table(f"info_{s.name}", f"Crown model facts of scenario {s.name}.",
                          ["quantity", "value"], [False, numeric])
            for k, v in info.items():
                table.add(k, f"{v:.6g}" if numeric else text(v))
        notes = [str(n) for n in s.build.get("notes", [])] if s.build_manifest_found else []
        if s.picture is not None:
            missing = ""
        elif s.picture_problem:
            missing = f"no picture ({s.picture_problem})"
        elif s.model == "none":
            missing = "no picture (no crown: open street)"
        else:
            missing = f"no picture (build/{s.name}/model.png not found)"
        if not s.build_manifest_found:
            notes = [f"no build manifest (build/{s.name}/manifest.json): run `radtree build` "
                     "to record how the crown was read"]
        out.append(ModelPicture(
            scenario=s.name, title=f"{s.name}: {s.model_label}, {s.form_label}",
            file=f"models/{s.name}.png" if s.picture is not None else None,
            missing=missing, notes=notes, info=table))
    return out
