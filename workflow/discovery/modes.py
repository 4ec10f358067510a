"""Several modes and several sensors of one hit in results/diagnosis.json.

Each (mode, channel) is diagnosed on its own, exactly as a one-mode, one-channel campaign
(:func:`diagnosed_outcome`). With several channels a configuration's verdict for a mode
is one joint analysis of every channel's segments (:func:`joint_outcome`,
:mod:`workflow.discovery.joint`: shared joint physics and run offsets, each channel on
the reference channel's amplitude scale with its own scatter, the same runs held out on
every channel), and each channel's own verdict goes under ``channels`` as a consistency
check (:func:`with_channels`). Nothing is voted or averaged across channels.
"""

from __future__ import annotations

from collections.abc import Mapping

from workflow.discovery.campaign import campaign_fit_context
from workflow.discovery.configuration import diagnose_configuration_segments, record_starts
from workflow.discovery.diagnosis_files import DiagnosedConfiguration
from workflow.discovery.joint import joint_segments

__all__ = ["diagnosed_outcome", "joint_outcome", "with_channels", "mode_document", "with_modes"]

NOT_DIAGNOSED = (
    "no kept segment: every run excluded (runs.parquet) or every segment rejected (segments_rejected.parquet)"
)


def diagnosed_outcome(segments, runs, configuration: str, **options) -> DiagnosedConfiguration:
    """One configuration's diagnosis from the segments of one mode and channel of every
    configuration (their fit context is the campaign's), or why it was not diagnosed.

    ``options`` go to :func:`~workflow.discovery.configuration.diagnose_configuration_segments`
    (``response_quantity``, ``settings``, ``segment_cycles``, ``segment_overlap``).
    """
    context = campaign_fit_context(segments)
    rows = (segments["configuration"].astype(str) == configuration).to_numpy().nonzero()[0]
    diagnosis, skipped = None, NOT_DIAGNOSED
    if rows.size:
        result = diagnose_configuration_segments(
            segments, configuration, context, record_start=record_starts(runs, configuration), **options
        )
        diagnosis, skipped = (None, result) if isinstance(result, str) else (result, "")
    return DiagnosedConfiguration(
        configuration, int(rows[0]) if rows.size else -1, context.reference_velocity_in_s, diagnosis, skipped
    )


JOINT_RULE = (
    "every channel's segments in one analysis: one fit of the joint's physics and the run offsets, "
    "each channel's amplitudes on the reference channel's scale (median ratio of the envelopes at "
    "the same instants of the same run) and its own scatter, the same runs held out on every channel"
)


def joint_outcome(segments, runs, configuration: str, **options) -> DiagnosedConfiguration:
    """:func:`diagnosed_outcome` of the segments of one mode seen by every channel, pooled
    by :func:`~workflow.discovery.joint.joint_segments`; the diagnosis's document says how
    (``joint``: the reference channel, each channel's amplitude factor, the channels left
    out, the rule)."""
    pooled, joint = joint_segments(segments)
    outcome = diagnosed_outcome(pooled, runs, configuration, **options)
    if outcome.diagnosis is not None:
        outcome.diagnosis.document["joint"] = {**joint[configuration], "rule": JOINT_RULE}
    return outcome


def with_channels(joint: dict, entries: Mapping[str, dict]) -> dict:
    """One configuration's entry for a mode: the joint analysis's (``joint``), with each
    channel's own verdict (channel -> that channel's entry, campaign.yaml's order) under
    ``channels``."""
    return {
        **joint,
        "channels": {
            channel: {
                "cause": entry["cause"],
                "causes": entry.get("causes") or [entry["cause"]],
                "confidence": entry["confidence"],
                "gain": {"ratio": entry["gain"]["ratio"]},
            }
            for channel, entry in entries.items()
        },
    }


def mode_document(mode_hz: float | None, documents: Mapping[str, dict], joint: dict | None = None) -> dict:
    """The ``modes`` entry of one mode from the campaign documents of its channels
    (channel -> :func:`~workflow.discovery.campaign.campaign_document`, campaign.yaml's
    channel order) and, with several channels, of their joint analysis (``joint``, from
    :func:`joint_outcome`'s diagnoses): the joint document, each configuration with its
    channels' verdicts (:func:`with_channels`). With one channel its document with
    ``mode_hz`` (None when no configuration has a mode: every configuration is then
    skipped)."""
    if len(documents) == 1 or joint is None:
        return {"mode_hz": mode_hz, **next(iter(documents.values()))}
    configurations = {
        name: with_channels(
            entry,
            {
                channel: document["configurations"][name]
                for channel, document in documents.items()
                if name in document["configurations"]
            },
        )
        for name, entry in joint["configurations"].items()
    }
    return {"mode_hz": mode_hz, **joint, "configurations": configurations}


def with_modes(modes: list[dict]) -> dict:
    """results/diagnosis.json: the first mode's document at the top (one-mode readers keep
    working) and every mode's under ``modes``."""
    top = {key: value for key, value in modes[0].items() if key != "mode_hz"}
    return {**top, "modes": modes}
