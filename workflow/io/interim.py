"""The files between rules (``results/interim/``): one writer and one reader each.

- ``campaign.json``: campaign.yaml as validated once by the ``campaign_settings`` rule.
- ``mode/<configuration>.json``: the configuration's modes and bands (the first's keys at
  the top), or why none was found, and the runs the mode search skipped (rule
  ``identify_mode``).
- ``status/<configuration>/<group>.json``: used or excluded, with the reason, for each
  run of one ``analyse_runs`` job; its segments and quality rows go beside it as column
  files (:func:`workflow.io.tables.write_columns`).

The diagnosis files (``diagnosis/<configuration>.npz``) are discovery's:
:mod:`workflow.discovery.diagnosis_files`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from workflow.io.campaign import Campaign, campaign_from_dict, campaign_to_dict
from workflow.io.tables import write_json

__all__ = [
    "ModeInfo",
    "ConfigurationMode",
    "write_campaign",
    "read_campaign",
    "write_mode",
    "read_mode",
    "write_run_statuses",
    "read_run_statuses",
]


@dataclass(frozen=True)
class ModeInfo:
    """First mode of a configuration and the band used to isolate it."""

    mode_hz: float
    band_hz: tuple[float, float]
    method: str  # "h1" (force recorded), "spectrum" (response only) or "campaign" (given)
    coherence_at_mode: float | None
    n_runs: int
    sample_rate_hz: float
    record_duration_s: float  # median over the runs used


@dataclass(frozen=True)
class ConfigurationMode:
    """What the mode search found for one configuration.

    Exactly one of ``mode`` and ``error`` is set: the (first) mode, or why none was found
    (then every run of the configuration is excluded with that reason).
    """

    mode: ModeInfo | None
    error: str = ""
    skipped_runs: dict[str, list[str]] = field(default_factory=dict)
    """Run name -> why the mode search left it out (it is excluded later with the same reason)."""
    further_modes: tuple[ModeInfo, ...] = ()
    """The modes after the first (campaign.yaml's ``modes_hz``, or every mode ``auto`` found)."""
    left_out: tuple[str, ...] = ()
    """Why each clear spectral peak that is not a mode was left out (``modes_hz: auto``)."""

    @property
    def modes(self) -> tuple[ModeInfo, ...]:
        """Every mode analysed, in increasing order of campaign.yaml's list (or frequency)."""
        return () if self.mode is None else (self.mode, *self.further_modes)


def write_campaign(path: str | Path, campaign: Campaign) -> None:
    """Write the validated campaign for every later job (which then needs neither PyYAML
    nor pydantic)."""
    write_json(path, campaign_to_dict(campaign))


def read_campaign(path: str | Path) -> Campaign:
    """The campaign written by :func:`write_campaign`."""
    return campaign_from_dict(json.loads(Path(path).read_text(encoding="utf-8")))


def _mode_document(mode: ModeInfo) -> dict:
    return {
        "mode_hz": mode.mode_hz,
        "band_hz": list(mode.band_hz),
        "method": mode.method,
        "coherence_at_mode": mode.coherence_at_mode,
        "n_runs": mode.n_runs,
        "sample_rate_hz": mode.sample_rate_hz,
        "record_duration_s": mode.record_duration_s,
    }


def _mode_of(document: dict) -> ModeInfo:
    return ModeInfo(
        mode_hz=float(document["mode_hz"]),
        band_hz=(float(document["band_hz"][0]), float(document["band_hz"][1])),
        method=str(document["method"]),
        coherence_at_mode=document.get("coherence_at_mode"),
        n_runs=int(document["n_runs"]),
        sample_rate_hz=float(document["sample_rate_hz"]),
        record_duration_s=float(document["record_duration_s"]),
    )


def write_mode(path: str | Path, found: ConfigurationMode) -> None:
    """Write one configuration's mode search result: the first mode's keys at the top,
    every mode under ``modes``."""
    document: dict = {"skipped_runs": found.skipped_runs, "left_out": list(found.left_out)}
    if found.mode is None:
        document["error"] = found.error
    else:
        document.update(_mode_document(found.mode))
        document["modes"] = [_mode_document(mode) for mode in found.modes]
    write_json(path, document)


def read_mode(path: str | Path) -> ConfigurationMode:
    """The mode search result written by :func:`write_mode`."""
    document = json.loads(Path(path).read_text(encoding="utf-8"))
    skipped = document.get("skipped_runs", {})
    left_out = tuple(document.get("left_out", ()))
    if "error" in document:
        return ConfigurationMode(None, document["error"], skipped, left_out=left_out)
    modes = [_mode_of(mode) for mode in document.get("modes", [document])]
    return ConfigurationMode(modes[0], "", skipped, tuple(modes[1:]), left_out)


def write_run_statuses(path: str | Path, statuses: list[dict]) -> None:
    """Write the status rows (configuration, run, path, status, reason, record_start,
    response_units) of one job's runs."""
    write_json(path, statuses)


def read_run_statuses(paths: list[str | Path]) -> list[dict]:
    """The status rows of every job's file written by :func:`write_run_statuses`, in order."""
    return [status for path in paths for status in json.loads(Path(path).read_text(encoding="utf-8"))]
