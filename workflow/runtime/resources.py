"""Memory the jobs that read run files declare (their ``mem_mb``), from the run files' sizes.

A job's peak grows with the samples of the runs it reads, so a fixed ``mem_mb`` is either
far too much for the usual 8192-sample run or too little for a long record (a 1e7-sample
ASCII run peaks at 1258 MB in ``analyse_runs``). The rules call these
functions with the job's run files once they exist; the peaks per sample are measured by
bench/bench_long_record_memory.py.
"""

from __future__ import annotations

import os
from collections.abc import Iterable

__all__ = [
    "ASCII_SUFFIXES",
    "BASE_MB",
    "KEPT_BYTES_PER_SAMPLE",
    "MODE_SEARCH_BYTES_PER_SAMPLE",
    "ANALYSE_BYTES_PER_SAMPLE",
    "BINARY_BYTES_PER_SAMPLE",
    "samples_at_most",
    "analyse_runs_mem_mb",
    "identify_mode_mem_mb",
]

ASCII_SUFFIXES = {".txt", ".csv", ".asc", ".dat"}

BASE_MB = 300
"""A job's memory before any run is read: the interpreter, NumPy, SciPy and the project
(46 MB measured) with room for Snakemake's script preamble and the small outputs."""

KEPT_BYTES_PER_SAMPLE = 24
"""A read run held in memory: time, force and response as float64."""

MODE_SEARCH_BYTES_PER_SAMPLE = 240
"""Peak of the mode search above the runs it holds, per sample of the longest run: 204-215 B
measured on ASCII runs of 2.8e6 and 5.6e6 samples (one to four runs). NumPy's FFT takes a
whole run whose length has a large prime factor (5,555,555 = 5 x 239 x 4649) by
Bluestein's algorithm, at twice the length: 168 B per sample for a transform and its
inverse, against 40 B for a length of small factors. It is above reading a run (93 B per
sample, the text parsed in chunks, the columns as float64), which it follows."""

ANALYSE_BYTES_PER_SAMPLE = 200
"""Peak of reading and analysing one run (band-pass forward and backward, analytic signal,
envelope, segments), per sample: 121-122 B measured on ASCII runs of 5.6e6 and 1e7
samples."""

BINARY_BYTES_PER_SAMPLE = 4
"""Fewest bytes a system format (MAT, UFF, TDMS) stores per sample: a float32 response
alone. A compressed MAT file can hold more samples than this gives for its size."""


def samples_at_most(path: str | os.PathLike) -> int:
    """An upper bound on the samples of one run file, without reading it as a run.

    ASCII: its number of lines (one sample per line, headers included), counted in 1 MB
    blocks (0.3 s for a 1e7-sample, 360 MB file). Other formats: the file's size over :data:`BINARY_BYTES_PER_SAMPLE`.
    """
    if os.path.splitext(path)[1].lower() not in ASCII_SUFFIXES:
        return os.path.getsize(path) // BINARY_BYTES_PER_SAMPLE
    line_feeds = carriage_returns = 0
    with open(path, "rb") as handle:
        while block := handle.read(1 << 20):
            line_feeds += block.count(b"\n")
            carriage_returns += block.count(b"\r")
    # LF, CRLF or CR line endings; the last line may have none.
    return max(line_feeds, carriage_returns) + 1


def _mb(n_bytes: float) -> int:
    # Snakemake reads mem_mb in MB (1e6 bytes); SLURM's --mem in MiB, 5 % more.
    return BASE_MB + int(n_bytes / 1e6) + 1


def analyse_runs_mem_mb(run_files: Iterable[str | os.PathLike]) -> int:
    """``mem_mb`` of an ``analyse_runs`` job: its runs are read and analysed one after the
    other, so the longest run sets the peak.

    Examples
    --------
    A 1e7-sample ASCII run (362 MB) peaked at 1258 MB (bench/bench_long_record_memory.py):

    >>> import tempfile
    >>> with tempfile.NamedTemporaryFile(suffix=".txt") as run:
    ...     _ = run.write(b"\\n" * 10_000_000)
    ...     run.flush()
    ...     analyse_runs_mem_mb([run.name])
    2301
    """
    return _mb(ANALYSE_BYTES_PER_SAMPLE * max((samples_at_most(path) for path in run_files), default=0))


def identify_mode_mem_mb(
    run_files: Iterable[str | os.PathLike], analysed_files: Iterable[str | os.PathLike] = ()
) -> int:
    """``mem_mb`` of an ``identify_mode`` job: every run of the configuration is held at
    once for the mode search, whose transform of the longest run peaks above them; the
    runs of ``analysed_files`` (its first group, still held) are then analysed one after
    the other, the longest setting the analysis's peak above them.

    Examples
    --------
    Two 5.6e6-sample ASCII runs (200 MB each), both analysed, peaked at 1389 MB
    (bench/bench_long_record_memory.py):

    >>> import tempfile
    >>> with tempfile.NamedTemporaryFile(suffix=".txt") as run:
    ...     _ = run.write(b"\\n" * 5_555_556)
    ...     run.flush()
    ...     identify_mode_mem_mb([run.name] * 2, [run.name] * 2)
    1901
    """
    samples = [samples_at_most(path) for path in run_files]
    analysed = max((samples_at_most(path) for path in analysed_files), default=0)
    peak = max(MODE_SEARCH_BYTES_PER_SAMPLE * max(samples, default=0), ANALYSE_BYTES_PER_SAMPLE * analysed)
    return _mb(KEPT_BYTES_PER_SAMPLE * sum(samples) + peak)
