"""Reading a measurement campaign: campaign.yaml and the ASCII run files.

This module implements the input contract of ``campaign-format.md``. Every malformed
input becomes a :class:`CampaignFormatError` that names the file, the line (when the
problem belongs to one) and what is wrong, so that a person can fix the file; the raw
files are only ever opened for reading.

Run files are parsed in two passes. The fast pass hands the numeric block (everything
after the header) to NumPy's C reader (``np.loadtxt``). Whenever it fails or its result
is suspicious, a careful line-by-line pass re-reads the block to find and name the
first bad line, so speed never costs an exact error message.

Decisions where the contract leaves room (documented here because outside campaigns
are run against them):

- ``name`` may be omitted from campaign.yaml; the campaign folder's name is used.
- A configuration given with no settings (``decay:`` or ``decay: {}``) takes the defaults.
- Run files are matched by the configuration's glob; names starting with ``.`` (e.g.
  macOS ``._run01.txt`` companions), and files in folders whose names start with ``.``
  (``.ipynb_checkpoints/``) unless the glob names such a folder, are skipped, as a shell
  glob would. Runs are sorted by plain (lexical) run name, the file name without its
  extension, which is the name every table and the run order use.
- A response column whose unit (in parentheses) differs from campaign.yaml's response
  unit is an error naming both, not a silent conversion: the contract makes any
  file/campaign.yaml disagreement an error, and one of the two labels is then wrong.
  The same holds for a force unit that contradicts campaign.yaml's ``force.unit``.
  A force column's own unit (lbf or N) is always converted to lbf; a force column with
  no unit anywhere is taken to be in lbf (the original lab's unit).
- Columns whose names match no role are ignored; two columns with the same role are
  an error.
- A trailing delimiter at the end of every row (some exporters write one) is accepted.
  Blank lines are accepted after the numbers, not among them.
- Without a line of names, a single text line directly before one-column numbers is
  indistinguishable from a header line and is treated as header.
- ``Pre-trigger`` in the header may be given in samples (``25 samples`` or ``25``) or
  in seconds (``0.01 s``, ``10 ms``), converted with the sample rate.
"""

from __future__ import annotations

import datetime
import errno
import io
import math
import os
import re
from collections import Counter
from dataclasses import asdict, dataclass, field, replace
from dataclasses import fields as dataclass_fields
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
from annotated_types import Ge, Gt, MinLen
from numpy.typing import NDArray

from workflow.io import limits, units
from workflow.io.limits import (
    MAX_QUOTED_PROBLEMS,
    QUOTED_CHARACTERS,
    magnitude_problem,
    name_length_problem,
    quoted,
    shortened,
)
from workflow.io.record_rules import (
    TIME_STEP_REL_TOLERANCE,
    column_role,
    first_bad_time_step,
    rates_agree,
    split_name_unit,
)
from workflow.io.validation import (
    FORBID_UNKNOWN_KEYS,
    MISSING_KEY_ERRORS,
    UNKNOWN_KEY_ERRORS,
    After,
    validate,
)

if TYPE_CHECKING:
    import yaml

__all__ = [
    "MIN_SAMPLES",
    "HEAD_ROWS",
    "CAMPAIGN_FILE",
    "CONFIGURATION_NAME",
    "MAX_CAMPAIGN_YAML_BYTES",
    "MAX_YAML_VALUES",
    "SYSTEM_FORMAT_EXTENSIONS",
    "CampaignFormatError",
    "SINGLE_CHANNEL_NAME",
    "ResponseSpec",
    "ForceSpec",
    "ConfigurationSpec",
    "Campaign",
    "campaign_to_dict",
    "campaign_from_dict",
    "load_campaign",
    "frequency_problem",
    "RunFile",
    "ExcludedPath",
    "scan_campaign",
    "list_runs",
    "DECIMAL_COMMA_HINT",
    "CAREFUL_CHUNK_ROWS",
    "FAST_CHUNK_CHARS",
    "response_unit",
    "ResponseChannel",
    "RunRecord",
    "HEAD_BYTES",
    "declared_sample_rate_hz",
    "read_run",
]


MIN_SAMPLES: int = 256
"""Fewest samples a run file must hold. Below this a record cannot hold even a few
cycles of the mode plus the filter's settling time, and such short files are in
practice truncated exports ("fewer than a few hundred samples" in the contract)."""

HEAD_ROWS: int = 11
"""Numeric rows whose majority decides the delimiter and the column count, so that a
single bad first row is reported as bad instead of setting the format."""

CAMPAIGN_FILE: str = "campaign.yaml"

CONFIGURATION_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,63}")
"""What a configuration name may be: it becomes part of output paths and Snakemake
wildcards, so no ``/``, ``..``, spaces or shell characters (docs/input-safety.md)."""

MAX_CAMPAIGN_YAML_BYTES: int = 1_000_000
"""Largest campaign.yaml read; a real one is a few kilobytes."""

MAX_YAML_VALUES: int = 100_000
"""Most values campaign.yaml may hold once its aliases are expanded: a bound on the
work of validating it, whatever its aliases and nesting (an alias bomb is refused)."""

SYSTEM_FORMAT_EXTENSIONS: frozenset[str] = frozenset({".mat", ".uff", ".unv", ".tdms"})
"""Run-file extensions read by the acquisition-system readers (workflow/io/readers);
every other extension is read as ASCII."""

# --------------------------------------------------------------------------------------
# Errors


class CampaignFormatError(ValueError):
    """A campaign file breaks the input contract.

    Attributes
    ----------
    path : str
        The offending file.
    line : int or None
        1-based line number, or None when the problem is not tied to one line.
    problem : str
        What is wrong, in words a person can act on.
    """

    def __init__(self, path: str | Path, line: int | None, problem: str) -> None:
        self.path = Path(path).as_posix() if isinstance(path, Path) else str(path)
        self.line = line
        self.problem = problem
        super().__init__(self._message())

    def _message(self) -> str:
        if self.line is None:
            return f"{self.path}: {self.problem}"
        return f"{self.path}:{self.line}: {self.problem}"

    def __str__(self) -> str:
        return self._message()

    def __reduce__(self) -> tuple[Any, ...]:
        # Exceptions are re-created from args when pickled (e.g. across processes).
        return (type(self), (self.path, self.line, self.problem))


# --------------------------------------------------------------------------------------
# campaign.yaml


def _canonical_force_unit(unit: str | None) -> str | None:
    if unit is None:
        return None
    canonical = units.normalize_unit(unit)
    if canonical not in units.known_units("force"):
        raise ValueError(f"unit {unit!r} is not a force unit; expected lbf or N")
    return canonical


def _relative_glob(files: str) -> str:
    if not files.strip():
        raise ValueError("files must be a non-empty glob")
    if Path(files).is_absolute() or files.startswith(("/", "\\", "~")) or re.match(r"[A-Za-z]:", files):
        raise ValueError(f"files glob {quoted(files)} must be relative to the campaign folder")
    if ".." in re.split(r"[/\\]", files):
        raise ValueError(f"files glob {quoted(files)} leaves the campaign folder ('..' is not allowed)")
    if not Path(files).parts:
        raise ValueError(f"files glob {quoted(files)} names no file")
    return files


def _ordered_window(window: tuple[float, float] | None) -> tuple[float, float] | None:
    if window is not None and not (0.0 <= window[0] < window[1]):
        raise ValueError(f"window_s must be [start, end] with 0 <= start < end, got {list(window)}")
    return window


def _channel_reference(channel: str | int | None) -> str | int | None:
    if isinstance(channel, int) and channel < 0:
        raise ValueError(f"channel index must be 0 or more, got {channel}")
    if isinstance(channel, str) and not channel.strip():
        raise ValueError("channel must be a non-empty name or a 0-based index")
    if isinstance(channel, str) and (problem := name_length_problem("channel name", channel)):
        raise ValueError(problem)
    return channel


def _channel_references(channels: tuple[str | int, ...] | None) -> tuple[str | int, ...] | None:
    if channels is None:
        return None
    if not channels:
        raise ValueError("channels must list at least one channel (a name or a 0-based index)")
    for channel in channels:
        _channel_reference(channel)
    repeated = sorted({str(c) for c in channels if sum(str(d) == str(c) for d in channels) > 1})
    if repeated:
        raise ValueError(f"channels lists {', '.join(map(quoted, repeated))} more than once")
    return channels


def _ordered_band(band: tuple[float, float] | None) -> tuple[float, float] | None:
    if band is not None and not (0.0 < band[0] < band[1]):
        raise ValueError(f"band_hz must be [low, high] with 0 < low < high, got {list(band)}")
    return band


def _mode_list(modes: tuple[float, ...] | Literal["auto"] | None) -> tuple[float, ...] | str | None:
    if modes is None or modes == "auto":
        return modes
    if not modes:
        raise ValueError("modes_hz must list at least one frequency, or be auto")
    if any(not mode > 0.0 for mode in modes):
        raise ValueError(f"modes_hz must be frequencies above 0 Hz, got {list(modes)}")
    if any(b <= a for a, b in zip(modes, modes[1:])):
        raise ValueError(f"modes_hz must increase, got {list(modes)}")
    return modes


def _band_list(bands: tuple[tuple[float, float], ...] | None) -> tuple[tuple[float, float], ...] | None:
    if bands is None:
        return None
    for band in bands:
        if not (0.0 < band[0] < band[1]):
            raise ValueError(f"bands_hz entries must be [low, high] with 0 < low < high, got {list(band)}")
    return bands


# Settings dataclasses (workflow/io/validation.py): load_campaign validates campaign.yaml
# into them; jobs that read the validated copy (campaign_to_dict / campaign_from_dict)
# never import pydantic or PyYAML.
# allow_inf_nan: YAML's .inf and .nan are numbers to it; no campaign.yaml value may be one.
_CAMPAIGN_YAML_CONFIG = {**FORBID_UNKNOWN_KEYS, "coerce_numbers_to_str": True, "allow_inf_nan": False}


SINGLE_CHANNEL_NAME = "response"
"""The ``channel`` of every table row of a campaign that names no response channel."""


@dataclass(frozen=True)
class ResponseSpec:
    """The recorded response channel(s)."""

    __pydantic_config__ = _CAMPAIGN_YAML_CONFIG

    quantity: Literal["acceleration", "velocity", "displacement"]
    unit: str | None = None
    """Canonical unit name (g, m/s^2, in/s^2, m/s, in/s, m, in); None when every run file
    records its response unit (the file's unit is then used)."""
    channel: Annotated[int | str | None, After(_channel_reference)] = None
    """Which channel of a run file holds the response: its name (a system file's channel,
    an ASCII column's name without its unit) or 0-based index (workflow/io/readers); None
    when the file has exactly one response channel."""
    channels: Annotated[tuple[int | str, ...] | None, After(_channel_references)] = None
    """Several response channels of every run file (sensors seeing the same hit), each a
    name or a 0-based index as ``channel``; each is analysed on its own."""

    def __post_init__(self) -> None:
        if self.channel is not None and self.channels is not None:
            raise ValueError("give channel (one sensor) or channels (several), not both")
        if self.unit is None:
            return
        canonical = units.normalize_unit(self.unit)
        allowed = units.known_units(self.quantity)
        if canonical not in allowed:
            raise ValueError(
                f"unit {self.unit!r} is not a unit of {self.quantity}; expected one of {', '.join(allowed)}"
            )
        object.__setattr__(self, "unit", canonical)

    def references(self) -> tuple[int | str | None, ...]:
        """What campaign.yaml names as the response channels, in its order: the entries
        of ``channels``, else ``channel`` (None: the file's one response channel)."""
        return self.channels if self.channels is not None else (self.channel,)

    def channel_names(self) -> tuple[str, ...]:
        """The response channels' names in every table (the ``channel`` column): each
        reference as written in campaign.yaml, :data:`SINGLE_CHANNEL_NAME` without one."""
        return tuple(SINGLE_CHANNEL_NAME if ref is None else str(ref) for ref in self.references())


@dataclass(frozen=True)
class ForceSpec:
    """The recorded hammer-force channel."""

    __pydantic_config__ = _CAMPAIGN_YAML_CONFIG

    unit: Annotated[str | None, After(_canonical_force_unit)] = None
    """Canonical unit name (lbf or N); None when the file records it (else lbf)."""
    channel: Annotated[int | str | None, After(_channel_reference)] = None
    """Which channel of a system-format file holds the force (name or 0-based index)."""


@dataclass(frozen=True, kw_only=True)
class ConfigurationSpec:
    """One joint configuration."""

    __pydantic_config__ = _CAMPAIGN_YAML_CONFIG

    bearing_area_in2: Annotated[float, Gt(0.0)] | None = None
    files: Annotated[str, After(_relative_glob)]
    """Glob relative to the campaign folder (default ``<name>/*.txt``)."""
    window_s: Annotated[tuple[float, float] | None, After(_ordered_window)] = None
    """Part of every run to analyse, [start, end] in s from the start of the file."""


@dataclass(frozen=True, kw_only=True)
class Campaign:
    """Validated content of campaign.yaml (see campaign-format.md)."""

    __pydantic_config__ = _CAMPAIGN_YAML_CONFIG

    name: str
    sample_rate_hz: Annotated[float, Gt(0.0)] | None = None
    pretrigger_samples: Annotated[int, Ge(0)] = 0
    mode_hz: Annotated[float, Gt(0.0)] | None = None
    band_hz: Annotated[tuple[float, float] | None, After(_ordered_band)] = None
    modes_hz: Annotated[tuple[float, ...] | Literal["auto"] | None, After(_mode_list)] = None
    """Several modes to analyse (Hz, increasing), or ``auto``: every clear, decaying mode
    of the response spectrum (:func:`workflow.measured.mode.find_decaying_modes`)."""
    bands_hz: Annotated[tuple[tuple[float, float], ...] | None, After(_band_list)] = None
    """One band-pass per entry of ``modes_hz``; default: a band around each mode."""
    response: ResponseSpec
    force: ForceSpec | None = None
    configurations: Annotated[dict[str, ConfigurationSpec], MinLen(1)]
    decimal: Literal[".", ","] = "."
    """Decimal mark of the ASCII run files; with ``","`` columns are separated by tabs,
    semicolons or spaces."""
    pretrigger_given: bool = field(default=False, init=False)
    """Whether campaign.yaml states ``pretrigger_samples`` (rather than the default 0);
    set by :func:`load_campaign`, not a key of campaign.yaml."""

    def __post_init__(self) -> None:
        problem = _modes_problem(self.mode_hz, self.band_hz, self.modes_hz, self.bands_hz)
        if problem is not None:
            raise ValueError(problem)

    @property
    def auto_modes(self) -> bool:
        """Whether campaign.yaml asks for every mode found (``modes_hz: auto``)."""
        return self.modes_hz == "auto"

    def mode_requests(self) -> tuple[tuple[float | None, tuple[float, float] | None], ...]:
        """The modes campaign.yaml asks for, as (mode Hz or None, band Hz or None) pairs:
        one per entry of ``modes_hz``; else ``mode_hz`` and ``band_hz`` (a None mode is
        searched for: the first mode). Empty with ``modes_hz: auto``."""
        if self.auto_modes:
            return ()
        if self.modes_hz is not None:
            bands = self.bands_hz if self.bands_hz is not None else (None,) * len(self.modes_hz)
            return tuple(zip(self.modes_hz, bands))
        return ((self.mode_hz, self.band_hz),)


def _modes_problem(
    mode_hz: float | None,
    band_hz: tuple[float, float] | None,
    modes_hz: tuple[float, ...] | str | None,
    bands_hz: tuple[tuple[float, float], ...] | None,
) -> str | None:
    """What is wrong with how campaign.yaml's mode keys combine, or None."""
    if modes_hz is not None and (mode_hz is not None or band_hz is not None):
        key = "mode_hz" if mode_hz is not None else "band_hz"
        return f"{key}: give the one-mode form (mode_hz, band_hz) or modes_hz (with bands_hz), not both"
    if bands_hz is None:
        return None
    if modes_hz is None or modes_hz == "auto":
        return "bands_hz: needs modes_hz listing one mode per band"
    if len(bands_hz) != len(modes_hz):
        return f"bands_hz: {len(bands_hz)} band(s) for {len(modes_hz)} mode(s) in modes_hz; give one band per mode"
    for mode, band in zip(modes_hz, bands_hz):
        if not band[0] < mode < band[1]:
            return (
                f"bands_hz: [{band[0]:.6g}, {band[1]:.6g}] Hz does not hold its mode {mode:.6g} Hz: "
                "the band-pass would isolate another mode (or none)"
            )
    return None


def campaign_to_dict(campaign: Campaign) -> dict[str, Any]:
    """The validated campaign as plain JSON-ready data (inverse of :func:`campaign_from_dict`)."""
    return asdict(campaign)


def campaign_from_dict(data: dict[str, Any]) -> Campaign:
    """The campaign of :func:`campaign_to_dict`'s data, which was validated when written
    (:mod:`workflow.io.interim` writes and reads it between rules)."""

    def pair(values: list[float] | None) -> tuple[float, float] | None:
        return None if values is None else (float(values[0]), float(values[1]))

    response = dict(data["response"])
    if response.get("channels") is not None:
        response["channels"] = tuple(response["channels"])
    modes_hz = data.get("modes_hz")
    campaign = Campaign(
        name=data["name"],
        response=ResponseSpec(**response),
        configurations={
            name: ConfigurationSpec(
                files=spec["files"],
                bearing_area_in2=spec["bearing_area_in2"],
                window_s=pair(spec["window_s"]),
            )
            for name, spec in data["configurations"].items()
        },
        sample_rate_hz=data["sample_rate_hz"],
        pretrigger_samples=data["pretrigger_samples"],
        mode_hz=data["mode_hz"],
        band_hz=pair(data["band_hz"]),
        modes_hz=modes_hz if modes_hz is None or modes_hz == "auto" else tuple(float(m) for m in modes_hz),
        bands_hz=None if data.get("bands_hz") is None else tuple(pair(band) for band in data["bands_hz"]),
        force=None if data["force"] is None else ForceSpec(**data["force"]),
        # A copy without the key was validated before campaign.yaml could set it.
        decimal=data.get("decimal", "."),
    )
    object.__setattr__(campaign, "pretrigger_given", bool(data["pretrigger_given"]))
    return campaign


_ALLOWED_KEYS: dict[str, tuple[str, ...]] = {
    "": tuple(item.name for item in dataclass_fields(Campaign) if item.init),
    "response": tuple(item.name for item in dataclass_fields(ResponseSpec)),
    "force": tuple(item.name for item in dataclass_fields(ForceSpec)),
    "configuration": tuple(item.name for item in dataclass_fields(ConfigurationSpec)),
}


def _allowed_keys(loc: tuple[Any, ...]) -> tuple[str, ...]:
    """Keys allowed in the mapping that holds the key at ``loc``."""
    parent = loc[:-1]
    if not parent:
        return _ALLOWED_KEYS[""]
    if parent[0] == "configurations" and len(parent) == 2:
        return _ALLOWED_KEYS["configuration"]
    return _ALLOWED_KEYS.get(str(parent[0]), ())


def _node_line(root: yaml.Node | None, loc: tuple[Any, ...]) -> int | None:
    """1-based line of the YAML node at ``loc`` (or of its deepest existing parent)."""
    import yaml

    node, line = root, None
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            match = next(((key, value) for key, value in node.value if str(key.value) == str(part)), None)
            if match is None:
                return line  # a missing key: the line of its parent (None at top level)
            line = match[0].start_mark.line + 1
            node = match[1]
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int) and part < len(node.value):
            node = node.value[part]
            line = node.start_mark.line + 1
        else:
            break
    return line


def _duplicate_key(root: yaml.Node | None) -> tuple[str, int] | None:
    """First key that appears twice in one mapping (PyYAML keeps the last silently).

    Each node is visited once, however many aliases refer to it, so the work stays
    proportional to the file's length.
    """
    import yaml

    visited: set[int] = set()
    pending = [root]
    while pending:
        node = pending.pop()
        if node is None or id(node) in visited:
            continue
        visited.add(id(node))
        if isinstance(node, yaml.MappingNode):
            seen: set[str] = set()
            for key, _value in node.value:
                name = str(key.value)
                if name in seen:
                    return name, key.start_mark.line + 1
                seen.add(name)
            pending.extend(value for _, value in reversed(node.value))
        elif isinstance(node, yaml.SequenceNode):
            pending.extend(reversed(node.value))
    return None


def _expanded_size(root: yaml.Node | None, limit: int) -> int:
    """Number of values in the document once every alias is expanded, counted up to
    just past ``limit`` (each node's size is computed once: linear work)."""
    import yaml

    sizes: dict[int, int] = {}
    order: list[yaml.Node] = []
    pending = [root]
    while pending:
        node = pending.pop()
        if node is None or id(node) in sizes:
            continue
        sizes[id(node)] = -1
        order.append(node)
        if isinstance(node, yaml.MappingNode):
            pending.extend(part for pair in node.value for part in pair)
        elif isinstance(node, yaml.SequenceNode):
            pending.extend(node.value)
    # Children are listed after their parents: sum them up in reverse order.
    for node in reversed(order):
        if isinstance(node, yaml.MappingNode):
            children = [part for pair in node.value for part in pair]
        elif isinstance(node, yaml.SequenceNode):
            children = node.value
        else:
            children = []
        sizes[id(node)] = min(limit + 1, 1 + sum(sizes[id(child)] for child in children))
    return 0 if root is None else sizes[id(root)]


def load_campaign(campaign_dir: str | Path) -> Campaign:
    """Read and validate ``campaign_dir/campaign.yaml``.

    Parameters
    ----------
    campaign_dir : str or Path
        The campaign folder.

    Returns
    -------
    Campaign
        The validated metadata, with every configuration's ``files`` glob filled in.

    Raises
    ------
    CampaignFormatError
        Missing or unreadable file, YAML syntax error, unknown key, duplicate key or bad
        value; the message names campaign.yaml, the line and the key.
    """
    import yaml
    from pydantic import ValidationError

    path = Path(campaign_dir) / CAMPAIGN_FILE
    outside = _link_problem(path, Path(campaign_dir).resolve())
    if outside is not None:
        raise CampaignFormatError(
            path, None, f"{outside}; campaign.yaml must be a file inside the campaign folder"
        )
    if path.exists() and not path.is_file():
        raise CampaignFormatError(
            path, None, "not read: not a regular file (a directory, a device or a pipe)"
        )
    if not path.is_file():
        raise CampaignFormatError(
            path, None, "missing: every campaign folder needs a campaign.yaml (campaign-format.md)"
        )
    try:
        size_bytes = path.stat().st_size
        if size_bytes > MAX_CAMPAIGN_YAML_BYTES:
            raise CampaignFormatError(
                path,
                None,
                f"{size_bytes} bytes: too large for a campaign.yaml (limit {MAX_CAMPAIGN_YAML_BYTES})",
            )
        text = path.read_text(encoding="utf-8-sig", errors="replace")
    except OSError as error:
        raise CampaignFormatError(path, None, f"cannot be read: {error.strerror or error}") from None
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
        if _expanded_size(root, MAX_YAML_VALUES) > MAX_YAML_VALUES:
            raise CampaignFormatError(
                path,
                None,
                f"its aliases (*name) expand to more than {MAX_YAML_VALUES} values: refused "
                "(an alias bomb?); write the settings out instead",
            )
        raw = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        problem = getattr(error, "problem", None) or str(error)
        raise CampaignFormatError(
            path, None if mark is None else mark.line + 1, f"not valid YAML: {problem}"
        ) from None
    except RecursionError:
        raise CampaignFormatError(path, None, "nested too deeply to be a campaign.yaml") from None
    if not isinstance(raw, dict):
        raise CampaignFormatError(path, 1, "must be a mapping of keys (name, response, configurations, ...)")
    duplicate = _duplicate_key(root)
    if duplicate:
        raise CampaignFormatError(path, duplicate[1], f"{duplicate[0]}: key given twice")
    if isinstance(raw.get("configurations"), dict):
        for name in raw["configurations"]:
            if not (isinstance(name, str) and CONFIGURATION_NAME.fullmatch(name)):
                raise CampaignFormatError(
                    path,
                    _node_line(root, ("configurations", name)),
                    f"configurations.{name}: configuration name {name!r} is not allowed: it names "
                    "output files, so it must be 1 to 64 letters, digits, '_' or '-', starting "
                    "with a letter or digit",
                )
    if "name" not in raw:
        raw = {**raw, "name": Path(campaign_dir).resolve().name}
    elif isinstance(raw["name"], bool | datetime.date):
        # free text that YAML read as a date or a yes/no: keep the text as written
        name_node = next(value for key, value in root.value if key.value == "name")
        raw = {**raw, "name": str(name_node.value)}
    modes = raw.get("modes_hz")
    if modes is not None and modes != "auto" and not isinstance(modes, list):
        # a union's own messages (one per form) would not say what to write
        raise CampaignFormatError(
            path,
            _node_line(root, ("modes_hz",)),
            f"modes_hz: expected a list of frequencies in Hz ([80.5, 297.7]) or auto, got {modes!r}",
        )
    try:
        campaign = validate(Campaign, _with_default_globs(raw))
    except ValidationError as error:
        problems, first_line = [], None
        errors = error.errors()
        for item in errors[:MAX_QUOTED_PROBLEMS]:
            loc = tuple(item["loc"])
            combined = re.match(r"(?:Value error, )?(mode_hz|band_hz|modes_hz|bands_hz): ", item["msg"])
            if not loc and combined:
                # a check across keys (Campaign.__post_init__) names the key it is about
                loc = (combined.group(1),)
                item = {**item, "msg": item["msg"][combined.start(1) + len(combined.group(1)) + 2 :]}
            key = ".".join(shortened(str(part)) for part in loc) or "(top level)"
            if item["type"] in UNKNOWN_KEY_ERRORS:
                message = f"unknown key (allowed here: {', '.join(_allowed_keys(loc))})"
            elif item["type"] in MISSING_KEY_ERRORS:
                message = "required key is missing"
            else:
                message = shortened(item["msg"], 10 * QUOTED_CHARACTERS)
            problems.append(f"{key}: {message}")
            if first_line is None:
                first_line = _node_line(root, loc)
        if len(errors) > MAX_QUOTED_PROBLEMS:
            problems.append(f"and {len(errors) - MAX_QUOTED_PROBLEMS} more problems")
        raise CampaignFormatError(path, first_line, "; ".join(problems)) from None
    object.__setattr__(campaign, "pretrigger_given", "pretrigger_samples" in raw)
    long_name = name_length_problem("name", campaign.name, limits.MAX_CAMPAIGN_NAME_CHARACTERS)
    if long_name is not None:
        raise CampaignFormatError(path, _node_line(root, ("name",)), long_name)
    if campaign.sample_rate_hz is not None:
        problem = frequency_problem(campaign, campaign.sample_rate_hz)
    else:
        problem = frequency_problem(campaign, math.inf)
    if problem is not None:
        key = problem.split(":", 1)[0].split("[", 1)[0]
        raise CampaignFormatError(path, _node_line(root, (key,)), problem)
    return campaign


def frequency_problem(campaign: Campaign, sample_rate_hz: float, rate_source: str = "") -> str | None:
    """What is wrong with campaign.yaml's modes and bands (``mode_hz``, ``band_hz``,
    ``modes_hz``, ``bands_hz``) for records sampled at ``sample_rate_hz``, or None.

    Each band must lie inside (0, Nyquist) and hold its mode, which must lie below
    Nyquist; a message starts with the campaign.yaml key it is about (``modes_hz[1]``
    for the second entry of a list).

    Parameters
    ----------
    campaign : Campaign
        The validated campaign.yaml.
    sample_rate_hz : float
        Sample rate of the records, Hz (``math.inf`` checks the bands and modes alone).
    rate_source : str, optional
        Where the sample rate comes from, for the message (e.g. ``"header line 2"``).
    """
    nyquist_hz = sample_rate_hz / 2.0
    source = f" ({rate_source})" if rate_source else ""
    rate = f"the Nyquist frequency {nyquist_hz:.6g} Hz of the sample rate {sample_rate_hz:.6g} Hz{source}"
    listed = campaign.modes_hz is not None
    for index, (mode_hz, band) in enumerate(campaign.mode_requests()):
        mode_key = f"modes_hz[{index}]" if listed else "mode_hz"
        band_key = f"bands_hz[{index}]" if listed else "band_hz"
        if mode_hz is not None and mode_hz >= nyquist_hz:
            return f"{mode_key}: {mode_hz:.6g} Hz is not below {rate}: such a mode cannot be in the records"
        if band is not None and band[1] >= nyquist_hz:
            return f"{band_key}: [{band[0]:.6g}, {band[1]:.6g}] Hz reaches {rate}; the band must lie below it"
        if band is not None and mode_hz is not None and not band[0] < mode_hz < band[1]:
            return (
                f"{band_key}: [{band[0]:.6g}, {band[1]:.6g}] Hz does not hold {mode_key} {mode_hz:.6g} Hz: "
                "the band-pass would isolate another mode (or none)"
            )
    return None


def _with_default_globs(raw: dict[str, Any]) -> dict[str, Any]:
    """campaign.yaml's mapping with each configuration's ``files`` default filled in
    (it depends on the configuration's name)."""
    if not isinstance(raw.get("configurations"), dict):
        return raw
    filled = {}
    for name, spec in raw["configurations"].items():
        spec = {} if spec is None else spec
        if isinstance(spec, dict) and "files" not in spec:
            spec = {**spec, "files": f"{name}/*.txt"}
        filled[name] = spec
    return {**raw, "configurations": filled}


# --------------------------------------------------------------------------------------
# Run discovery


@dataclass(frozen=True)
class RunFile:
    """One run file of a configuration."""

    configuration: str
    run: str
    """File name without extension."""
    path: str
    """Path relative to the campaign folder, with ``/`` separators."""


@dataclass(frozen=True)
class ExcludedPath:
    """A path a configuration's glob leads to that is not read, or a glob that matches
    nothing: a row of runs.parquet with status ``excluded`` and the reason."""

    configuration: str
    run: str
    """File name without extension (empty for a glob that matches nothing)."""
    path: str
    """Path relative to the campaign folder, or the glob that matched nothing."""
    reason: str

    def status(self) -> dict[str, str]:
        """The runs-table row (the keys of the analysis jobs' status documents)."""
        return {**asdict(self), "status": "excluded"}


def _link_problem(path: Path, root_resolved: Path) -> str | None:
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


def _unreadable_reason(path: Path, root_resolved: Path) -> str | None:
    """Why a path matched by a glob is not read as a run file, or None."""
    link = _link_problem(path, root_resolved)
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


def scan_campaign(campaign_dir: str | Path, campaign: Campaign) -> tuple[list[RunFile], list[ExcludedPath]]:
    """The run files of every configuration, and what its glob leads to that is not read.

    Only regular, readable files whose real path (symbolic links followed) lies inside
    the campaign folder are run files. Directories, links leading outside, other
    special files and unreadable files are excluded with their reason; a glob that
    matches nothing gives one excluded entry that names ``configurations.<name>.files``.
    Names starting with ``.``, and folders starting with ``.`` that the glob does not
    name, are skipped, as a shell glob would.

    Parameters
    ----------
    campaign_dir : str or Path
        The campaign folder.
    campaign : Campaign
        Its validated campaign.yaml.

    Returns
    -------
    runs : list of RunFile
        Configurations in campaign.yaml order, runs sorted by run name (the file name
        without its extension: the file-name run order).
    excluded : list of ExcludedPath
        Everything else the globs lead to, in the same order.

    Raises
    ------
    CampaignFormatError
        Two runs of one configuration with the same name (their rows would collide), or
        a glob that pathlib cannot use.
    """
    root = Path(campaign_dir)
    root_resolved = root.resolve()
    runs: list[RunFile] = []
    excluded: list[ExcludedPath] = []
    for configuration, spec in campaign.configurations.items():
        # a shell's * leaves out dot-names; pathlib's does not
        names_dot_folder = any(part.startswith(".") for part in Path(spec.files).parts[:-1])
        try:
            matches = sorted(
                (
                    p
                    for p in root.glob(spec.files)
                    if not p.name.startswith(".")
                    and (
                        names_dot_folder
                        or not any(part.startswith(".") for part in p.relative_to(root).parts)
                    )
                ),
                key=lambda p: (p.stem, p.as_posix()),
            )
        except (ValueError, NotImplementedError, IndexError) as error:
            raise CampaignFormatError(
                root / CAMPAIGN_FILE,
                None,
                f"configurations.{configuration}.files: {quoted(spec.files)} is not a usable glob ({error})",
            ) from None
        if not matches:
            excluded.append(
                ExcludedPath(
                    configuration,
                    "",
                    spec.files,
                    f"configurations.{configuration}.files: the glob {quoted(spec.files)} matches no "
                    f"file in the campaign folder {root.as_posix()}",
                )
            )
        seen: dict[str, str] = {}
        for match in matches:
            relative = match.relative_to(root).as_posix()
            reason = _unreadable_reason(match, root_resolved)
            long_name = name_length_problem("run file name", match.name)
            if long_name is not None:
                # the name itself is not repeated in full anywhere
                shown = shortened(relative)
                excluded.append(
                    ExcludedPath(
                        configuration, shortened(match.stem), shown, f"{shown}: not read: {long_name}"
                    )
                )
                continue
            if reason is not None:
                excluded.append(
                    ExcludedPath(
                        configuration, match.stem, relative, f"{root.as_posix()}/{relative}: {reason}"
                    )
                )
                continue
            if match.stem in seen:
                raise CampaignFormatError(
                    root / CAMPAIGN_FILE,
                    None,
                    f"configurations.{configuration}.files matches two runs named "
                    f"{quoted(match.stem)}: {seen[match.stem]} and {relative}",
                )
            seen[match.stem] = relative
            runs.append(RunFile(configuration, match.stem, relative))
    return runs, excluded


def list_runs(campaign_dir: str | Path, campaign: Campaign) -> list[RunFile]:
    """The run files of :func:`scan_campaign` (regular, readable files inside the campaign
    folder), configurations in campaign.yaml order, runs sorted by run name."""
    return scan_campaign(campaign_dir, campaign)[0]


# --------------------------------------------------------------------------------------
# Run files: tokens and rows

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
_KEY_VALUE = re.compile(r"\s*([^:]*[^:\s])\s*:\s*(.*?)\s*")
_VALUE_WITH_UNIT = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*")
_SPACES = " "  # marker: columns separated by runs of spaces
_DELIMITER_NAMES = {"\t": "tab", ",": "comma", ";": "semicolon", _SPACES: "spaces"}
# Characters a numeric block may hold; anything else sends it to the careful pass.
_FOREIGN = {
    "\t": re.compile(r"[^0-9eE+\-. \t\n]"),
    ",": re.compile(r"[^0-9eE+\-. ,\n]"),
    ";": re.compile(r"[^0-9eE+\-. ;\n]"),
    _SPACES: re.compile(r"[^0-9eE+\-. \n]"),
}


def _line_delimiter(line: str) -> str:
    """The delimiter a single row appears to use (tab, comma, semicolon, else spaces)."""
    for delimiter in ("\t", ",", ";"):
        if delimiter in line:
            return delimiter
    return _SPACES


def _split_row(line: str, delimiter: str) -> list[str]:
    """Cells of one row; a single trailing comma/semicolon is tolerated."""
    if delimiter == _SPACES:
        return line.split()
    cells = [cell.strip() for cell in line.strip().split(delimiter)]
    if len(cells) > 1 and cells[-1] == "":
        cells.pop()
    return cells


def _is_numeric_row(line: str) -> bool:
    cells = _split_row(line, _line_delimiter(line))
    return bool(cells) and all(_NUMBER.fullmatch(cell) for cell in cells)


def _is_data_like(cell: str) -> bool:
    """A token that looks like a measured value (decimal, exponent, NaN or inf)."""
    if _NON_FINITE.fullmatch(cell):
        return True
    return bool(_NUMBER.fullmatch(cell)) and ("." in cell or "e" in cell.lower())


_DECIMAL_COMMA_NUMBER = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")
DECIMAL_COMMA_HINT = (
    "numbers written with decimal commas; the decimal point of run files is '.' "
    'unless campaign.yaml says decimal: "," (campaign-format.md)'
)


def _is_decimal_comma_row(line: str) -> bool:
    """A row of numbers written with decimal commas (``0,0021<TAB>-0,00037``)."""
    cells = [cell for cell in re.split(r"[\t; ]+", line.strip()) if cell]
    return (
        bool(cells)
        and all(_NUMBER.fullmatch(cell) or _DECIMAL_COMMA_NUMBER.fullmatch(cell) for cell in cells)
        and any(_DECIMAL_COMMA_NUMBER.fullmatch(cell) for cell in cells)
    )


def _row_problem(line: str, delimiter: str, n_columns: int, format_line: int) -> str | None:
    """What is wrong with one row of the numeric block, or None if it is fine."""
    stripped = line.strip()
    if not stripped:
        return "blank line among the numbers"
    if delimiter != "," and _is_decimal_comma_row(stripped):
        return f"{DECIMAL_COMMA_HINT}: {stripped[:60]!r}"
    for other in ("\t", ",", ";"):
        if other != delimiter and other in stripped:
            return (
                f"mixed delimiters: {_DELIMITER_NAMES[other]} in a row separated by "
                f"{_DELIMITER_NAMES[delimiter]} (as set by the numbers from line {format_line})"
                + ("; note that '.' is the decimal point" if other == "," else "")
            )
    cells = _split_row(stripped, delimiter)
    if delimiter != _SPACES and any(re.search(r"\s", cell) for cell in cells):
        return f"mixed delimiters: spaces inside a cell of a row separated by {_DELIMITER_NAMES[delimiter]}"
    if len(cells) != n_columns:
        return (
            f"ragged row: {len(cells)} value{'s' if len(cells) != 1 else ''}, expected "
            f"{n_columns} like the rows from line {format_line}"
        )
    for column, cell in enumerate(cells, start=1):
        if cell == "":
            return f"empty cell in column {column}"
        if _NON_FINITE.fullmatch(cell):
            return f"NaN/inf value {quoted(cell)} in column {column}"
        if not _NUMBER.fullmatch(cell):
            return f"non-numeric cell {quoted(cell)} in column {column}"
        if not math.isfinite(float(cell)):
            return f"value {quoted(cell)} in column {column} overflows a float"
    return None


CAREFUL_CHUNK_ROWS: int = 2048
"""Rows per chunk when hunting for a bad line: clean chunks still go through the C
parser, so only the chunk holding the bad line is read line by line."""


def _parse_block_careful(
    rows: list[str], first_line: int, delimiter: str, n_columns: int, path: str
) -> NDArray[np.float64]:
    """Parse that names the first bad line (chunked; line by line where needed)."""
    values = np.empty((len(rows), n_columns))
    for start in range(0, len(rows), CAREFUL_CHUNK_ROWS):
        chunk = rows[start : start + CAREFUL_CHUNK_ROWS]
        fast = _parse_block_fast("\n".join(chunk), delimiter, len(chunk), n_columns)
        if fast is not None:
            values[start : start + len(chunk)] = fast
            continue
        for index, row in enumerate(chunk, start=start):
            problem = _row_problem(row, delimiter, n_columns, first_line)
            if problem is not None:
                raise CampaignFormatError(path, first_line + index, problem)
            values[index] = [float(cell) for cell in _split_row(row, delimiter)]
    return values


FAST_CHUNK_CHARS: int = 1 << 20
"""Characters of the numeric block handed to the C reader at a time: the reader's working
copy of the text (4 bytes a character) then stays small however long the record."""


def _parse_text_fast(
    text: str, start: int, end: int, delimiter: str, n_rows: int, n_columns: int
) -> NDArray[np.float64] | None:
    """:func:`_parse_block_fast` of ``text[start:end]``, in chunks of whole rows (no copy
    of the whole block); None whenever the careful pass must decide."""
    if _FOREIGN[delimiter].search(text, start, end):
        return None
    values = np.empty((n_rows, n_columns))
    row, position = 0, start
    while position <= end:
        stop = end
        if position + FAST_CHUNK_CHARS < end:
            stop = text.rfind("\n", position, position + FAST_CHUNK_CHARS)
            if stop < 0:
                stop = text.find("\n", position + FAST_CHUNK_CHARS, end)
                stop = end if stop < 0 else stop
        chunk = text[position:stop]
        chunk_rows = chunk.count("\n") + 1
        if row + chunk_rows > n_rows:
            return None
        parsed = _parse_block_fast(chunk, delimiter, chunk_rows, n_columns)
        if parsed is None:
            return None
        values[row : row + chunk_rows] = parsed
        row, position = row + chunk_rows, stop + 1
    return values if row == n_rows else None


def _parse_block_fast(block: str, delimiter: str, n_rows: int, n_columns: int) -> NDArray[np.float64] | None:
    """C-parser read of the numeric block; None whenever the careful pass must decide."""
    if _FOREIGN[delimiter].search(block):
        return None
    if (
        delimiter != _SPACES
        and block.count(delimiter + "\n") == n_rows - 1
        and block.rstrip().endswith(delimiter)
    ):
        block = block.replace(delimiter + "\n", "\n").rstrip()[:-1]  # one trailing delimiter per row
    try:
        # NumPy's C reader (not pandas): the run-analysis jobs then start without pandas.
        values = np.loadtxt(
            io.StringIO(block),
            delimiter=None if delimiter == _SPACES else delimiter,
            comments=None,
            ndmin=2,
            dtype=np.float64,
        )
    except ValueError:
        return None
    if values.shape != (n_rows, n_columns) or not np.isfinite(values).all():
        return None
    return np.ascontiguousarray(values)


def _print_resolution(tokens: list[str]) -> float:
    """Spacing of the last printed digit of the coarsest of some numbers.

    ``'0.0000195'`` -> 1e-7, ``'1.28e+01'`` -> 0.1. Bare integers (such as a first
    time stamp written ``0``) say nothing about the precision and are skipped unless
    all tokens are integers.
    """
    resolutions = []
    for token in tokens:
        mantissa, marker, exponent = token.lower().partition("e")
        if "." in mantissa or marker:
            decimals = len(mantissa.partition(".")[2])
            resolutions.append(10.0 ** (int(exponent or 0) - decimals))
    return max(resolutions) if resolutions else 1.0


# --------------------------------------------------------------------------------------
# Run files: header


def _merge_unit_tokens(tokens: list[str]) -> list[str]:
    """Re-join whitespace tokens so that ``Time (s)`` stays one name."""
    merged: list[str] = []
    for token in tokens:
        open_unit = merged and merged[-1].count("(") > merged[-1].count(")")
        if merged and (token.startswith(("(", "[")) or open_unit):
            merged[-1] += " " + token
        else:
            merged.append(token)
    return merged


def _split_names(line: str, delimiter: str, n_columns: int) -> list[str] | None:
    """The line's cells when some reading of it gives exactly ``n_columns`` names."""
    stripped = line.strip()
    candidates = []
    if delimiter != _SPACES:
        candidates.append(_split_row(stripped, delimiter))
    candidates += [[cell.strip() for cell in stripped.split(d)] for d in ("\t", ",", ";")]
    candidates.append(re.split(r"\s{2,}", stripped))
    candidates.append(_merge_unit_tokens(stripped.split()))
    for names in candidates:
        names = [_unquoted(name) for name in names]
        if len(names) == n_columns and all(names):
            return names
    return None


def _unquoted(cell: str) -> str:
    """A cell without the quotes a CSV writer puts around text: ``"Force (N)"``."""
    cell = cell.strip()
    if len(cell) >= 2 and cell[0] == cell[-1] and cell[0] in "\"'":
        return cell[1:-1].strip()
    return cell


def _names_of(line: str, delimiter: str, n_columns: int) -> list[str] | None:
    names = _split_names(line, delimiter, n_columns)
    if names is None:
        return None
    roles = {column_role(name) for name in names} - {None}
    if not roles:
        return None
    # Split otherwise than the numbers are, a title ("Ring-down acceleration record") can
    # give as many words as there are columns: names must then name two roles at least.
    if n_columns >= 2 and len(roles) < 2 and not _splits_as_data(line, delimiter, n_columns):
        return None
    return names


def _splits_as_data(line: str, delimiter: str, n_columns: int) -> bool:
    """Whether ``line`` splits at the numbers' own delimiter into ``n_columns`` cells."""
    return delimiter != _SPACES and len(_split_row(line, delimiter)) == n_columns


def _is_key_value(line: str, delimiter: str, n_columns: int) -> bool:
    """A ``key: value`` header line, not a line of names that holds a colon
    (``Time (s)<TAB>Ch1: Acceleration (g)<TAB>Ch2: Force (lbf)``)."""
    if not _KEY_VALUE.fullmatch(line):
        return False
    if n_columns < 2 or not _splits_as_data(line, delimiter, n_columns):
        return True
    cells = [_unquoted(cell) for cell in _split_row(line, delimiter)]
    return len({column_role(cell) for cell in cells} - {None}) < 2


_KNOWN_UNIT_WORDS = {"s", "ms", "sec", "lbf", "N", "g", "m/s^2", "in/s^2", "m/s", "in/s", "m", "in"}


def _is_units_row(line: str, delimiter: str, n_columns: int) -> list[str] | None:
    """Cells of a line of bare units under the names (``s  lbf  g``), else None."""
    cells = _split_names(line, delimiter, n_columns)
    if cells is None:
        return None
    bare = [cell.strip("()[] ") for cell in cells]
    if all(units.normalize_unit(cell) in _KNOWN_UNIT_WORDS for cell in bare):
        return bare
    return None


def _canonical_header_key(key: str) -> tuple[str, str | None]:
    """``"Sample rate (Hz)"`` -> ``("sample rate", "Hz")``."""
    name, unit = split_name_unit(key)
    return re.sub(r"[\s_\-]+", " ", name.lower()).strip(), unit


_SAMPLE_RATE_KEYS = {
    "sample rate",
    "sampling rate",
    "sample frequency",
    "sampling frequency",
    "sampling freq",
    "sample freq",
    "fs",
}
_PRETRIGGER_KEYS = {
    "pre trigger",
    "pretrigger",
    "pre trigger samples",
    "pretrigger samples",
    "pre trigger length",
    "pretrigger length",
}
_RATE_FACTORS_HZ = {"": 1.0, "hz": 1.0, "khz": 1e3, "sps": 1.0, "samples/s": 1.0, "s/s": 1.0}
_PRETRIGGER_SAMPLE_UNITS = {"", "samples", "sample", "points", "pts"}
_PRETRIGGER_TIME_UNITS_S = {"s": 1.0, "sec": 1.0, "ms": 1e-3}


@dataclass(frozen=True)
class _HeaderValues:
    sample_rate_hz: float | None = None
    sample_rate_line: int | None = None
    pretrigger_samples: int | None = None
    pretrigger_s: float | None = None
    pretrigger_line: int | None = None
    entries: dict[str, str] = field(default_factory=dict)


def _header_values(lines: list[tuple[int, str]], path: str) -> _HeaderValues:
    """``key: value`` lines of the header, with sample rate and pre-trigger understood."""
    entries: dict[str, str] = {}
    rate = rate_line = pre_samples = pre_s = pre_line = None
    for number, line in lines:
        match = _KEY_VALUE.fullmatch(line)
        if not match:
            continue
        # a spreadsheet pads the line with empty cells: "Sample rate: 2560 Hz,,"
        key, value = match.group(1), match.group(2).rstrip(",;\t ")
        entries.setdefault(key, value)
        name, key_unit = _canonical_header_key(key)
        if name in _SAMPLE_RATE_KEYS and rate is None:
            parsed = _VALUE_WITH_UNIT.fullmatch(value)
            unit = (parsed.group(2) if parsed and parsed.group(2) else key_unit or "").lower()
            if not parsed or unit not in _RATE_FACTORS_HZ or not 0 < float(parsed.group(1)) < math.inf:
                raise CampaignFormatError(
                    path, number, f"cannot read a positive sample rate in Hz from {quoted(line.strip())}"
                )
            rate, rate_line = float(parsed.group(1)) * _RATE_FACTORS_HZ[unit], number
        elif name in _PRETRIGGER_KEYS and pre_line is None:
            parsed = _VALUE_WITH_UNIT.fullmatch(value)
            unit = (parsed.group(2) if parsed and parsed.group(2) else key_unit or "").lower()
            amount = float(parsed.group(1)) if parsed else -1.0
            amount = amount if math.isfinite(amount) else -1.0
            if parsed and amount >= 0 and unit in _PRETRIGGER_SAMPLE_UNITS and amount == round(amount):
                pre_samples, pre_line = int(round(amount)), number
            elif parsed and amount >= 0 and unit in _PRETRIGGER_TIME_UNITS_S:
                pre_s, pre_line = amount * _PRETRIGGER_TIME_UNITS_S[unit], number
            else:
                raise CampaignFormatError(
                    path,
                    number,
                    f"cannot read the pre-trigger from {quoted(line.strip())} "
                    "(expected a whole number of samples, e.g. 'Pre-trigger: 25 samples')",
                )
    return _HeaderValues(rate, rate_line, pre_samples, pre_s, pre_line, entries)


# --------------------------------------------------------------------------------------
# Run files: the record


def response_unit(file_unit: str | None, campaign: Campaign, what: str) -> str:
    """The unit of a response channel: the one its file records, which must be a unit of
    campaign.yaml's response quantity and agree with campaign.yaml's ``unit`` when given;
    else campaign.yaml's (campaign.yaml fills only what the file leaves out).

    Parameters
    ----------
    file_unit : str or None
        The unit the file records for the channel (None: none).
    campaign : Campaign
        The validated campaign.yaml.
    what : str
        How the message names the channel, e.g. ``response column 'acc1 (g)'``.

    Raises
    ------
    ValueError
        The file's unit is no unit of the quantity or disagrees with campaign.yaml, or
        neither gives one; the message names the channel (the caller adds the file).
    """
    quantity, yaml_unit = campaign.response.quantity, campaign.response.unit
    if file_unit is None:
        if yaml_unit is None:
            raise ValueError(
                f"{what}: the file records no unit and campaign.yaml gives none; "
                "add unit to response in campaign.yaml"
            )
        return yaml_unit
    canonical = units.normalize_unit(file_unit)
    if canonical not in units.known_units(quantity):
        raise ValueError(
            f"{what}: unit {quoted(file_unit)} in the file is not a unit of {quantity} "
            f"(campaign.yaml response quantity); expected one of {', '.join(units.known_units(quantity))}"
        )
    if yaml_unit is not None and canonical != yaml_unit:
        raise ValueError(
            f"{what}: unit {quoted(file_unit)} in the file disagrees with campaign.yaml response unit "
            f"{yaml_unit!r} ({quantity})"
        )
    return canonical


@dataclass(frozen=True, eq=False)
class ResponseChannel:
    """One response channel of a run, in its own unit.

    Attributes
    ----------
    name : str
        The channel's name in every table: campaign.yaml's reference
        (:meth:`ResponseSpec.channel_names`).
    values : ndarray
        The samples.
    unit : str
        Canonical unit of ``values``.
    source : str
        The file's own name for the channel (column name, system channel name; empty
        for an unnamed ASCII column).
    """

    name: str
    values: NDArray[np.float64]
    unit: str
    source: str = ""


@dataclass(frozen=True, eq=False)
class RunRecord:
    """One run file, read and checked.

    Attributes
    ----------
    path : str
        The file's path relative to the campaign folder (``/`` separators).
    sample_rate_hz : float
        Samples per second.
    pretrigger_samples : int
        Samples recorded before the trigger.
    time_s : ndarray or None
        The file's time column in s, when it has one.
    force_lbf : ndarray or None
        Hammer force in lbf, when recorded.
    response : ndarray
        The response in the campaign's response unit, as in the file.
    response_quantity : str
        acceleration, velocity or displacement.
    response_unit : str
        Canonical unit of ``response``.
    header : dict
        The header's ``key: value`` lines (raw strings).
    n_samples : int
        Number of samples.
    column_names : tuple of str
        Names from the header's line of names (empty without one).
    sample_rate_source : str
        Where the sample rate came from: ``campaign.yaml``, ``header`` or ``time column``.
    pretrigger_source : str
        ``campaign.yaml``, ``header``, ``time column`` (a time column that starts before
        0) or ``default`` (contract default 0, not stated).
    record_start : str
        Wall-clock time the recording started, ISO 8601, when the file states it
        (:mod:`workflow.io.recording_time`); empty otherwise (ASCII files).
    responses : tuple of ResponseChannel
        Every response channel campaign.yaml asks for, in its order; ``response`` and
        ``response_unit`` are the first's (:meth:`for_channel` picks another).
    """

    path: str
    sample_rate_hz: float
    pretrigger_samples: int
    time_s: NDArray[np.float64] | None
    force_lbf: NDArray[np.float64] | None
    response: NDArray[np.float64]
    response_quantity: str
    response_unit: str
    header: dict[str, str]
    n_samples: int
    column_names: tuple[str, ...] = ()
    sample_rate_source: str = "campaign.yaml"
    pretrigger_source: str = "default"
    record_start: str = ""
    responses: tuple[ResponseChannel, ...] = ()

    def channel_names(self) -> tuple[str, ...]:
        """The names of :attr:`responses`."""
        return tuple(channel.name for channel in self.responses)

    def for_channel(self, name: str) -> RunRecord:
        """The record with ``response`` and ``response_unit`` of the response channel
        ``name`` (KeyError when the record has none of that name)."""
        for channel in self.responses:
            if channel.name == name:
                if channel.values is self.response:
                    return self
                return replace(self, response=channel.values, response_unit=channel.unit)
        raise KeyError(f"{self.path}: no response channel {name!r} (has {', '.join(self.channel_names())})")


@dataclass(frozen=True)
class _Columns:
    roles: dict[str, int]
    units: dict[str, str | None]
    names: tuple[str, ...]
    line: int | None
    responses: tuple[int, ...] = ()
    """The response columns, one per campaign.yaml channel (``roles["response"]`` is the first)."""
    response_units: tuple[str | None, ...] = ()
    """Each response column's unit as written (None: none given)."""


_WIDE_ENCODINGS = (
    (b"\xff\xfe\x00\x00", "UTF-32 (little-endian)"),
    (b"\x00\x00\xfe\xff", "UTF-32 (big-endian)"),
    (b"\xff\xfe", "UTF-16 (little-endian)"),
    (b"\xfe\xff", "UTF-16 (big-endian)"),
)


def _wide_encoding(raw: bytes) -> str | None:
    """The name of a UTF-16/UTF-32 encoding the bytes are written in, from the byte-order
    mark or, without one, from NUL bytes alternating with ASCII text; else None."""
    for mark, name in _WIDE_ENCODINGS:
        if raw.startswith(mark):
            return name
    head = raw[:4096]
    if len(head) >= 8:
        even_nul = head[0::2].count(0) / len(head[0::2])
        odd_nul = head[1::2].count(0) / len(head[1::2])
        if odd_nul > 0.9 and even_nul < 0.1:
            return "UTF-16 (little-endian)"
        if even_nul > 0.9 and odd_nul < 0.1:
            return "UTF-16 (big-endian)"
    return None


def _read_text(path: Path, shown: str) -> str:
    """File text with LF line ends (UTF-8, else Windows-1252 for old exports)."""
    try:
        with open(path, "rb") as handle:  # read-only: raw files are never modified
            raw = handle.read()
    except OSError as error:
        raise CampaignFormatError(shown, None, f"cannot be read: {error.strerror or error}") from None
    encoding = _wide_encoding(raw)
    if encoding is not None:
        raise CampaignFormatError(
            shown,
            None,
            f"text encoded as {encoding}: run files must be ASCII or UTF-8 text "
            "(save the export as ASCII/UTF-8, or convert it, e.g. with iconv)",
        )
    nul = raw.find(b"\x00")
    if nul >= 0:
        # lines end in LF, CRLF or a lone CR, as the text is read below
        line_ends = raw.count(b"\n", 0, nul) + raw.count(b"\r", 0, nul) - raw.count(b"\r\n", 0, nul)
        raise CampaignFormatError(shown, line_ends + 1, "binary data (NUL byte): not a text export")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    del raw  # a long record: hold one copy of its text at a time
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text


_COMMA_SEPARATED_CELL = re.compile(r"[^\t; \n]*,[^\t; \n]*[,.]|[^\t; \n]*\.[^\t; \n]*,")


_NUMERIC_CHARACTERS = re.compile(r"[0-9eE+\-.,;\t ]+")


def _decimal_commas_to_points(text: str, shown: str) -> str:
    """Text of a file written with decimal commas, with decimal points instead.

    In a row of numbers, a cell holding two commas, or a comma and a point, means commas
    also separate the columns (or mark thousands), which cannot be told apart from
    decimal commas. A header line of text with such a cell (a date: ``12.05.2004, 14:03``)
    is left as it is.
    """
    lines = text.split("\n")
    for number, line in enumerate(lines, start=1):
        clash = _COMMA_SEPARATED_CELL.search(line)
        if clash is None:
            lines[number - 1] = line.replace(",", ".")
        elif _NUMERIC_CHARACTERS.fullmatch(line.strip()):
            raise CampaignFormatError(
                shown,
                number,
                f"campaign.yaml says decimal: ',' but {quoted(clash.group(0))} holds more than one separator; "
                "with decimal commas the columns must be separated by tabs, semicolons or spaces",
            )
    return "\n".join(lines)


def _locate_numbers(text: str) -> tuple[list[tuple[int, str]], int, int]:
    """Header lines, character offset and 1-based line of the first numeric row."""
    header: list[tuple[int, str]] = []
    position, number = 0, 0
    while position < len(text):
        end = text.find("\n", position)
        end = len(text) if end < 0 else end
        line = text[position:end]
        number += 1
        if line.strip() and _is_numeric_row(line):
            return header, position, number
        header.append((number, line))
        position = end + 1
    return header, -1, number


def _majority(items: list[Any], fallback: Any) -> Any:
    if not items:
        return fallback
    counts = Counter(items)
    best = max(counts.values())
    return next(item for item in items if counts[item] == best)


def _find_columns(
    header: list[tuple[int, str]],
    first_line: int,
    delimiter: str,
    n_columns: int,
    campaign: Campaign,
    path: str,
) -> _Columns:
    """Column roles and units from the line of names, or the positional rules."""
    text_lines = [
        (number, line)
        for number, line in header
        if line.strip() and not _is_key_value(line, delimiter, n_columns)
    ]
    # A first data row with a bad cell is not numeric and so lands in the header:
    # recognise it by its shape so that it is reported instead of silently dropped.
    if text_lines and text_lines[-1][0] == first_line - 1:
        number, line = text_lines[-1]
        tokens = [t for t in re.split(r"[\t,;\s]+", line.strip()) if t]
        # With several columns a bad row may also have lost or gained a cell; with one
        # column only an exact match is taken, so that a title line stays a title.
        counts = (n_columns,) if n_columns == 1 else (n_columns - 1, n_columns, n_columns + 1)
        if len(tokens) in counts and any(_is_data_like(t) for t in tokens):
            problem = _row_problem(line, delimiter, n_columns, first_line) or "not a numeric row"
            raise CampaignFormatError(path, number, problem)

    names, names_line, units_cells = None, None, None
    if text_lines:
        last_number, last_line = text_lines[-1]
        names = _names_of(last_line, delimiter, n_columns)
        names_line = last_number if names else None
        if names is None and len(text_lines) >= 2:
            above_number, above_line = text_lines[-2]
            above = _names_of(above_line, delimiter, n_columns)
            if above is not None:
                units_cells = _is_units_row(last_line, delimiter, n_columns)
                if units_cells is None:
                    raise CampaignFormatError(
                        path,
                        last_number,
                        f"unexpected text {quoted(last_line.strip())} between the column names "
                        f"(line {above_number}) and the numbers",
                    )
                names, names_line = above, above_number
        if names is None:
            roles_in_line = {column_role(t) for t in _merge_unit_tokens(last_line.split())} - {None}
            if len(roles_in_line) >= 2:
                raise CampaignFormatError(
                    path,
                    last_number,
                    f"the column names do not match the {n_columns} column(s) of numbers",
                )

    references = campaign.response.references()
    if references != (None,):
        return _named_response_columns(names, names_line, units_cells, n_columns, first_line, campaign, path)
    if names is None:
        order = _positional_roles(n_columns, 0, campaign)
        if order is None:
            raise CampaignFormatError(
                path,
                first_line,
                f"{n_columns} columns and no line of column names: cannot tell which is "
                "the response (name the columns, e.g. 'Time (s)  Force (lbf)  Acceleration (g)')",
            )
        roles = {role: i for i, role in enumerate(order)}
        return _Columns(roles, {}, (), None, (roles["response"],), (None,))

    for name in names:
        long_name = name_length_problem("column name", name)
        if long_name is not None:
            raise CampaignFormatError(path, names_line, long_name)
    roles: dict[str, int] = {}
    column_units: dict[str, str | None] = {}
    for index, name in enumerate(names):
        role = column_role(name)
        if role is None:
            continue  # columns with other names (extra channels) are not used
        if role in roles:
            raise CampaignFormatError(
                path,
                names_line,
                f"two {role} columns: {quoted(names[roles[role]])} and {quoted(name)}",
            )
        roles[role] = index
        unit = split_name_unit(name)[1]
        if unit is None and any(bracket in name for bracket in "()[]"):
            raise CampaignFormatError(
                path,
                names_line,
                f"the unit of the {role} column {quoted(name)} cannot be read: write one unit in "
                "parentheses or brackets after the name, e.g. 'Acceleration (m/s^2)' or 'Force [N]'",
            )
        if units_cells is not None:
            unit = units_cells[index]
        column_units[role] = unit
    if "response" not in roles:
        raise CampaignFormatError(
            path,
            names_line,
            f"no response column among {[shortened(name) for name in names][:MAX_QUOTED_PROBLEMS]} (a response column's name contains acc, vel, resp or disp)",
        )
    response_name = split_name_unit(names[roles["response"]])[0].lower()
    for word, quantity in (("acc", "acceleration"), ("vel", "velocity"), ("disp", "displacement")):
        if word in response_name and quantity != campaign.response.quantity:
            raise CampaignFormatError(
                path,
                names_line,
                f"response column {quoted(names[roles['response']])} is {quantity} but "
                f"campaign.yaml says response quantity {campaign.response.quantity}",
            )
    return _Columns(
        roles, column_units, tuple(names), names_line, (roles["response"],), (column_units["response"],)
    )


def _positional_roles(n_columns: int, n_responses: int, campaign: Campaign) -> tuple[str, ...] | None:
    """Roles of a file's columns without a line of names (the contract's positional rules),
    or None when they do not decide. With ``n_responses`` > 0 the responses are already
    picked by index and the roles are those of the other columns, in order."""
    if n_responses == 0:
        if n_columns == 3:
            return ("time", "force", "response")
        if n_columns == 2:
            return ("force", "response") if campaign.force is not None else ("time", "response")
        return ("response",) if n_columns == 1 else None
    others = n_columns - n_responses
    if others == 2:
        return ("time", "force")
    if others == 1:
        return ("force",) if campaign.force is not None else ("time",)
    return () if others == 0 else None


def _named_response_columns(
    names: list[str] | None,
    names_line: int | None,
    units_cells: list[str] | None,
    n_columns: int,
    first_line: int,
    campaign: Campaign,
    path: str,
) -> _Columns:
    """Columns of a file whose response channels campaign.yaml names (``channel`` or
    ``channels``): a name is a column's name without its unit (case ignored), an index
    counts the columns from 0; the time and force columns keep the contract's rules."""
    references = campaign.response.references()
    key = "response.channels" if campaign.response.channels is not None else "response.channel"
    for name in names or ():
        long_name = name_length_problem("column name", name)
        if long_name is not None:
            raise CampaignFormatError(path, names_line, long_name)
    listing = ", ".join(f"[{i}] {quoted(name)}" for i, name in enumerate(names)) if names else ""
    bare = [split_name_unit(name)[0].strip().lower() for name in names] if names else []
    responses = []
    for reference in references:
        if isinstance(reference, int):
            if reference >= n_columns:
                raise CampaignFormatError(
                    path,
                    names_line,
                    f"campaign.yaml {key}: {reference} but the file has {n_columns} column(s)",
                )
            responses.append(reference)
            continue
        if names is None:
            raise CampaignFormatError(
                path,
                first_line,
                f"campaign.yaml {key}: {quoted(reference)} names a column but the file has no line of column names",
            )
        matches = [i for i, name in enumerate(names) if name == reference]
        matches = matches or [i for i, name in enumerate(bare) if name == reference.strip().lower()]
        if len(matches) != 1:
            found = "several columns" if matches else "no column"
            raise CampaignFormatError(
                path,
                names_line,
                f"campaign.yaml {key}: {quoted(reference)} matches {found}; the columns: {listing}",
            )
        responses.append(matches[0])
    roles: dict[str, int] = {}
    column_units: dict[str, str | None] = {}
    others = [index for index in range(n_columns) if index not in responses]
    if names is None:
        order = _positional_roles(n_columns, len(responses), campaign)
        if order is None:
            raise CampaignFormatError(
                path,
                first_line,
                f"{n_columns} columns and no line of column names: cannot tell which are the time "
                "and force columns (name the columns)",
            )
        roles = {role: index for role, index in zip(order, others)}
    else:
        for index in others:
            role = column_role(names[index])
            if role in ("time", "force"):
                if role in roles:
                    raise CampaignFormatError(
                        path,
                        names_line,
                        f"two {role} columns: {quoted(names[roles[role]])} and {quoted(names[index])}",
                    )
                roles[role] = index
                column_units[role] = (
                    units_cells[index] if units_cells is not None else split_name_unit(names[index])[1]
                )
        for index in responses:
            for word, quantity in (("acc", "acceleration"), ("vel", "velocity"), ("disp", "displacement")):
                if word in bare[index] and quantity != campaign.response.quantity:
                    raise CampaignFormatError(
                        path,
                        names_line,
                        f"response column {quoted(names[index])} is {quantity} but campaign.yaml says "
                        f"response quantity {campaign.response.quantity}",
                    )
    response_units = tuple(
        None
        if names is None
        else (units_cells[i] if units_cells is not None else split_name_unit(names[i])[1])
        for i in responses
    )
    roles["response"] = responses[0]
    column_units["response"] = response_units[0]
    return _Columns(roles, column_units, tuple(names or ()), names_line, tuple(responses), response_units)


def _response_column_units(columns: _Columns, campaign: Campaign, path: str) -> tuple[str, ...]:
    """Each response column's canonical unit (:func:`response_unit`)."""
    found = []
    for index, unit in zip(columns.responses, columns.response_units):
        what = (
            f"response column {quoted(columns.names[index])}"
            if columns.names
            else f"response column {index + 1}"
        )
        try:
            found.append(response_unit(unit, campaign, what))
        except ValueError as error:
            raise CampaignFormatError(path, columns.line, str(error)) from None
    return tuple(found)


_TIME_UNIT_FACTORS_S = {
    **dict.fromkeys(("s", "sec", "secs", "second", "seconds"), 1.0),
    **dict.fromkeys(("ms", "msec", "millisecond", "milliseconds"), 1e-3),
}
"""Spellings of a time column's unit, and the factor to seconds."""


def _column_unit_factors(columns: _Columns, campaign: Campaign, path: str) -> tuple[float, float]:
    """Factors taking the time column to s and the force column to lbf; checks units."""
    line = columns.line
    time_factor_s = 1.0
    time_unit = columns.units.get("time")
    if time_unit:
        time_factor_s = _TIME_UNIT_FACTORS_S.get(time_unit.strip().lower(), 0.0)
        if time_factor_s == 0.0:
            raise CampaignFormatError(path, line, f"time column unit {quoted(time_unit)}: expected s or ms")
    force_factor_lbf = 1.0
    if "force" in columns.roles:
        file_unit = columns.units.get("force")
        yaml_unit = campaign.force.unit if campaign.force is not None else None
        if file_unit:
            canonical = units.normalize_unit(file_unit)
            if canonical not in units.known_units("force"):
                raise CampaignFormatError(
                    path, line, f"force column unit {quoted(file_unit)}: expected lbf or N"
                )
            if yaml_unit is not None and canonical != yaml_unit:
                raise CampaignFormatError(
                    path,
                    line,
                    f"force column unit {quoted(file_unit)} disagrees with campaign.yaml force unit {yaml_unit!r}",
                )
        # The column's own unit first; else campaign.yaml's; else the original lab's lbf.
        unit = units.normalize_unit(file_unit) if file_unit else (yaml_unit or "lbf")
        force_factor_lbf = units.factor_to_internal("force", unit)
    return time_factor_s, force_factor_lbf


def _check_magnitude(
    column: NDArray[np.float64], role: str, index: int, columns: _Columns, first_line: int, path: str
) -> None:
    """Refuse a force or response column (0-based ``index``) the analysis cannot square
    (:mod:`workflow.io.limits`), naming the line of the first such value."""
    name = f" {quoted(columns.names[index])}" if columns.names else ""
    problem = magnitude_problem(column, f"{role} column {index + 1}{name}")
    if problem is not None:
        raise CampaignFormatError(path, first_line + problem[0], problem[1])


def _check_time(time_s: NDArray[np.float64], resolution_s: float, first_line: int, path: str) -> float:
    """Sample rate (Hz) from a time column that must increase in uniform steps."""
    steps = np.diff(time_s)
    bad = first_bad_time_step(steps, resolution_s)
    if bad is not None:
        i, typical_s = bad
        if steps[i] <= 0.0:
            problem = f"time column not increasing: {time_s[i + 1]:.9g} s follows {time_s[i]:.9g} s"
        elif i + 1 < steps.size and steps[i + 1] <= 0.0:
            # a stamp ahead of its neighbours (a spike, two rows swapped): this line is the wrong one
            problem = (
                f"time column out of order: {time_s[i + 1]:.9g} s is followed by {time_s[i + 2]:.9g} s "
                "on the next line"
            )
        else:
            tolerance_s = TIME_STEP_REL_TOLERANCE * typical_s + resolution_s
            problem = (
                f"time column not uniform: step {steps[i]:.6g} s (from {time_s[i]:.9g} s on the line "
                f"before) differs from the record's typical step {typical_s:.6g} s by "
                f"{100 * abs(steps[i] / typical_s - 1):.3g} % (tolerance {100 * tolerance_s / typical_s:.3g} %)"
            )
        raise CampaignFormatError(path, first_line + i + 1, problem)
    return (time_s.size - 1) / (time_s[-1] - time_s[0])


HEAD_BYTES: int = 65536
"""Bytes of a run file that :func:`declared_sample_rate_hz` reads: enough for any header
and the first rows of the numbers."""


def declared_sample_rate_hz(campaign_dir: str | Path, run_file: RunFile, campaign: Campaign) -> float | None:
    """The sample rate (Hz) a run file declares, from its first :data:`HEAD_BYTES` only:
    campaign.yaml's ``sample_rate_hz``, else the header's, else the step of the first
    rows of the time column; None when the head does not tell (or cannot be read: the
    full read then reports why).

    Planning checks campaign.yaml's band and mode against it before any job runs,
    without reading whole records.
    """
    if campaign.sample_rate_hz is not None:
        return campaign.sample_rate_hz
    path = Path(campaign_dir) / run_file.path
    shown = path.as_posix()
    try:
        with open(path, "rb") as handle:
            raw = handle.read(HEAD_BYTES)
        if _wide_encoding(raw) is not None or b"\x00" in raw:
            return None
        text = raw.decode("utf-8-sig", errors="replace").replace("\r\n", "\n").replace("\r", "\n")
        header, offset, first_line = _locate_numbers(text)
        if offset < 0:
            return None
        header_values = _header_values(header, shown)
        if header_values.sample_rate_hz is not None:
            return header_values.sample_rate_hz
        rows = [row for row in text[offset:].split("\n")[:HEAD_ROWS] if row.strip()]
        delimiter = _majority([_line_delimiter(row) for row in rows], _SPACES)
        n_columns = _majority([len(_split_row(row, delimiter)) for row in rows], 1)
        columns = _find_columns(header, first_line, delimiter, n_columns, campaign, shown)
        if "time" not in columns.roles:
            return None
        time_factor_s = _column_unit_factors(columns, campaign, shown)[0]
        time_s = np.array([float(_split_row(row, delimiter)[columns.roles["time"]]) for row in rows[:-1]])
    except (OSError, ValueError, IndexError):  # CampaignFormatError is a ValueError
        return None
    steps_s = np.diff(time_s) * time_factor_s
    if steps_s.size == 0 or not np.all(steps_s > 0):
        return None
    return float(1.0 / np.mean(steps_s))


def _checked_against_band(record: RunRecord, campaign: Campaign, shown: str) -> RunRecord:
    """A system-format record whose own sample rate cannot hold campaign.yaml's band and
    mode is refused, as an ASCII one is."""
    problem = frequency_problem(campaign, record.sample_rate_hz, f"the file's {record.sample_rate_source}")
    if problem is not None:
        raise CampaignFormatError(shown, None, f"campaign.yaml {problem}")
    return record


def read_run(
    campaign_dir: str | Path, run_file_or_path: RunFile | str | Path, campaign: Campaign
) -> RunRecord:
    """Read one run file and check it against the input contract.

    Parameters
    ----------
    campaign_dir : str or Path
        The campaign folder.
    run_file_or_path : RunFile, str or Path
        The run, or its path (relative to ``campaign_dir``, or absolute).
    campaign : Campaign
        The campaign's validated campaign.yaml.

    Returns
    -------
    RunRecord
        Response in the campaign's unit, force in lbf, time in s.

    Raises
    ------
    CampaignFormatError
        Any malformed input; the message names the file (as
        ``campaign_dir/relative path``), the line and the problem.
    """
    root = Path(campaign_dir)
    given = Path(run_file_or_path.path if isinstance(run_file_or_path, RunFile) else run_file_or_path)
    full = given if given.is_absolute() else root / given
    try:
        relative = full.relative_to(root).as_posix()
    except ValueError:
        relative = full.as_posix()
    shown = full.as_posix()
    if not full.exists():
        raise CampaignFormatError(shown, None, "no such file")
    reason = _unreadable_reason(full, root.resolve())
    if reason is not None:
        raise CampaignFormatError(shown, None, reason)
    if full.suffix.lower() in SYSTEM_FORMAT_EXTENSIONS:
        from workflow.io.readers import read_system_run

        return _checked_against_band(read_system_run(full, relative, shown, campaign), campaign, shown)

    text = _read_text(full, shown)
    if campaign.decimal == ",":
        text = _decimal_commas_to_points(text, shown)
    if not text.strip():
        raise CampaignFormatError(shown, 1, "the file is empty")
    header, offset, first_line = _locate_numbers(text)
    if offset < 0:
        comma_line = next(
            (number for number, line in header if line.strip() and _is_decimal_comma_row(line)), None
        )
        if comma_line is not None:
            raise CampaignFormatError(
                shown, comma_line, f"{DECIMAL_COMMA_HINT}: {header[comma_line - 1][1].strip()[:60]!r}"
            )
        last_line = len(text.rstrip("\n").split("\n"))
        raise CampaignFormatError(
            shown,
            last_line,
            f"no numeric rows: all {last_line} line(s) are header text (expected numbers "
            "after the header, one sample per line)",
        )

    # The numbers are text[offset:end]; no copy of them is made (a long record's text
    # is the largest thing a run-analysis job holds).
    end = len(text)
    while end > offset and text[end - 1].isspace():
        end -= 1
    head_end = offset
    for _ in range(HEAD_ROWS):
        head_end = text.find("\n", head_end + 1, end)
        if head_end < 0:
            head_end = end
            break
    rows_head = [row for row in text[offset:head_end].split("\n") if row.strip()]
    delimiter = _majority([_line_delimiter(row) for row in rows_head], _SPACES)
    n_columns = _majority([len(_split_row(row, delimiter)) for row in rows_head], 1)
    n_rows = text.count("\n", offset, end) + 1

    header_values = _header_values(header, shown)
    columns = _find_columns(header, first_line, delimiter, n_columns, campaign, shown)
    time_factor_s, force_factor_lbf = _column_unit_factors(columns, campaign, shown)
    response_units = _response_column_units(columns, campaign, shown)

    values = _parse_text_fast(text, offset, end, delimiter, n_rows, n_columns)
    if values is None:
        values = _parse_block_careful(text[offset:end].split("\n"), first_line, delimiter, n_columns, shown)
    last_data_line = first_line + n_rows - 1
    if n_rows < MIN_SAMPLES:
        raise CampaignFormatError(
            shown,
            last_data_line,
            f"only {n_rows} samples; a run needs at least {MIN_SAMPLES}",
        )

    # Sample rate: campaign.yaml, then the header, then the time column; any two
    # sources that are present must agree.
    sources: list[tuple[str, float, int | None, float]] = []
    if campaign.sample_rate_hz is not None:
        sources.append(("campaign.yaml sample_rate_hz", campaign.sample_rate_hz, None, 0.0))
    if header_values.sample_rate_hz is not None:
        sources.append(("header", header_values.sample_rate_hz, header_values.sample_rate_line, 0.0))
    time_s = None
    if "time" in columns.roles:
        time_s = values[:, columns.roles["time"]] * time_factor_s
        first_row, last_row = rows_head[0], text[max(text.rfind("\n", offset, end), offset - 1) + 1 : end]
        resolution_s = time_factor_s * _print_resolution(
            [_split_row(row, delimiter)[columns.roles["time"]] for row in (first_row, last_row)]
        )
        rate_hz = _check_time(time_s, resolution_s, first_line, shown)
        duration_s = time_s[-1] - time_s[0]
        sources.append(("time column", rate_hz, first_line, 2.0 * resolution_s / duration_s))
    if not sources:
        raise CampaignFormatError(
            shown,
            None,
            "sample rate missing: no time column, no 'Sample rate: ... Hz' header line "
            "and no sample_rate_hz in campaign.yaml",
        )
    for i, (name_a, rate_a, line_a, slack_a) in enumerate(sources):
        for name_b, rate_b, line_b, slack_b in sources[i + 1 :]:
            if not rates_agree(rate_a, rate_b, slack_a + slack_b):
                raise CampaignFormatError(
                    shown,
                    line_b if line_b is not None else line_a,
                    f"sample rate {rate_b:.9g} Hz from the {name_b} disagrees with "
                    f"{rate_a:.9g} Hz from the {name_a}",
                )
    source_name, sample_rate_hz = sources[0][0], sources[0][1]
    rate_line = sources[0][2]
    rate_source = source_name if rate_line is None else f"{source_name}, line {rate_line}"
    problem = frequency_problem(campaign, sample_rate_hz, rate_source)
    if problem is not None:
        raise CampaignFormatError(shown, rate_line, f"campaign.yaml {problem}")
    sample_rate_source = "campaign.yaml" if source_name.startswith("campaign") else source_name

    pretrigger_samples, pretrigger_source = campaign.pretrigger_samples, "default"
    if header_values.pretrigger_line is not None:
        header_pre = header_values.pretrigger_samples
        if header_pre is None:
            header_pre = int(round(header_values.pretrigger_s * sample_rate_hz))
        if campaign.pretrigger_given and header_pre != campaign.pretrigger_samples:
            raise CampaignFormatError(
                shown,
                header_values.pretrigger_line,
                f"pre-trigger {header_pre} samples in the header disagrees with "
                f"campaign.yaml pretrigger_samples {campaign.pretrigger_samples}",
            )
        pretrigger_samples, pretrigger_source = header_pre, "header"
    if time_s is not None and time_s[0] * sample_rate_hz <= -0.5:
        # a time column that starts before 0 counts the samples before the trigger
        time_pre = int(round(-time_s[0] * sample_rate_hz))
        stated = {
            "header": (header_values.pretrigger_line is not None, pretrigger_samples),
            "campaign.yaml pretrigger_samples": (campaign.pretrigger_given, campaign.pretrigger_samples),
        }
        for where, (given, samples) in stated.items():
            if given and samples != time_pre:
                raise CampaignFormatError(
                    shown,
                    first_line,
                    f"the time column starts at {time_s[0]:.9g} s, a pre-trigger of {time_pre} samples, "
                    f"but the {where} says {samples} samples",
                )
        pretrigger_samples, pretrigger_source = time_pre, "time column"
    if campaign.pretrigger_given:
        pretrigger_source = "campaign.yaml"
    if pretrigger_samples >= n_rows:
        raise CampaignFormatError(
            shown,
            header_values.pretrigger_line,
            f"pre-trigger of {pretrigger_samples} samples is not shorter than the record ({n_rows} samples)",
        )

    checked = [("force", columns.roles["force"])] if "force" in columns.roles else []
    for role, index in checked + [("response", index) for index in columns.responses]:
        _check_magnitude(values[:, index], role, index, columns, first_line, shown)
    force_lbf = None
    if "force" in columns.roles:
        force_lbf = values[:, columns.roles["force"]] * force_factor_lbf
    responses = tuple(
        ResponseChannel(
            name, np.ascontiguousarray(values[:, index]), unit, columns.names[index] if columns.names else ""
        )
        for name, index, unit in zip(campaign.response.channel_names(), columns.responses, response_units)
    )
    response = responses[0].values
    return RunRecord(
        path=relative,
        sample_rate_hz=float(sample_rate_hz),
        pretrigger_samples=int(pretrigger_samples),
        time_s=None if time_s is None else np.ascontiguousarray(time_s),
        force_lbf=None if force_lbf is None else np.ascontiguousarray(force_lbf),
        response=response,
        response_quantity=campaign.response.quantity,
        response_unit=responses[0].unit,
        header=dict(header_values.entries),
        n_samples=int(n_rows),
        column_names=columns.names,
        sample_rate_source=sample_rate_source,
        pretrigger_source=pretrigger_source,
        responses=responses,
    )
