"""Diagnosis harness: the campaign document together with the per-configuration details."""

from __future__ import annotations

import numpy as np
import pandas as pd

from workflow.discovery.campaign import campaign_document, diagnose_configurations
from workflow.discovery.configuration import ConfigurationDiagnosis
from workflow.models.configuration_data import ConfigurationData


def diagnose_with_details(
    segments: pd.DataFrame, campaign_name: str, **options
) -> tuple[dict, dict[str, ConfigurationDiagnosis]]:
    """``results/diagnosis.json``'s document of a campaign diagnosed in one process, and
    every configuration's :class:`ConfigurationDiagnosis` (fits, data, residuals) behind it.

    ``options`` are those of :func:`workflow.discovery.campaign.diagnose_configurations`.
    """
    context, diagnoses, skipped = diagnose_configurations(segments, **options)
    return campaign_document(campaign_name, context, diagnoses, skipped), diagnoses


def segments_data(velocity_in_s, run_index, anchor_velocity_in_s: float, channel_index=None):
    """A configuration's segments at the given amplitudes and runs (damping 1e-3,
    frequency 100 Hz: the statistics under test take their residuals elsewhere)."""
    velocity = np.asarray(velocity_in_s, dtype=float)
    runs = np.asarray(run_index)
    ones = np.ones(velocity.size)
    return ConfigurationData(
        "c",
        velocity,
        1e-3 * ones,
        100.0 * ones,
        runs,
        [f"run{r + 1:02d}" for r in range(int(runs.max()) + 1)],
        1.0,
        anchor_velocity_in_s=anchor_velocity_in_s,
        channel_index=channel_index,
    )
