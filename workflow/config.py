"""Workflow configuration (``config.yaml``), validated at workflow start.

Each section is a class of the stage that uses it, which documents every key and owns
its default: ``analysis``, ``quality`` and ``fits`` in :mod:`workflow.measured.settings`,
``models`` and ``discovery`` in :mod:`workflow.models.settings`, ``demo`` in
:mod:`workflow.lab.layout`; ``config.yaml`` repeats them. Unknown keys and bad values
stop the run at once with a message that names the key, so a typo is never silently
ignored.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from annotated_types import Ge, Le

from workflow.io.validation import FORBID_UNKNOWN_KEYS, UNKNOWN_KEY_ERRORS, validate
from workflow.lab.layout import DemoSettings
from workflow.measured.settings import AnalysisSettings, DampingFitSettings, QualitySettings
from workflow.models.settings import DiscoverySettings, ModelSettings

if TYPE_CHECKING:
    from pydantic import ValidationError


__all__ = [
    "WorkflowConfig",
    "ConfigError",
    "valid_keys",
    "format_validation_error",
    "validate_config",
]


@dataclass(frozen=True)
class WorkflowConfig:
    """Top level of ``config.yaml``."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    campaign: str = "results/demo_campaign"
    """Campaign folder (campaign-format.md); relative to the working directory."""

    strict: bool = False
    """True: a run that cannot be read or fails a quality check stops the workflow.
    False: it is excluded from fits and listed with its reason in runs.parquet."""

    # Runs are analysed one after the other (memory is one run's); 1000 is a 60 s job.
    runs_per_job: Annotated[int, Ge(1), Le(1000)] = 10
    """Run files analysed (read, checked, band-passed, segmented) by one job. Each
    job spends about 0.25 s starting (Python, Snakemake's script preamble, NumPy)
    and 0.06 s per run on signal work, and Snakemake's own bookkeeping grows with the
    number of jobs; 1 gives one job per run file. Results do not depend on it."""

    units: Literal["inch-second", "si"] = "inch-second"
    """Units of the results: ``inch-second`` (in/s, in, in², lbf: the paper's, and the
    output contract's columns) or ``si``: the tables gain SI columns beside the
    inch-second ones (``velocity_amplitude_m_s`` ...), and figures, notes and the verdict
    page show m/s, m, m², N (workflow.io.units.UNIT_SYSTEMS). Frequencies are Hz either way."""

    analysis: AnalysisSettings = field(default_factory=AnalysisSettings)
    quality: QualitySettings = field(default_factory=QualitySettings)
    fits: DampingFitSettings = field(default_factory=DampingFitSettings)
    models: ModelSettings = field(default_factory=ModelSettings)
    discovery: DiscoverySettings = field(default_factory=DiscoverySettings)
    demo: DemoSettings = field(default_factory=DemoSettings)

    def uses_demo_campaign(self, workdir: Path | str = ".") -> bool:
        """Whether ``campaign`` is the built-in demo (which a rule then generates)."""
        root = Path(workdir)
        return (root / self.campaign).resolve() == (root / self.demo.path).resolve()


class ConfigError(ValueError):
    """A configuration value is wrong; the message names the key."""


def valid_keys(path: tuple) -> list[str]:
    """The keys config.yaml accepts at ``path`` (() is the top level); [] below a leaf."""
    import typing

    section: Any = WorkflowConfig
    for part in path:
        hints = typing.get_type_hints(section) if isinstance(section, type) else {}
        section = hints.get(str(part))
    if not (isinstance(section, type) and hasattr(section, "__dataclass_fields__")):
        return []
    return list(section.__dataclass_fields__)


def _given(overrides: Mapping[str, Any] | None, path: tuple) -> bool:
    """Whether ``path`` was set in ``overrides`` (the command line's --config)."""
    level: Any = overrides or {}
    for part in path:
        if not isinstance(level, Mapping) or str(part) not in level:
            return False
        level = level[str(part)]
    return True


def format_validation_error(
    error: ValidationError, source: str, command_line: Mapping[str, Any] | None = None
) -> str:
    """One line per problem: ``where: key.path: what is wrong``, where is the command
    line when the key was given with ``--config``, else ``source``; an unknown key is
    followed by the keys valid at its place."""
    lines = []
    for item in error.errors():
        path = tuple(item["loc"])
        key = ".".join(str(part) for part in path) or "(top level)"
        origin = "command line (--config)" if _given(command_line, path) else source
        message = item["msg"]
        if item["type"] in UNKNOWN_KEY_ERRORS:
            keys = valid_keys(path[:-1])
            message = "unknown key" + (f"; valid keys here: {', '.join(keys)}" if keys else "")
        lines.append(f"{origin}: {key}: {message}")
    return "\n".join(lines)


def validate_config(
    raw: dict[str, Any] | None, source: str = "config.yaml", command_line: Mapping[str, Any] | None = None
) -> WorkflowConfig:
    """Validate the merged Snakemake config; raise ConfigError naming every bad key and
    where it came from (``command_line``: the keys given with ``--config``).

    Examples
    --------
    >>> validate_config({"units": "si"}).analysis.filter_order
    10
    >>> validate_config({"analysis": {"filter_order": 9}})
    Traceback (most recent call last):
        ...
    workflow.config.ConfigError: config.yaml: analysis.filter_order: Value error, must be even (a band-pass has an even order), got 9
    """
    from pydantic import ValidationError

    try:
        return validate(WorkflowConfig, raw or {})
    except ValidationError as error:
        raise ConfigError(format_validation_error(error, source, command_line)) from None
