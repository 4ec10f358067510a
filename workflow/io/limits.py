"""Bounds on what a campaign may hand the workflow: name lengths, sample magnitudes, and
how much of an untrusted text an error message quotes (docs/input-safety.md).

Campaign folders come from outside the project; these bounds keep one hostile file from
costing minutes and gigabytes, overflowing the arithmetic, or flooding a message.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "MAX_NAME_CHARACTERS",
    "MAX_CAMPAIGN_NAME_CHARACTERS",
    "QUOTED_CHARACTERS",
    "MAX_QUOTED_PROBLEMS",
    "MAX_SAMPLE_MAGNITUDE",
    "MIN_PEAK_MAGNITUDE",
    "MAX_RUN_FILE_BYTES",
    "shortened",
    "quoted",
    "name_length_problem",
    "magnitude_problem",
]

MAX_NAME_CHARACTERS: int = 255
"""Longest campaign name, run name or channel name. 255 is NAME_MAX, the longest file or
folder name POSIX file systems (255 bytes) and NTFS (255 UTF-16 units) allow: a campaign's
default name is its folder's name and a run's name is its file's name, so every name a
real campaign gives fits. Names are shown in figure titles, legends and table cells; a
100 kB name made one figure job take 74 s and 3.7 GB."""

MAX_CAMPAIGN_NAME_CHARACTERS: int = 1000
"""Longest campaign name (campaign.yaml's free-text ``name``): a title of a dozen lines.
Every page and the summary show a text of up to 2000 characters whole
(:data:`workflow.io.escape.DISPLAY_LIMIT`), so the name is never cut; a 100 kB
name made one figure job take 74 s and 3.7 GB. Names that are file names (run files,
channels, the default campaign name: its folder's) keep :data:`MAX_NAME_CHARACTERS`."""

QUOTED_CHARACTERS: int = 60
"""Most characters of an untrusted text (a name, a YAML key) an error message quotes."""

MAX_QUOTED_PROBLEMS: int = 10
"""Most problems of one file an error message lists (the rest are counted)."""

MAX_SAMPLE_MAGNITUDE: float = 1e100
"""Largest magnitude of a force or response sample. The analysis squares samples and sums
the squares (energies, spectral power ``|X|**2`` of an FFT, whose bins sum up to N
samples, and force x response cross-spectra, summed over runs). float64 holds up to
1.8e308: with N up to 1e9 samples and unit factors up to 1e3, ``(1e9 * 1e3 * 1e100)**2``
is 1e224, which leaves 84 decades for sums over runs and intermediate products. No
measurement in any unit of the contract comes near 1e100; a file that does would turn
the spectra into inf and NaN."""

MAX_RUN_FILE_BYTES: int = 1_000_000_000
"""Largest run file read (1 GB). A job holds about 2.3 times an ASCII file's size while
reading it (measured: 113 MB of text, 3 million rows, peak 326 MB) and more while
analysing it; a hammer ring-down of 3 channels at 51.2 kHz for 60 s is about 0.11 GB of text.
A larger file (a hostile or mistaken one: a sparse file reads as gigabytes of zeros)
would exhaust the machine and stop every other job with it."""

MIN_PEAK_MAGNITUDE: float = 1e-100
"""Smallest peak magnitude of a channel that is not zero throughout: the squares of
smaller samples (below 1e-200) sum in the subnormal range of float64 (below 2.2e-308
lies 0), where the spectra lose their digits or vanish."""


def shortened(text: str, limit: int = QUOTED_CHARACTERS) -> str:
    """An untrusted text cut to ``limit`` characters with its length said (unquoted:
    a YAML key path, a message that quotes a value)."""
    return text if len(text) <= limit else f"{text[:limit]}… ({len(text)} characters)"


def quoted(text: str, limit: int = QUOTED_CHARACTERS) -> str:
    """``repr`` of an untrusted text, cut to ``limit`` characters with its length said.

    Parameters
    ----------
    text : str
        A name, key or line from a campaign.
    limit : int, optional
        Characters kept.

    Returns
    -------
    str
        ``'abc'`` for a short text, ``'abc…' (100000 characters)`` for a long one.

    Examples
    --------
    >>> quoted("Force (lbf)")
    "'Force (lbf)'"
    >>> quoted("x" * 100, limit=5)
    "'xxxxx…' (100 characters)"
    """
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit] + '…'!r} ({len(text)} characters)"


def name_length_problem(what: str, name: str, limit: int | None = None) -> str | None:
    """What is wrong with the length of a name, or None.

    Parameters
    ----------
    what : str
        What the name names, for the message (``"run file name"``).
    name : str
        The name.
    limit : int, optional
        Most characters: :data:`MAX_NAME_CHARACTERS` (a file name's bound) unless given.
    """
    limit = MAX_NAME_CHARACTERS if limit is None else limit
    if len(name) <= limit:
        return None
    why = (
        "the longest file name a file system allows"
        if limit == MAX_NAME_CHARACTERS
        else "a title of a dozen lines"
    )
    return f"{what} {quoted(name)} is too long: at most {limit} characters ({why})"


def magnitude_problem(values: NDArray[np.float64], what: str) -> tuple[int, str] | None:
    """The first sample whose magnitude the analysis cannot square, or None.

    Parameters
    ----------
    values : ndarray
        Finite samples of one channel.
    what : str
        The channel, for the message (``"column 3 (Acceleration (g))"``).

    Returns
    -------
    (index, problem) or None
        0-based index of the first sample beyond :data:`MAX_SAMPLE_MAGNITUDE` (or, for a
        channel whose peak is below :data:`MIN_PEAK_MAGNITUDE` but not zero, of its
        peak) and the problem in words.

    Examples
    --------
    >>> index, problem = magnitude_problem(np.array([0.0, 1.5, -3e160]), "response")
    >>> index, problem[:50]
    (2, 'response: value -3e+160 is beyond ±1e+100: its squ')
    >>> magnitude_problem(np.array([0.0, 1.5, -3.0]), "response") is None
    True
    """
    if values.size == 0:
        return None
    magnitude = np.abs(values)
    beyond = np.flatnonzero(magnitude > MAX_SAMPLE_MAGNITUDE)
    if beyond.size:
        index = int(beyond[0])
        return index, (
            f"{what}: value {values[index]:.6g} is beyond ±{MAX_SAMPLE_MAGNITUDE:.0e}: its square would "
            "overflow the analysis (energies, spectral power); check the file's unit and scaling"
        )
    peak = int(np.argmax(magnitude))
    if 0.0 < magnitude[peak] < MIN_PEAK_MAGNITUDE:
        return peak, (
            f"{what}: its largest value {values[peak]:.6g} is below {MIN_PEAK_MAGNITUDE:.0e}: its square "
            "would underflow the analysis (energies, spectral power); check the file's unit and scaling"
        )
    return None
