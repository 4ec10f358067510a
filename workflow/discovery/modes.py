"""Several modes and several sensors of one hit in results/diagnosis.json.

Each (mode, channel) is diagnosed on its own, exactly as a one-mode, one-channel campaign
(:func:`diagnosed_outcome`). A configuration's verdict for a mode then uses every channel
(:func:`combine_channels`): the cause is the one most channels name (ties: the higher mean
confidence), its confidence the mean of the channels' confidences, and the rest of the
entry (baseline, extended model, gain, evidence) is that of the channel most confident
in that cause; each channel's own verdict goes under ``channels``. The campaign's cause
for a mode is :func:`~workflow.discovery.campaign.campaign_verdict` of the combined
configuration causes. This is a combination of per-channel diagnoses, not one fit to the
pooled channels.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from workflow.discovery.campaign import campaign_fit_context, campaign_verdict
from workflow.discovery.configuration import diagnose_configuration_segments, record_starts
from workflow.discovery.diagnosis_files import DiagnosedConfiguration

__all__ = ["diagnosed_outcome", "combine_channels", "mode_document", "with_modes"]

NOT_DIAGNOSED = (
    "no kept segment: every run excluded (runs.parquet) or every segment rejected (segments_rejected.parquet)"
)


def diagnosed_outcome(segments, runs, configuration: str, **options) -> DiagnosedConfiguration:
    """One configuration's diagnosis from the segments of one mode and channel of every
    configuration (their fit context is the campaign's), or why it was not diagnosed.

    ``options`` go to :func:`~workflow.discovery.configuration.diagnose_configuration_segments`
    (``response_quantity``, ``settings``, ``segment_cycles``).
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


def _mean_confidence(confidences: list[Mapping[str, float]]) -> dict[str, float]:
    causes = list(dict.fromkeys(cause for confidence in confidences for cause in confidence))
    mean = {cause: float(np.mean([c.get(cause, 0.0) for c in confidences])) for cause in causes}
    return dict(sorted(mean.items(), key=lambda item: -item[1]))


def combine_channels(entries: Mapping[str, dict]) -> dict:
    """One configuration's entry for a mode from its channels' entries (channel -> the
    configuration's entry of that channel's document), in campaign.yaml's channel order.

    With one channel the entry is returned unchanged (no ``channels`` key)."""
    if len(entries) == 1:
        return next(iter(entries.values()))
    named: dict[str, list[str]] = {}
    for channel, entry in entries.items():
        named.setdefault(entry["cause"], []).append(channel)

    def mean_own(cause: str) -> float:
        return float(np.mean([entries[c]["confidence"].get(cause, 0.0) for c in named[cause]]))

    cause = max(named, key=lambda c: (len(named[c]), mean_own(c)))
    source = max(named[cause], key=lambda c: entries[c]["confidence"].get(cause, 0.0))
    combined = dict(entries[source])
    combined["confidence"] = _mean_confidence([entry["confidence"] for entry in entries.values()])
    combined["channels"] = {
        channel: {
            "cause": entry["cause"],
            "confidence": entry["confidence"],
            "gain": {"ratio": entry["gain"]["ratio"]},
        }
        for channel, entry in entries.items()
    }
    combined["channel_combination"] = (
        f"each channel diagnosed on its own; cause named by {len(named[cause])} of {len(entries)} channels, "
        f"confidence the channels' mean, the rest from channel {source!r}"
    )
    return combined


def mode_document(mode_hz: float | None, documents: Mapping[str, dict]) -> dict:
    """The ``modes`` entry of one mode from the campaign documents of its channels
    (channel -> :func:`~workflow.discovery.campaign.campaign_document`), in campaign.yaml's
    channel order; with one channel that document with ``mode_hz`` (None when no
    configuration has a mode: every configuration is then skipped)."""
    first = next(iter(documents.values()))
    if len(documents) == 1:
        return {"mode_hz": mode_hz, **first}
    names = list(
        dict.fromkeys(name for document in documents.values() for name in document["configurations"])
    )
    configurations = {
        name: combine_channels(
            {
                channel: document["configurations"][name]
                for channel, document in documents.items()
                if name in document["configurations"]
            }
        )
        for name in names
    }
    cause = campaign_verdict(
        [entry["cause"] for entry in configurations.values()],
        [entry["gain"]["ratio"] for entry in configurations.values()],
    )
    return {
        "mode_hz": mode_hz,
        **first,
        "cause": cause,
        "confidence": _mean_confidence([document["confidence"] for document in documents.values()]),
        "configurations": configurations,
    }


def with_modes(modes: list[dict]) -> dict:
    """results/diagnosis.json: the first mode's document at the top (one-mode readers keep
    working) and every mode's under ``modes``."""
    top = {key: value for key, value in modes[0].items() if key != "mode_hz"}
    return {**top, "modes": modes}
