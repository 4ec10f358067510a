"""One verdict from every sensor: the segments of all response channels of one mode pooled
into one analysis of the joint.

Every channel of a hit measures the same modal decay: the same damping and frequency at
the same instant, its velocity amplitude the modal amplitude times the channel's
mode-shape value (and its unit). The joint's physics is a function of the modal
amplitude, so each channel's amplitudes are put on one channel's scale by a factor
estimated from the data (:func:`channel_scales`): within one run, the ratio of two
channels' envelope amplitudes at the same instants is the ratio of their mode-shape
values. The pooled segments keep their real runs (the run offsets and the held-out runs
are shared by every channel) and their channel (each channel has its own scatter,
:func:`workflow.models.configuration_data.scatter_of`), and the existing decision and
confidence run once on them (docs/discovery.md, "Several sensors: one joint analysis").
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["reference_channel", "channel_scales", "joint_segments"]


def reference_channel(segments: pd.DataFrame) -> str:
    """The channel whose amplitude scale the pooled segments take: the one that sees the
    mode largest (median velocity amplitude over every configuration; ties by name), so
    that the choice does not depend on the order the channels are listed in."""
    median = segments.groupby(segments["channel"].astype(str))["velocity_amplitude_in_s"].median()
    return str(max(sorted(median.index), key=lambda channel: median[channel]))


def _log_ratios(reference: pd.DataFrame, other: pd.DataFrame) -> np.ndarray:
    """``ln(V_other / V_reference)`` at the reference's segment times within the time both
    channels cover, over every run they share (``t_s``, ``velocity_amplitude_in_s``)."""
    ratios = []
    for run, mine in reference.groupby("run"):
        theirs = other[other["run"] == run].sort_values("t_s")
        if len(theirs) < 2:
            continue
        t, v = theirs["t_s"].to_numpy(float), theirs["velocity_amplitude_in_s"].to_numpy(float)
        at = mine["t_s"].to_numpy(float)
        inside = (at >= t[0]) & (at <= t[-1])
        ratios.append(
            np.interp(at[inside], t, np.log(v))
            - np.log(mine["velocity_amplitude_in_s"].to_numpy(float)[inside])
        )
    return np.concatenate(ratios) if ratios else np.empty(0)


def channel_scales(segments: pd.DataFrame, reference: str) -> dict[str, float]:
    """Per channel, the factor that puts its velocity amplitudes on the reference
    channel's scale (the reference's mode-shape value over the channel's).

    Parameters
    ----------
    segments : DataFrame
        One configuration's segments of one mode, every channel: ``channel``, ``run``,
        ``t_s`` (s from the record's start), ``velocity_amplitude_in_s``.
    reference : str
        :func:`reference_channel`.

    Returns
    -------
    dict
        Channel -> factor (1 for the reference): the inverse of the median over every
        shared run and instant of the ratio of the channel's envelope amplitude to the
        reference's (a robust median: noise and the decay start of a weak channel move
        a few instants, not the ratio). A channel sharing no instant of any run with the
        reference is left out.
    """
    channel = segments["channel"].astype(str)
    mine = segments[channel == reference]
    scales = {}
    for name in sorted(set(channel)):
        if name == reference:
            scales[name] = 1.0
            continue
        log_ratio = _log_ratios(mine, segments[channel == name])
        if log_ratio.size:
            scales[name] = float(np.exp(-np.median(log_ratio)))
    return scales


def joint_segments(segments: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, dict]]:
    """Every channel's segments of one mode as one configuration's pooled segments.

    Parameters
    ----------
    segments : DataFrame
        The kept segments of one mode, every channel (results/tables/segments.parquet
        rows of one ``mode_hz``).

    Returns
    -------
    pooled : DataFrame
        The rows of every channel that shares instants with the reference channel,
        ordered by configuration, run, channel name and time, with
        ``velocity_amplitude_in_s`` on the reference channel's scale and an integer
        ``channel_index`` (channels by name).
    joint : dict
        Per configuration: ``reference_channel`` (the campaign's, :func:`reference_channel`;
        where it has no segment of the configuration, the configuration's own),
        ``amplitude_factors`` (channel -> factor, :func:`channel_scales`) and ``left_out``
        (channels sharing no instant with the reference: not pooled).
    """
    reference = reference_channel(segments)
    frames, joint = [], {}
    for configuration, rows in segments.groupby(segments["configuration"].astype(str), sort=False):
        channel = rows["channel"].astype(str)
        own = reference if reference in set(channel) else reference_channel(rows)
        factors = channel_scales(rows, own)
        joint[configuration] = {
            "reference_channel": own,
            "amplitude_factors": factors,
            "left_out": sorted(set(channel) - set(factors)),
        }
        kept = rows[channel.isin(list(factors))].copy()
        kept["velocity_amplitude_in_s"] *= kept["channel"].astype(str).map(factors).to_numpy(float)
        frames.append(kept)
    pooled = pd.concat(frames) if frames else segments.iloc[:0].copy()
    names = sorted(set(pooled["channel"].astype(str)))
    configuration_order = {c: i for i, c in enumerate(dict.fromkeys(segments["configuration"].astype(str)))}
    pooled = pooled.assign(
        channel_index=pooled["channel"].astype(str).map({n: i for i, n in enumerate(names)}),
        _channel=pooled["channel"].astype(str),
        _configuration=pooled["configuration"].astype(str).map(configuration_order),
    )
    pooled = pooled.sort_values(["_configuration", "run", "_channel", "t_s"], kind="stable")
    return pooled.drop(columns=["_channel", "_configuration"]).reset_index(drop=True), joint
