"""Checks of a campaign's paths before they are opened: links that leave the campaign
folder, files that are not regular or cannot be read (docs/input-safety.md).
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

from workflow.io import limits

__all__ = [
    "link_problem",
    "unreadable_reason",
]


def link_problem(path: Path, root_resolved: Path) -> str | None:
    """Why a path inside the campaign folder leads elsewhere (a symbolic link out of the
    folder, or a loop of links), or None. The test is on the real path, all links resolved."""
    try:
        path.stat()
    except OSError as error:
        if error.errno == errno.ELOOP:
            return "not read: a symbolic link loop (the link leads back to itself)"
    try:
        resolved = path.resolve()
    except (OSError, RuntimeError):  # a loop further up the path
        return "not read: a symbolic link loop (the link leads back to itself)"
    if not resolved.is_relative_to(root_resolved):
        return "not read: a symbolic link that leads outside the campaign folder (docs/input-safety.md)"
    return None


def unreadable_reason(path: Path, root_resolved: Path) -> str | None:
    """Why a path matched by a glob is not read as a run file, or None."""
    link = link_problem(path, root_resolved)
    if link is not None:
        return link
    if path.is_dir():
        return "not read: a directory, not a run file"
    if not path.is_file():
        return "not read: not a regular file (a broken link, a device or a pipe)"
    if not os.access(path, os.R_OK):
        return "not read: permission denied (the file cannot be opened for reading)"
    size_bytes = path.stat().st_size
    if size_bytes > limits.MAX_RUN_FILE_BYTES:
        return (
            f"not read: {size_bytes} bytes, larger than a run file may be "
            f"({limits.MAX_RUN_FILE_BYTES} bytes; docs/input-safety.md): cut the record "
            "to the ring-down or export fewer channels"
        )
    return None
