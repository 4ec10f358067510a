"""The files between rules (``results/interim/``): one writer and one reader each.

- ``campaign.json``: campaign.yaml as validated once by the ``campaign_settings`` rule.
- ``mode/<configuration>.json``: the configuration's modes and bands (the first's keys at
  the top), or why none was found, and the runs the mode search skipped (rule
  ``identify_mode``).
- ``status/<configuration>/<group>.json``: used or excluded, with the reason, for each
  run of one ``analyse_runs`` job; its segments and quality rows go beside it as column
  files (:func:`workflow.io.tables.write_columns`).
- ``diagnosis/<configuration>.npz``: one configuration's diagnosis (rule
  ``diagnose_configuration``), everything the campaign's ``diagnose`` rule needs of it,
  or why it was not diagnosed.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from workflow.io.campaign import Campaign, campaign_from_dict, campaign_to_dict
from workflow.io.tables import read_columns, write_columns, write_json

if TYPE_CHECKING:
    from workflow.discovery.diagnosis import ConfigurationDiagnosis


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


@dataclass(frozen=True)
class DiagnosedConfiguration:
    """One configuration's outcome of rule ``diagnose_configuration``.

    ``diagnosis`` is set when it was diagnosed; otherwise ``skipped`` says why (empty
    when the configuration has no segment at all: it is then left out of the campaign's
    document). ``order`` is the position of its first row in the segments table (the
    campaign's document lists configurations in that order); ``reference_velocity_in_s``
    the campaign's fit context.
    """

    configuration: str
    order: int
    reference_velocity_in_s: float
    diagnosis: ConfigurationDiagnosis | None = None
    skipped: str = ""


_SEPARATOR = "__"  # array names: "<part>__<model>__<key>" (no "/" inside a .npz)


def write_configuration_diagnosis(path: str | Path, outcome: DiagnosedConfiguration) -> None:
    """Write one configuration's diagnosis: its arrays (fit coordinates, data, scatter,
    residuals) exactly, as ``.npz`` columns, and the rest as one JSON text column."""
    from workflow.discovery.diagnosis import ConfigurationData

    summary: dict = {
        "configuration": outcome.configuration,
        "order": outcome.order,
        "reference_velocity_in_s": outcome.reference_velocity_in_s,
        "skipped": outcome.skipped,
    }
    arrays: dict[str, np.ndarray] = {}
    d = outcome.diagnosis
    if d is not None:
        summary["document"] = d.document
        summary["fits"] = {m: {"params": f.params, "cost": f.cost} for m, f in d.fits.items()}
        summary["resamples"] = d.resamples
        summary["data"] = {}
        for spec in fields(ConfigurationData):
            value = getattr(d.data, spec.name)
            if isinstance(value, np.ndarray):
                arrays[f"data{_SEPARATOR}{spec.name}"] = value
            else:
                summary["data"][spec.name] = value
        for m, f in d.fits.items():
            arrays[f"coords{_SEPARATOR}{m}"] = np.asarray(f.coords, float)
        for spec in fields(d.scatter):
            arrays[f"scatter{_SEPARATOR}{spec.name}"] = getattr(d.scatter, spec.name)
        for m, curves in d.residuals.items():
            for key, value in curves.items():
                arrays[f"residuals{_SEPARATOR}{m}{_SEPARATOR}{key}"] = np.asarray(value)
    # allow_nan: costs and parameters of a failed fit may be inf or NaN; this file is
    # read back only by read_configuration_diagnosis.
    write_columns(path, {"summary": np.array(json.dumps(summary, default=_plain)), **arrays})


def _plain(value: object) -> object:
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def read_configuration_diagnosis(path: str | Path) -> DiagnosedConfiguration:
    """The outcome written by :func:`write_configuration_diagnosis`."""
    from workflow.discovery.diagnosis import ConfigurationData, ConfigurationDiagnosis, FitResult, Scatter

    columns = read_columns(path)
    summary = json.loads(str(columns.pop("summary")))
    parts: dict[str, dict] = {}
    for name, value in columns.items():
        part, key = name.split(_SEPARATOR, 1)
        parts.setdefault(part, {})[key] = value
    diagnosis = None
    if "document" in summary:
        residuals: dict[str, dict[str, np.ndarray]] = {}
        for key, value in parts.get("residuals", {}).items():
            model, curve = key.split(_SEPARATOR, 1)
            residuals.setdefault(model, {})[curve] = value
        fits = {
            m: FitResult(m, parts["coords"][m], fit["params"], fit["cost"])
            for m, fit in summary["fits"].items()
        }
        diagnosis = ConfigurationDiagnosis(
            document=summary["document"],
            fits=fits,
            data=ConfigurationData(**summary["data"], **parts["data"]),
            scatter=Scatter(**parts["scatter"]),
            residuals=residuals,
            resamples=summary["resamples"],
        )
    return DiagnosedConfiguration(
        configuration=summary["configuration"],
        order=int(summary["order"]),
        reference_velocity_in_s=float(summary["reference_velocity_in_s"]),
        diagnosis=diagnosis,
        skipped=summary["skipped"],
    )
