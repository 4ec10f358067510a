"""From the channels of a system-format file to the run record the analysis reads.

Decisions where the contract leaves room:

- A channel's role (time, force, response) comes from the file's own label where it has
  one (UFF58 data type), else from its unit (N or lbf: force; a unit of acceleration,
  velocity or displacement: response; s: time), else from its name by the ASCII column
  rules (``t`` is time too).
- ``channel: <index>`` counts every channel of the file from 0, in file order, as the
  error messages list them.
- ``response.channels`` names several response channels; each must be in the file, once,
  with as many samples and the same sample interval as the others.
- Without ``response.channel`` the response is the one response channel of the file; when
  there is none, the one channel with no role (a plain MAT file of ``t`` and ``x``).
  Without ``force.channel`` the force is the one force channel, if any (as in ASCII, a
  force channel is read even when campaign.yaml has no ``force``).
- Unit labels that say nothing (empty, ``NONE``, ``-``) count as absent.
- A start time below zero (half a sample or more) is the pre-trigger; a start time at or
  after zero says nothing about it, and campaign.yaml's ``pretrigger_samples`` applies.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from workflow.io import units
from workflow.io.campaign import force_unit, response_units
from workflow.io.limits import magnitude_problem, name_length_problem, quoted, shortened
from workflow.io.record_rules import column_role, first_bad_time_step, rates_agree
from workflow.io.recording_time import iso_text
from workflow.io.records import MIN_SAMPLES, CampaignFormatError, ResponseChannel, RunRecord

if TYPE_CHECKING:
    from workflow.io.campaign import Campaign

__all__ = [
    "Channel",
    "FileChannels",
    "unit_label",
    "channel_role",
    "describe_channels",
    "assemble_record",
    "LISTED_CHANNELS",
]

LISTED_CHANNELS: int = 32
"""Most channels an error message lists (a file may hold thousands)."""

_EMPTY_UNIT_LABELS = {"", "none", "-", "n/a", "unknown", "eu"}
_TIME_UNITS_S = {"s": 1.0, "sec": 1.0, "ms": 1e-3}


@dataclass(frozen=True, eq=False)
class Channel:
    """One channel of a system-format file, as the file records it.

    Attributes
    ----------
    name : str
        The name ``channel:`` in campaign.yaml refers to (variable name, Test.Lab
        ``function_record.name``, UFF58 ID line, TDMS ``group/channel``).
    values : ndarray or None
        The samples, in ``unit``; None when the reader reads them on demand (``load``).
    record : str
        How error messages name the channel's place in the file, e.g. ``variable 'x'``.
    unit : str or None
        Unit label as written in the file.
    sample_interval_s : float or None
        Time between samples in s, when the file records it.
    interval_source : str or None
        Where in the file the sample interval is, for messages.
    start_s : float or None
        Time of the first sample in s (negative: samples before the trigger).
    role : str or None
        ``time``, ``force`` or ``response`` when the file labels it so.
    aliases : tuple of str
        Other names that select the channel (a TDMS channel's bare name).
    role_name : str or None
        The name the ASCII column rules read for the role, when not ``name`` (Test.Lab
        names start with the function type, ``Time Acc1:+X``, which is not a time vector).
    record_start : datetime or None
        Wall-clock time the recording started, as the file states it (aware when the
        file gives the time zone).
    load : callable or None
        Reads the samples from the file, for a channel whose ``values`` are None: a MAT
        file's variables are decompressed only when a channel the run uses needs them.
    """

    name: str
    values: NDArray[np.float64]
    record: str
    unit: str | None = None
    sample_interval_s: float | None = None
    interval_source: str | None = None
    start_s: float | None = None
    role: str | None = None
    aliases: tuple[str, ...] = ()
    role_name: str | None = None
    record_start: datetime | None = None
    load: Callable[[], NDArray] | None = None

    def samples(self) -> NDArray:
        """The samples: ``values``, or ``load()``'s, read once."""
        if self.values is not None:
            return self.values
        if "_loaded" not in self.__dict__:
            object.__setattr__(self, "_loaded", self.load())
        return self.__dict__["_loaded"]


@dataclass(frozen=True)
class FileChannels:
    """Every channel of one file, in file order, and the format's name."""

    format_name: str
    channels: list[Channel]


def unit_label(unit: str | None) -> str | None:
    """The unit label, or None for labels that say nothing (``NONE``, empty)."""
    if unit is None or unit.strip().lower() in _EMPTY_UNIT_LABELS:
        return None
    return unit.strip()


def channel_role(channel: Channel) -> str | None:
    """time, force, response or None: the file's label, else the unit, else the name."""
    if channel.role is not None:
        return channel.role
    unit = unit_label(channel.unit)
    if unit is not None:
        canonical = units.normalize_unit(unit)
        if canonical in units.known_units("force"):
            return "force"
        if any(canonical in units.known_units(q) for q in units.RESPONSE_QUANTITIES):
            return "response"
        if unit.lower() in _TIME_UNITS_S:
            return "time"
    name = channel.name if channel.role_name is None else channel.role_name
    if name.strip().lower() == "t":
        return "time"
    return column_role(name)


def describe_channels(channels: list[Channel]) -> str:
    """``[0] 't' (s), [1] 'x', ...``: the listing error messages give."""
    parts = []
    for index, channel in enumerate(channels[:LISTED_CHANNELS]):
        unit = unit_label(channel.unit)
        parts.append(f"[{index}] {quoted(channel.name)}" + (f" ({shortened(unit)})" if unit else ""))
    if len(channels) > LISTED_CHANNELS:
        parts.append(f"and {len(channels) - LISTED_CHANNELS} more")
    return ", ".join(parts)


def _by_reference(
    channels: list[Channel], reference: str | int, key: str, shown: str, format_name: str
) -> Channel:
    """The channel that campaign.yaml's ``key`` (a name or a 0-based index) names."""
    if isinstance(reference, int):
        if reference < len(channels):
            return channels[reference]
        raise CampaignFormatError(
            shown,
            None,
            f"campaign.yaml {key}: {reference} but the {format_name} file has {len(channels)} "
            f"channel(s): {describe_channels(channels)}",
        )
    matches = [c for c in channels if c.name == reference]
    matches = matches or [c for c in channels if reference in c.aliases]
    matches = matches or [c for c in channels if c.name.strip().lower() == reference.strip().lower()]
    if len(matches) == 1:
        return matches[0]
    found = "several channels" if matches else "no channel"
    raise CampaignFormatError(
        shown,
        None,
        f"campaign.yaml {key}: {reference!r} matches {found} of the {format_name} file; "
        f"its channels: {describe_channels(channels)}",
    )


def _select_channels(
    file_channels: FileChannels, campaign: Campaign, shown: str
) -> tuple[list[Channel], Channel | None]:
    """The response channels (campaign.yaml's order) and the force channel (or None)."""
    channels, name = file_channels.channels, file_channels.format_name
    if not channels:
        raise CampaignFormatError(shown, None, f"no channels of samples in the {name} file")
    for index, channel in enumerate(channels):
        long_name = name_length_problem(f"channel [{index}]: name", channel.name)
        if long_name is not None:
            raise CampaignFormatError(shown, None, long_name)
    roles = {id(c): channel_role(c) for c in channels}
    force = None
    if campaign.force is not None and campaign.force.channel is not None:
        force = _by_reference(channels, campaign.force.channel, "force.channel", shown, name)
    references = campaign.response.references()
    if references != (None,):
        key = "response.channels" if campaign.response.channels is not None else "response.channel"
        responses = [_by_reference(channels, ref, key, shown, name) for ref in references]
        repeated = [c for i, c in enumerate(responses) if any(c is d for d in responses[:i])]
        if repeated:
            raise CampaignFormatError(
                shown, None, f"campaign.yaml {key} names {repeated[0].record} more than once"
            )
    else:
        others = [c for c in channels if c is not force]
        candidates = [c for c in others if roles[id(c)] == "response"]
        candidates = candidates or [c for c in others if roles[id(c)] is None]
        if len(candidates) != 1:
            raise CampaignFormatError(
                shown,
                None,
                f"{'no' if not candidates else len(candidates)} response channels in the {name} file; "
                "say which one with response: {channel: NAME or INDEX} (or channels: [...] for several) "
                f"in campaign.yaml; its channels: {describe_channels(channels)}",
            )
        responses = candidates
    if force is not None and any(force is c for c in responses):
        raise CampaignFormatError(
            shown, None, f"campaign.yaml names {force.record} as both a response and the force"
        )
    if force is None:
        candidates = [c for c in channels if roles[id(c)] == "force" and not any(c is r for r in responses)]
        if len(candidates) > 1:
            raise CampaignFormatError(
                shown,
                None,
                f"{len(candidates)} force channels in the {name} file; say which one with "
                f"force: {{channel: NAME or INDEX}} in campaign.yaml; its channels: {describe_channels(channels)}",
            )
        force = candidates[0] if candidates else None
    return responses, force


def _checked_samples(channel: Channel, shown: str) -> NDArray[np.float64]:
    """The channel's samples as finite float64; at least MIN_SAMPLES of them."""
    values = np.asarray(channel.samples())
    if values.ndim != 1 or not np.issubdtype(values.dtype, np.number) or np.iscomplexobj(values):
        raise CampaignFormatError(
            shown,
            None,
            f"{channel.record}: not a vector of real numbers (shape {values.shape}, {values.dtype})",
        )
    values = np.ascontiguousarray(values, dtype=np.float64)
    if values.size < MIN_SAMPLES:
        raise CampaignFormatError(
            shown, None, f"{channel.record}: only {values.size} samples; a run needs at least {MIN_SAMPLES}"
        )
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise CampaignFormatError(
            shown, None, f"{channel.record}: NaN/inf value at sample {int(bad[0])} (0-based)"
        )
    return values


def _checked_magnitude(channel: Channel, values: NDArray[np.float64], shown: str) -> NDArray[np.float64]:
    """The samples of a force or response channel, refused when the analysis cannot square
    them (:mod:`workflow.io.limits`), naming the sample."""
    problem = magnitude_problem(values, channel.record)
    if problem is not None:
        raise CampaignFormatError(shown, None, f"{problem[1]} (sample {problem[0]}, 0-based)")
    return values


def _force_factor_lbf(channel: Channel, campaign: Campaign, shown: str) -> float:
    """Factor taking the force channel to lbf: the file's unit, else campaign.yaml's, else lbf."""
    try:
        unit = force_unit(unit_label(channel.unit), campaign, f"{channel.record}: force")
    except ValueError as error:
        raise CampaignFormatError(shown, None, str(error)) from None
    return units.factor_to_internal("force", unit)


def _time_channel(channels: list[Channel], n_samples: int, shown: str) -> Channel | None:
    """The file's time vector (role time, as many samples as the response), if it has one."""
    found = [c for c in channels if channel_role(c) == "time" and np.size(c.samples()) == n_samples]
    return found[0] if found else None


def _rate_from_time(channel: Channel, shown: str) -> tuple[NDArray[np.float64], float]:
    """Time vector in s and the sample rate it implies; it must increase in uniform steps."""
    factor_s = _TIME_UNITS_S.get((unit_label(channel.unit) or "s").lower())
    if factor_s is None:
        raise CampaignFormatError(
            shown, None, f"{channel.record}: time unit {channel.unit!r}: expected s or ms"
        )
    time_s = np.ascontiguousarray(np.asarray(channel.samples(), dtype=np.float64).ravel() * factor_s)
    steps = np.diff(time_s)
    bad = first_bad_time_step(steps)
    if bad is not None:
        i, typical_s = bad
        raise CampaignFormatError(
            shown,
            None,
            f"{channel.record}: time not increasing in uniform steps: step {steps[i]:.6g} s after "
            f"sample {i} (0-based), typical step {typical_s:.6g} s",
        )
    return time_s, (time_s.size - 1) / (time_s[-1] - time_s[0])


def assemble_record(file_channels: FileChannels, relative: str, shown: str, campaign: Campaign) -> RunRecord:
    """The run record of a system-format file, checked against campaign.yaml.

    Parameters
    ----------
    file_channels : FileChannels
        What the format reader found in the file.
    relative : str
        The file's path relative to the campaign folder.
    shown : str
        The path used in error messages.
    campaign : Campaign
        The validated campaign.yaml.

    Returns
    -------
    RunRecord
        Response in the campaign's response unit, force in lbf.

    Raises
    ------
    CampaignFormatError
        Ambiguous or missing channel, too few or non-finite samples, channels of different
        lengths or sample intervals, a missing sample interval, a unit or sample rate or
        pre-trigger that contradicts campaign.yaml.
    """
    selected, force = _select_channels(file_channels, campaign, shown)
    response = selected[0]
    # every channel read has as many samples as the first response channel
    samples = {
        id(c): _checked_magnitude(c, _checked_samples(c, shown), shown)
        for c in (*selected, force)
        if c is not None
    }
    n_samples = samples[id(response)].size
    for channel in (*selected, force):
        if channel is not None and samples[id(channel)].size != n_samples:
            raise CampaignFormatError(
                shown,
                None,
                f"{channel.record} has {samples[id(channel)].size} samples but {response.record} has {n_samples}",
            )
    names = campaign.response.channel_names()
    try:
        found, refusals = response_units(
            [unit_label(channel.unit) for channel in selected], campaign, [c.record for c in selected]
        )
    except ValueError as error:
        raise CampaignFormatError(shown, None, str(error)) from None
    responses = [
        ResponseChannel(name, samples[id(channel)], unit, channel.name)
        for name, channel, unit in zip(names, selected, found)
        if unit is not None
    ]
    force_lbf = None
    if force is not None:
        force_values = samples[id(force)]
        force_lbf = force_values * _force_factor_lbf(force, campaign, shown)

    # Sample rate: campaign.yaml, the file's sample interval, the file's time vector;
    # every source present must agree.
    sources: list[tuple[str, float]] = []
    if campaign.sample_rate_hz is not None:
        sources.append(("campaign.yaml sample_rate_hz", campaign.sample_rate_hz))
    start_s = response.start_s
    for channel in (*selected, force):
        if channel is not None and channel.sample_interval_s is not None:
            if not channel.sample_interval_s > 0:
                raise CampaignFormatError(
                    shown,
                    None,
                    f"{channel.record}: sample interval {channel.sample_interval_s!r} s "
                    f"({channel.interval_source}) is not positive",
                )
            sources.append(
                (f"{channel.interval_source} of {channel.record}", 1.0 / channel.sample_interval_s)
            )
    time_channel = _time_channel(file_channels.channels, n_samples, shown)
    time_s = None
    if time_channel is not None:
        _checked_samples(time_channel, shown)
        time_s, rate_hz = _rate_from_time(time_channel, shown)
        sources.append((time_channel.record, rate_hz))
        start_s = time_s[0] if start_s is None else start_s
    if not sources:
        raise CampaignFormatError(
            shown,
            None,
            f"sample interval missing: {response.record} records none, the file has no time "
            "vector and campaign.yaml has no sample_rate_hz",
        )
    for i, (name_a, rate_a) in enumerate(sources):
        for name_b, rate_b in sources[i + 1 :]:
            if not rates_agree(rate_a, rate_b):
                raise CampaignFormatError(
                    shown,
                    None,
                    f"sample rate {rate_b:.9g} Hz from the {name_b} disagrees with {rate_a:.9g} Hz "
                    f"from the {name_a}",
                )
    sample_rate_hz = sources[0][1]
    sample_rate_source = "campaign.yaml" if sources[0][0].startswith("campaign") else "file"

    pretrigger_samples, pretrigger_source = campaign.pretrigger_samples, "default"
    if campaign.pretrigger_given:
        pretrigger_source = "campaign.yaml"
    if start_s is not None and start_s * sample_rate_hz <= -0.5:
        file_pretrigger = int(round(-start_s * sample_rate_hz))
        if campaign.pretrigger_given and file_pretrigger != campaign.pretrigger_samples:
            raise CampaignFormatError(
                shown,
                None,
                f"{response.record}: start time {start_s:.9g} s means a pre-trigger of "
                f"{file_pretrigger} samples, but campaign.yaml says pretrigger_samples "
                f"{campaign.pretrigger_samples}",
            )
        pretrigger_samples, pretrigger_source = file_pretrigger, pretrigger_source.replace("default", "file")
    if pretrigger_samples >= n_samples:
        raise CampaignFormatError(
            shown,
            None,
            f"pre-trigger of {pretrigger_samples} samples is not shorter than {response.record} "
            f"({n_samples} samples)",
        )

    record_start = response.record_start or (force.record_start if force is not None else None)
    header = {"format": file_channels.format_name, "response channel": response.name}
    if len(selected) > 1:
        header["response channels"] = ", ".join(channel.name for channel in selected)
    if force is not None:
        header["force channel"] = force.name
    if start_s is not None:
        header["start time (s)"] = f"{start_s:.9g}"
    return RunRecord(
        path=relative,
        sample_rate_hz=float(sample_rate_hz),
        pretrigger_samples=int(pretrigger_samples),
        time_s=time_s,
        force_lbf=None if force_lbf is None else np.ascontiguousarray(force_lbf),
        response=responses[0].values,
        response_quantity=responses[0].quantity,
        response_unit=responses[0].unit,
        header=header,
        n_samples=int(n_samples),
        column_names=tuple(c.name for c in file_channels.channels),
        sample_rate_source=sample_rate_source,
        pretrigger_source=pretrigger_source,
        record_start=iso_text(record_start),
        responses=tuple(responses),
        refused_channels=tuple((name, why) for name, why in zip(names, refusals) if why is not None),
    )
