"""Diagnosis harness: the campaign document together with the per-configuration details."""

from __future__ import annotations

import pandas as pd

from workflow.discovery.campaign import campaign_document, diagnose_configurations
from workflow.discovery.configuration import ConfigurationDiagnosis


def diagnose_with_details(
    segments: pd.DataFrame, campaign_name: str, **options
) -> tuple[dict, dict[str, ConfigurationDiagnosis]]:
    """``results/diagnosis.json``'s document of a campaign diagnosed in one process, and
    every configuration's :class:`ConfigurationDiagnosis` (fits, data, residuals) behind it.

    ``options`` are those of :func:`workflow.discovery.campaign.diagnose_configurations`.
    """
    context, diagnoses, skipped = diagnose_configurations(segments, **options)
    return campaign_document(campaign_name, context, diagnoses, skipped), diagnoses
