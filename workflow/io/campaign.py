"""campaign.yaml: its schema and settings, read and validated (:func:`load_campaign`).

This module implements the campaign.yaml part of the input contract of
``campaign-format.md``. Every malformed input becomes a
:class:`~workflow.io.records.CampaignFormatError` that names the file, the line (when the
problem belongs to one) and what is wrong, so that a person can fix the file; the raw
files are only ever opened for reading. The run files are found and read by
:mod:`workflow.io.run_files`.

Decisions where the contract leaves room (documented here because outside campaigns
are run against them):

- ``name`` may be omitted from campaign.yaml; the campaign folder's name is used.
- A configuration given with no settings (``decay:`` or ``decay: {}``) takes the defaults.
"""

from __future__ import annotations

import datetime
import math
import re
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from dataclasses import fields as dataclass_fields
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from annotated_types import Ge, Gt, MinLen

from workflow.io import limits, units
from workflow.io.limits import MAX_QUOTED_PROBLEMS, QUOTED_CHARACTERS, name_length_problem, quoted, shortened
from workflow.io.validation import (
    FORBID_UNKNOWN_KEYS,
    MISSING_KEY_ERRORS,
    UNKNOWN_KEY_ERRORS,
    After,
    validate,
)

if TYPE_CHECKING:
    import yaml
from workflow.io.path_checks import link_problem
from workflow.io.records import CampaignFormatError

__all__ = [
    "CAMPAIGN_FILE",
    "CONFIGURATION_NAME",
    "MAX_CAMPAIGN_YAML_BYTES",
    "MAX_YAML_VALUES",
    "SINGLE_CHANNEL_NAME",
    "ResponseSpec",
    "ForceSpec",
    "ConfigurationSpec",
    "Campaign",
    "campaign_to_dict",
    "campaign_from_dict",
    "load_campaign",
    "frequency_problem",
    "response_unit",
    "response_units",
    "force_unit",
]


CAMPAIGN_FILE: str = "campaign.yaml"


CONFIGURATION_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,63}")
"""What a configuration name may be: it becomes part of output paths and Snakemake
wildcards, so no ``/``, ``..``, spaces or shell characters (docs/input-safety.md)."""


MAX_CAMPAIGN_YAML_BYTES: int = 1_000_000
"""Largest campaign.yaml read; a real one is a few kilobytes."""


MAX_YAML_VALUES: int = 100_000
"""Most values campaign.yaml may hold once its aliases are expanded: a bound on the
work of validating it, whatever its aliases and nesting (an alias bomb is refused)."""


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

    quantity: Literal["acceleration", "velocity", "displacement"] | None = None
    """What every response channel records; the unit's quantity when only ``unit`` is
    given; None when every run file records each channel's unit, each channel then
    recording its unit's quantity (accelerometers beside a laser vibrometer)."""
    unit: str | None = None
    """Canonical unit name (g, m/s^2, in/s^2, mm/s^2, m/s, in/s, mm/s, m, in, mm, um); None when every run file
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
        if self.quantity is None:
            quantity = units.response_quantity_of(canonical)
            if quantity is None:
                raise ValueError(
                    f"unit {self.unit!r} is no response unit; expected one of {', '.join(units.RESPONSE_UNITS)}"
                )
            object.__setattr__(self, "quantity", quantity)
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

    def bearing_areas_in2(self) -> dict[str, float | None]:
        """Configuration -> bearing area (in^2) as campaign.yaml states it, None where it
        states none, in campaign.yaml's order."""
        return {name: spec.bearing_area_in2 for name, spec in self.configurations.items()}


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

    Examples
    --------
    >>> campaign = load_campaign(Path(__file__).parents[2] / "tests" / "data" / "example_campaign")
    >>> sorted(campaign.configurations), campaign.response.quantity
    (['no_washer', 'small_washer'], 'acceleration')
    """
    import yaml
    from pydantic import ValidationError

    path = Path(campaign_dir) / CAMPAIGN_FILE
    outside = link_problem(path, Path(campaign_dir).resolve())
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
            path,
            None,
            "missing: every campaign folder needs a campaign.yaml naming its configurations and "
            "what the run files hold (docs/input-format.md; a complete example: "
            "tests/data/example_campaign/campaign.yaml)",
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


def response_unit(file_unit: str | None, campaign: Campaign, what: str) -> str:
    """The unit of a response channel: the one its file records, which must be a unit of
    campaign.yaml's response quantity when it gives one (else of any response quantity)
    and agree with campaign.yaml's ``unit`` when given; else campaign.yaml's (campaign.yaml
    fills only what the file leaves out). The unit names the channel's quantity
    (:func:`workflow.io.units.response_quantity_of`).

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
    found = units.response_quantity_of(canonical)
    if quantity is None:
        if found is None:
            raise ValueError(
                f"{what}: unit {quoted(file_unit)} in the file is no response unit; "
                f"expected one of {', '.join(units.RESPONSE_UNITS)}"
            )
        return canonical
    if found != quantity:
        # a sensor of another quantity (a laser vibrometer beside accelerometers): say so
        hint = (
            f"; it is a unit of {found}: leave quantity out of response in campaign.yaml (each "
            "channel then records its file's unit's quantity), or leave the channel out of channels"
            if found is not None
            else ""
        )
        raise ValueError(
            f"{what}: unit {quoted(file_unit)} in the file is not a unit of {quantity} "
            f"(campaign.yaml response quantity); expected one of {', '.join(units.known_units(quantity))}"
            f"{hint}"
        )
    if yaml_unit is not None and canonical != yaml_unit:
        raise ValueError(
            f"{what}: unit {quoted(file_unit)} in the file disagrees with campaign.yaml response unit "
            f"{yaml_unit!r} ({quantity})"
        )
    return canonical


def response_units(
    file_units: Sequence[str | None], campaign: Campaign, whats: Sequence[str]
) -> tuple[tuple[str | None, ...], tuple[str | None, ...]]:
    """:func:`response_unit` of each response channel of a file, a channel whose unit is
    refused left out (its unit None, its message beside it) while another is kept: one
    sensor that contradicts campaign.yaml does not take the hit the others measured down.

    Returns
    -------
    units, refusals : tuple
        Per channel, its canonical unit or None, and None or why it was refused.

    Raises
    ------
    ValueError
        Every channel refused (the messages joined).
    """
    found, refusals = [], []
    for file_unit, what in zip(file_units, whats, strict=True):
        try:
            found.append(response_unit(file_unit, campaign, what))
            refusals.append(None)
        except ValueError as error:
            found.append(None)
            refusals.append(str(error))
    if all(unit is None for unit in found):
        raise ValueError("; ".join(refusals))
    return tuple(found), tuple(refusals)


def force_unit(file_unit: str | None, campaign: Campaign, what: str) -> str:
    """The unit of the force channel: the one its file records, which must be a force unit
    and agree with campaign.yaml's ``force.unit`` when given; else campaign.yaml's; else the
    original lab's lbf.

    Parameters
    ----------
    file_unit : str or None
        The unit the file records for the channel (None: none).
    campaign : Campaign
        The validated campaign.yaml.
    what : str
        How the message names the channel, e.g. ``force column``.

    Raises
    ------
    ValueError
        The file's unit is no force unit or disagrees with campaign.yaml; the message names
        the channel (the caller adds the file).
    """
    yaml_unit = campaign.force.unit if campaign.force is not None else None
    if file_unit is None:
        return yaml_unit or "lbf"
    canonical = units.normalize_unit(file_unit)
    if canonical not in units.known_units("force"):
        raise ValueError(f"{what} unit {quoted(file_unit)}: expected lbf or N")
    if yaml_unit is not None and canonical != yaml_unit:
        raise ValueError(
            f"{what} unit {quoted(file_unit)} disagrees with campaign.yaml force unit {yaml_unit!r}"
        )
    return canonical
