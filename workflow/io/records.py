"""What campaign.yaml's reader and the run-file readers share: the error that names a
file and line, the smallest run, the record of one run file, and the checks of a file's
units and sample rate against campaign.yaml.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workflow.io.units import response_quantity_of

__all__ = [
    "MIN_SAMPLES",
    "CampaignFormatError",
    "RunFile",
    "ResponseChannel",
    "RunRecord",
]


MIN_SAMPLES: int = 256
"""Fewest samples a run file must hold. Below this a record cannot hold even a few
cycles of the mode plus the filter's settling time, and such short files are in
practice truncated exports ("fewer than a few hundred samples" in the contract)."""


# --------------------------------------------------------------------------------------
# Errors


class CampaignFormatError(ValueError):
    """A campaign file breaks the input contract.

    Attributes
    ----------
    path : str
        The offending file.
    line : int or None
        1-based line number, or None when the problem is not tied to one line.
    problem : str
        What is wrong, in words a person can act on.
    """

    def __init__(self, path: str | Path, line: int | None, problem: str) -> None:
        self.path = Path(path).as_posix() if isinstance(path, Path) else str(path)
        self.line = line
        self.problem = problem
        super().__init__(self._message())

    def _message(self) -> str:
        if self.line is None:
            return f"{self.path}: {self.problem}"
        return f"{self.path}:{self.line}: {self.problem}"

    def __str__(self) -> str:
        return self._message()

    def __reduce__(self) -> tuple[Any, ...]:
        # Exceptions are re-created from args when pickled (e.g. across processes).
        return (type(self), (self.path, self.line, self.problem))


# --------------------------------------------------------------------------------------
# Run files: the record


@dataclass(frozen=True)
class RunFile:
    """One run file of a configuration."""

    configuration: str
    run: str
    """File name without extension."""
    path: str
    """Path relative to the campaign folder, with ``/`` separators."""


@dataclass(frozen=True, eq=False)
class ResponseChannel:
    """One response channel of a run, in its own unit.

    Attributes
    ----------
    name : str
        The channel's name in every table: campaign.yaml's reference
        (:meth:`workflow.io.campaign.ResponseSpec.channel_names`).
    values : ndarray
        The samples.
    unit : str
        Canonical unit of ``values``.
    source : str
        The file's own name for the channel (column name, system channel name; empty
        for an unnamed ASCII column).
    """

    name: str
    values: NDArray[np.float64]
    unit: str
    source: str = ""

    @property
    def quantity(self) -> str:
        """What the channel records (acceleration, velocity, displacement): its unit's."""
        return response_quantity_of(self.unit)


@dataclass(frozen=True, eq=False)
class RunRecord:
    """One run file, read and checked.

    Attributes
    ----------
    path : str
        The file's path relative to the campaign folder (``/`` separators).
    sample_rate_hz : float
        Samples per second.
    pretrigger_samples : int
        Samples recorded before the trigger.
    time_s : ndarray or None
        The file's time column in s, when it has one.
    force_lbf : ndarray or None
        Hammer force in lbf, when recorded.
    response : ndarray
        The first response channel's samples as in the file, in ``response_unit``.
    response_quantity : str
        acceleration, velocity or displacement: what ``response`` records.
    response_unit : str
        Canonical unit of ``response``.
    header : dict
        The header's ``key: value`` lines (raw strings).
    n_samples : int
        Number of samples.
    column_names : tuple of str
        Names from the header's line of names (empty without one).
    sample_rate_source : str
        Where the sample rate came from: ``campaign.yaml``, ``header`` or ``time column``.
    pretrigger_source : str
        ``campaign.yaml``, ``header``, ``time column`` (a time column that starts before
        0) or ``default`` (contract default 0, not stated).
    record_start : str
        Wall-clock time the recording started, ISO 8601, when the file states it
        (:mod:`workflow.io.recording_time`); empty otherwise (ASCII files).
    refused_channels : tuple of (str, str)
        The response channels campaign.yaml asks for whose unit contradicts it (name, why),
        left out of ``responses`` while another channel is kept.
    responses : tuple of ResponseChannel
        Every other response channel campaign.yaml asks for, in its order; ``response`` and
        ``response_unit`` are the first's (:meth:`for_channel` picks another; the channels
        may record different quantities, each its unit's).
    """

    path: str
    sample_rate_hz: float
    pretrigger_samples: int
    time_s: NDArray[np.float64] | None
    force_lbf: NDArray[np.float64] | None
    response: NDArray[np.float64]
    response_quantity: str
    response_unit: str
    header: dict[str, str]
    n_samples: int
    column_names: tuple[str, ...] = ()
    sample_rate_source: str = "campaign.yaml"
    pretrigger_source: str = "default"
    record_start: str = ""
    responses: tuple[ResponseChannel, ...] = ()
    refused_channels: tuple[tuple[str, str], ...] = ()

    def channel_names(self) -> tuple[str, ...]:
        """The names of :attr:`responses`."""
        return tuple(channel.name for channel in self.responses)

    def without_channels(self, names: set[str]) -> RunRecord:
        """The record without the response channels ``names`` (at least one must remain);
        ``response`` is then the first remaining channel's."""
        if not names:
            return self
        remaining = tuple(channel for channel in self.responses if channel.name not in names)
        if not remaining:
            raise ValueError(f"{self.path}: no response channel would remain")
        return replace(self, responses=remaining).for_channel(remaining[0].name)

    def for_channel(self, name: str) -> RunRecord:
        """The record with ``response``, ``response_unit`` and ``response_quantity`` of the
        response channel ``name`` (KeyError when the record has none of that name)."""
        for channel in self.responses:
            if channel.name == name:
                if channel.values is self.response:
                    return self
                return replace(
                    self,
                    response=channel.values,
                    response_unit=channel.unit,
                    response_quantity=channel.quantity,
                )
        raise KeyError(f"{self.path}: no response channel {name!r} (has {', '.join(self.channel_names())})")
