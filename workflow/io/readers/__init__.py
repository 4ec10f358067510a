"""Readers of the files that acquisition systems write (campaign-format.md, "System formats").

Each format module turns one file into :class:`~workflow.io.readers.channels.Channel`
objects (samples plus whatever the file records: unit, sample interval, start time);
:func:`~workflow.io.readers.channels.assemble_record` then picks the response and force
channels and checks them against campaign.yaml exactly as the ASCII reader does, so every
format gives the same :class:`~workflow.io.records.RunRecord`.

The format libraries (scipy.io, h5py, pyuff, npTDMS) are imported only by the reader of a
file that needs them, so a job reading ASCII runs never loads them.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from workflow.io.campaign import Campaign
    from workflow.io.records import RunRecord


__all__ = [
    "read_system_run",
]


def read_system_run(full_path: Path, relative: str, shown: str, campaign: Campaign) -> RunRecord:
    """Read one run file written by an acquisition system.

    Parameters
    ----------
    full_path : Path
        The file.
    relative : str
        Its path relative to the campaign folder (the record's ``path``).
    shown : str
        The path used in error messages.
    campaign : Campaign
        The validated campaign.yaml.

    Returns
    -------
    RunRecord
        Response in the campaign's unit, force in lbf.

    Raises
    ------
    CampaignFormatError
        Unreadable, truncated or mislabelled file, ambiguous or missing channel, missing
        sample interval, disagreement with campaign.yaml; the message names the file, the
        record or variable and the problem.
    """
    from workflow.io.readers.channels import assemble_record
    from workflow.io.records import CampaignFormatError

    suffix = full_path.suffix.lower()
    if suffix == ".mat":
        from workflow.io.readers.mat import read_mat_channels as read_channels
    elif suffix in (".uff", ".unv"):
        from workflow.io.readers.uff import read_uff_channels as read_channels
    elif suffix == ".tdms":
        from workflow.io.readers.tdms import read_tdms_channels as read_channels
    else:
        raise ValueError(f"{shown}: no system-format reader for extension {suffix!r}")
    if full_path.stat().st_size == 0:
        raise CampaignFormatError(shown, None, "the file is empty")
    file_channels = read_channels(full_path, shown)
    return assemble_record(file_channels, relative, shown, campaign)
