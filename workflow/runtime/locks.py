"""Resuming after a hard kill: stale Snakemake directory locks.

Snakemake locks its working directory with plain files in ``.snakemake/locks/``
and removes them when it ends, also on Ctrl-C or SIGTERM. A hard kill (SIGKILL,
the OOM killer, a power loss) leaves them behind, and the next ``snakemake``
then refuses to start until someone runs ``snakemake --unlock``. The contract is
that ``snakemake -c2 all`` resumes an interrupted run, so the workflow tells a
stale lock from a live one itself:

every lapjoint Snakemake process holds an OS lock (``flock``) on
``.snakemake/lapjoint.alive`` for as long as it lives; the kernel drops it when
the process dies, however it dies. A process that gets that lock therefore
knows that no other lapjoint process is running in this directory, so any
Snakemake lock files there are stale and are removed. A process that does not
get it leaves the lock files alone, and Snakemake's own check then reports the
other run as usual.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: no flock, stale locks stay manual
    fcntl = None

__all__ = [
    "ALIVE_FILE",
    "clear_stale_snakemake_locks",
]

ALIVE_FILE: str = "lapjoint.alive"

_held: IO[str] | None = None


def clear_stale_snakemake_locks(workdir: str | Path = ".") -> list[str]:
    """Remove Snakemake's lock files in ``workdir`` when no other lapjoint run is alive.

    Call once per Snakemake process, while the Snakefile is parsed (before
    Snakemake checks its locks). The OS lock taken here is held until the process
    ends.

    Parameters
    ----------
    workdir : str or Path
        Snakemake's working directory (the current directory while parsing).

    Returns
    -------
    list of str
        Names of the stale lock files removed (empty when another lapjoint
        process holds the directory, when there were none, or without ``flock``).
    """
    global _held
    if fcntl is None or _held is not None:
        return []
    meta = Path(workdir) / ".snakemake"
    meta.mkdir(parents=True, exist_ok=True)
    handle = open(meta / ALIVE_FILE, "a")  # noqa: SIM115 - held for the process lifetime
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        return []  # another lapjoint snakemake runs here: its locks are real
    _held = handle
    removed = []
    for lock in sorted((meta / "locks").glob("*.lock")):
        lock.unlink(missing_ok=True)
        removed.append(lock.name)
    return removed
