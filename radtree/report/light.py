"""The light the report describes: the manifest's record of the weather each scenario-hour was
traced with (:func:`radtree.pipeline.manifest.weather_record`), in words."""

from __future__ import annotations

from typing import Any

from radtree.report.data import SKY_LABELS


def weather_records(manifest: dict[str, Any] | None) -> dict[str, list[dict[str, Any]]]:
    """The manifest's weather record (``{scenario: [{time, source, direct_normal_lux,
    diffuse_horizontal_lux, sky}]}``, :func:`radtree.pipeline.manifest.weather_record`);
    empty when the results predate it."""
    rec = (manifest or {}).get("weather")
    return rec if isinstance(rec, dict) else {}


def light_description(records: list[dict[str, Any]]) -> str:
    """One line on the light of the hours traced, from their weather records."""
    if not records:
        return ("light not recorded (results written before radtree recorded the weather in "
                "results/manifest.json: run `radtree simulate` again)")

    def span(key: str) -> str:
        v = [float(r[key]) for r in records]
        return f"{min(v):,.0f} lx" if max(v) - min(v) < 0.5 else f"{min(v):,.0f}–{max(v):,.0f} lx"

    skies = sorted({str(r["sky"]) for r in records})
    text = f"{', '.join(SKY_LABELS.get(s, s) for s in skies)}: direct normal {span('direct_normal_lux')}"
    if any(float(r["diffuse_horizontal_lux"]) > 0 for r in records):
        text += f", diffuse horizontal {span('diffuse_horizontal_lux')}"
    sources = sorted({str(r["source"]) for r in records})
    return text + f" ({'; '.join(sources)})"
