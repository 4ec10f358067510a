"""The diagnosis files between rules: ``results/interim/diagnosis/<configuration>.npz``.

One configuration's diagnosis (rule ``diagnose_configuration``), everything the
campaign's ``diagnose`` rule needs of it, or why it was not diagnosed: its arrays (fit
coordinates, data, scatter, residuals) exactly, as ``.npz`` columns, the rest as one JSON
text column. One writer, one reader.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from workflow.discovery.configuration import ConfigurationDiagnosis
from workflow.io.tables import read_columns, write_columns
from workflow.models.averaged_fit import FitResult
from workflow.models.configuration_data import ConfigurationData, Scatter

__all__ = ["DiagnosedConfiguration", "write_configuration_diagnosis", "read_configuration_diagnosis"]


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
