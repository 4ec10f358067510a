"""Parquet tables with units in the schema, written atomically.

A table is first written to a temporary file beside its target and then renamed,
so an interrupted run never leaves a truncated table that a later rule would
read as valid.
"""

from __future__ import annotations

import glob
import io
import json
import os
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from workflow.io.units import MODEL_PARAMETER_UNITS, SI_TWIN_COLUMNS

if TYPE_CHECKING:
    import pandas as pd

# pyarrow (and through it pandas, which pyarrow imports on its first conversion) are
# imported where a Parquet table is read or written, not here: the run-analysis jobs
# write their columns with write_columns and start without them.

__all__ = [
    "COLUMN_UNITS",
    "atomic_write_bytes",
    "write_json",
    "write_columns",
    "read_columns",
    "concatenate_columns",
    "with_si_columns",
    "write_table",
    "read_table",
    "table_rows",
    "column_units",
]


#: Units of the columns that the output contract and the project's tables use.
COLUMN_UNITS: dict[str, str] = {
    "t_s": "s",
    "response_amplitude": "response unit (see response_unit)",
    "velocity_amplitude_in_s": "in/s",
    "frequency_hz": "Hz",
    "zeta": "1 (fraction of critical damping)",
    "bearing_area_in2": "in^2",
    "mode_hz": "Hz",
    "nominal_mode_hz": "Hz",
    "band_low_hz": "Hz",
    "band_high_hz": "Hz",
    "fit_rms": "1 (rms residual of ln envelope)",
    "zeta_low": "1 (fraction of critical damping)",
    "zeta_high": "1 (fraction of critical damping)",
    "amplitude_low_in_s": "in/s",
    "amplitude_high_in_s": "in/s",
    "sample_rate_hz": "Hz",
    "record_duration_s": "s",
    "coherence_at_mode": "1 (0-1)",
}


def _temporary_beside(target: Path) -> tuple[int, str]:
    """A new temporary file beside ``target`` (open handle, path), for a rename onto it.

    Temporaries that a killed job left for the same target are removed first (only
    one job writes a given output), and the new one gets the permissions of a file
    created normally (``mkstemp`` makes it 0600, which the rename would keep).
    """
    target.parent.mkdir(parents=True, exist_ok=True)
    for stale in target.parent.glob(f".{glob.escape(target.name)}.*"):
        stale.unlink(missing_ok=True)
    handle, temporary = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.")
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(temporary, 0o666 & ~umask)
    return handle, temporary


def atomic_write_bytes(path: Path | str, payload: bytes) -> None:
    """Write ``payload`` to ``path`` through a temporary file and a rename."""
    target = Path(path)
    handle, temporary = _temporary_beside(target)
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(payload)
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def write_json(path: Path | str, document: object) -> None:
    """Write a JSON document atomically (sorted keys for stable diffs)."""
    text = json.dumps(document, indent=2, sort_keys=False, allow_nan=False, default=_json_default)
    atomic_write_bytes(path, (text + "\n").encode())


def _json_default(value: object) -> object:
    # numpy scalars and arrays appear in computed documents
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_columns(path: Path | str, columns: Mapping[str, np.ndarray]) -> None:
    """Write named 1-D arrays (a small table's columns) as ``.npz``, atomically."""
    buffer = io.BytesIO()
    np.savez(buffer, **{name: np.asarray(column) for name, column in columns.items()})
    atomic_write_bytes(path, buffer.getvalue())


def read_columns(path: Path | str) -> dict[str, np.ndarray]:
    """The columns written by :func:`write_columns`, in their order."""
    with np.load(path, allow_pickle=False) as archive:
        return {name: archive[name] for name in archive.files}


def concatenate_columns(tables: Sequence[Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Tables with the same columns (as from :func:`read_columns`) stacked row-wise."""
    if not tables:
        raise ValueError("no tables to concatenate")
    names = list(tables[0])
    for table in tables[1:]:
        if list(table) != names:
            raise ValueError(f"columns differ: {list(table)} vs {names}")
    return {name: np.concatenate([np.asarray(table[name]) for table in tables]) for name in names}


def with_si_columns(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with each inch-second column of :data:`~workflow.io.units.SI_TWIN_COLUMNS`
    followed by its SI twin (``velocity_amplitude_m_s`` = ``velocity_amplitude_in_s`` x
    0.0254), and, for a table of model parameters (``parameter``, ``value``, ``std``),
    ``unit`` (as fitted) then ``value_si``, ``std_si`` and ``unit_si``.

    Raises
    ------
    ValueError
        A model parameter whose unit is not in
        :data:`~workflow.io.units.MODEL_PARAMETER_UNITS` (the message names it).
    """
    import pandas as pd

    columns = {}
    for name in frame.columns:
        columns[name] = frame[name]
        if name in SI_TWIN_COLUMNS:
            twin, _, factor = SI_TWIN_COLUMNS[name]
            columns[twin] = frame[name] * factor
        if name == "std" and "parameter" in frame.columns:
            unknown = sorted(set(frame["parameter"]) - set(MODEL_PARAMETER_UNITS))
            if unknown:
                raise ValueError(f"model parameters with no known unit, cannot be written in SI: {unknown}")
            entries = frame["parameter"].map(MODEL_PARAMETER_UNITS)  # (unit, SI unit, factor)
            columns["unit"] = entries.str[0]
            columns["value_si"] = frame["value"] * entries.str[2]
            columns["std_si"] = frame["std"] * entries.str[2]
            columns["unit_si"] = entries.str[1]
    return pd.DataFrame(columns, index=frame.index)


def write_table(
    frame: pd.DataFrame,
    path: Path | str,
    units: Mapping[str, str] | None = None,
) -> None:
    """Write ``frame`` as Parquet with each column's unit as field metadata, and the SI
    columns of :func:`with_si_columns` beside the inch-second ones.

    The table is the same whatever config ``units`` says: that choice is how results are
    shown (figures, report), so changing it re-runs no analysis.

    Parameters
    ----------
    frame : DataFrame
        The table; its index is dropped.
    path : path
        Target file; written atomically.
    units : mapping, optional
        Extra ``column -> unit`` entries beside :data:`COLUMN_UNITS`.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    all_units = {**COLUMN_UNITS, **(units or {})}
    frame = with_si_columns(frame)
    all_units.update({twin: unit for twin, unit, _ in SI_TWIN_COLUMNS.values()})
    table = pa.Table.from_pandas(frame.reset_index(drop=True), preserve_index=False)
    fields = [
        field.with_metadata({"unit": all_units[field.name]}) if field.name in all_units else field
        for field in table.schema
    ]
    table = table.cast(pa.schema(fields, metadata=table.schema.metadata))
    target = Path(path)
    handle, temporary = _temporary_beside(target)
    os.close(handle)
    try:
        pq.write_table(table, temporary)
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def read_table(path: Path | str) -> pd.DataFrame:
    """Read a Parquet table written by :func:`write_table`."""
    import pyarrow.parquet as pq

    # ParquetFile, not pq.read_table: the latter imports pyarrow.dataset (0.35 s of
    # start-up in every job that reads a table) for features a single file never needs.
    return pq.ParquetFile(path).read().to_pandas()


def table_rows(path: Path | str) -> int:
    """Rows of a Parquet table, from its footer (no column is read, no pandas imported)."""
    import pyarrow.parquet as pq

    return pq.ParquetFile(path).metadata.num_rows


def column_units(path: Path | str) -> dict[str, str]:
    """The ``unit`` field metadata of each column of a Parquet file."""
    import pyarrow.parquet as pq

    schema = pq.read_schema(path)
    return {
        field.name: field.metadata[b"unit"].decode()
        for field in schema
        if field.metadata and b"unit" in field.metadata
    }
