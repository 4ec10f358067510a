"""The `snakemake --report` command of a finished run, as the user can type it anywhere.

Imported by the Snakefile (its end of `all` writes and prints the command), so it needs
nothing but the standard library.
"""

from __future__ import annotations

import json
import re
import shlex
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "config_arguments",
    "report_command",
]

REPORT_COMMAND_FILE = "results/report_command.txt"
"""Where the end of `all` writes :func:`report_command` (and prints it)."""


_PLAIN = re.compile(r"[A-Za-z0-9_./+-]+")


def _flow(value: Any) -> str:
    """``value`` as YAML flow text that Snakemake's --config parser reads back as it is
    (it reads nested values as text: ``{a: 4}`` gives ``{"a": "4"}``)."""
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_flow(key)}: {_flow(item)}" for key, item in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_flow(item) for item in value) + "]"
    text = str(value)
    return text if _PLAIN.fullmatch(text) else json.dumps(text)


def config_arguments(config: Mapping) -> list[str]:
    """``--config`` values that give back ``config`` (the command line's, as Snakemake
    parsed them: text, numbers, booleans and mappings)."""
    return [
        f"{key}={_flow(value) if isinstance(value, Mapping | list) else value}"
        for key, value in config.items()
    ]


def report_command(
    snakefile: str | Path,
    workdir: str | Path,
    stylesheet: str | Path,
    configfiles: Sequence[str | Path] = (),
    config: Mapping | None = None,
) -> str:
    """The `snakemake --report` command that builds this run's one-file report
    (``workdir/results/report.html``) from whatever folder it is typed in: absolute
    Snakefile, working directory and stylesheet, and the run's --configfile and --config.

    Returns
    -------
    str
        One shell command, each argument quoted as the shell needs it.

    Examples
    --------
    >>> print(report_command("/opt/lapjoint/Snakefile", "/data/run 1", "/opt/lapjoint/report/style.css",
    ...                      config={"units": "si"}))
    snakemake -s /opt/lapjoint/Snakefile -d '/data/run 1' --report '/data/run 1/results/report.html' --report-html-stylesheet-path /opt/lapjoint/report/style.css --config units=si
    """
    workdir = Path(workdir).absolute()
    arguments = ["snakemake", "-s", str(Path(snakefile).absolute()), "-d", str(workdir)]
    arguments += ["--report", str(workdir / "results" / "report.html")]
    arguments += ["--report-html-stylesheet-path", str(Path(stylesheet).absolute())]
    for path in configfiles:
        arguments += ["--configfile", str(Path(path).absolute())]
    if config:
        arguments += ["--config", *config_arguments(config)]
    return shlex.join(arguments)
