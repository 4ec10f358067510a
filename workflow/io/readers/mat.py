"""MATLAB MAT files: plain variables, or LMS Test.Lab / Simcenter export structs.

MAT 5 files are read by ``scipy.io.loadmat``, MATLAB 7.3 files (HDF5 underneath) by
h5py; both are turned into the same nested mapping (structs as dicts, char arrays as
str, numeric arrays squeezed), so the channel logic below serves both.

- A variable that is a struct with ``x_values`` and ``y_values`` is a Test.Lab export
  group: ``y_values.values`` holds samples x channels, named by ``function_record.name``;
  the unit is ``y_values.quantity.label``, the sample interval and start time are
  ``x_values.increment`` and ``start_value``. Test.Lab stores SI values and gives the
  label's unit as ``label value = SI value * factor + offset``
  (``y_values.quantity.unit_transformation``); that conversion is applied, so the samples
  are in the label's unit. ``function_record.creation_time`` (``YYYY/MM/DD HH:MM:SS``,
  local clock time) is when the recording started.
- Other numeric vectors are channels named by their variable; ``t``/``time...`` is the
  time vector; a scalar ``fs`` (or ``sample_rate``, ``sampling_rate``) in Hz or ``dt``
  (or ``sample_interval``) in s gives the sample interval. Plain variables carry no
  units: campaign.yaml gives them. Matrices are not read as channels.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from workflow.io.limits import quoted
from workflow.io.readers.channels import Channel, FileChannels
from workflow.io.recording_time import parse_clock_time
from workflow.io.records import CampaignFormatError

__all__ = [
    "read_mat_channels",
    "channels_from_variables",
    "Mat5VariableHeader",
    "mat5_variable_headers",
]


_RATE_NAMES_HZ = {"fs", "sample_rate", "sample_rate_hz", "samplerate", "sampling_rate", "sampling_frequency"}
_INTERVAL_NAMES_S = {"dt", "sample_interval", "sample_interval_s", "sampling_interval"}
_MAT73_SIGNATURE = b"MATLAB 7.3"
_TESTLAB_TIME_FUNCTION = "Time "
"""Prefix of Test.Lab channel names of time signals (``Time Laser:+X``)."""


def read_mat_channels(path: Path, shown: str) -> FileChannels:
    """Channels of a MAT file (MAT 5 or 7.3).

    Raises
    ------
    CampaignFormatError
        The file is not a readable MAT file, or a variable is malformed (named in the message).
    """
    with open(path, "rb") as handle:  # read-only: raw files are never modified
        signature = handle.read(128)
    if _MAT73_SIGNATURE in signature[:116]:
        variables, format_name = _read_mat73(path, shown), "MAT 7.3"
    else:
        variables, format_name = _read_mat5(path, shown), "MAT"
    return channels_from_variables(variables, format_name, shown)


@dataclass(frozen=True)
class _DeferredVector:
    """A plain numeric vector of a MAT 5 file, read only when a channel needs it."""

    load: Callable[[], np.ndarray]


def _read_mat5(path: Path, shown: str) -> dict[str, Any]:
    """The variables of a MAT 5 file as ``loadmat(squeeze_me=True, simplify_cells=True)``
    gives them, each plain numeric vector (a channel, perhaps unused) as a
    :class:`_DeferredVector`: decompressing a vector costs more than the rest of reading it,
    and a file often holds vectors no run uses (PFF's record: the force beside the response).
    A file whose layout :func:`mat5_variable_headers` does not follow is read whole."""
    data = path.read_bytes()
    headers = mat5_variable_headers(data)
    if headers is None:
        return _loadmat_bytes(data, shown)
    eager = [
        h
        for h in headers
        if not (h.plain_vector and h.name.lower() not in _RATE_NAMES_HZ | _INTERVAL_NAMES_S)
    ]
    loaded = (
        _loadmat_bytes(data[:128] + b"".join(data[h.first : h.stop] for h in eager), shown) if eager else {}
    )
    variables: dict[str, Any] = {}
    for header in headers:
        if header.name.startswith("__"):
            continue
        if any(header is h for h in eager):
            variables[header.name] = loaded[header.name]
        else:
            variables[header.name] = _DeferredVector(lambda header=header: _plain_vector(data, header, shown))
    return variables


def _plain_vector(data: bytes, header: Mat5VariableHeader, shown: str) -> np.ndarray:
    """The samples of a plain vector of a MAT 5 file's bytes, as ``loadmat(squeeze_me=True)``
    gives them: inflated by libdeflate (twice as fast as zlib, which scipy uses) and taken
    as a view of the inflated bytes when they are real, not logical and
    little-endian; anything else, or bytes libdeflate refuses, read by scipy (which names
    the damage)."""
    import deflate

    element = data[header.first : header.stop]
    if header.compressed:
        try:
            element = deflate.zlib_decompress(element[8:], header.element_bytes)
        except deflate.DeflateError:
            element = b""
    samples = _real_samples(element, "<" if data[126:128] == b"IM" else ">")
    if samples is None:
        return _loadmat_bytes(data[:128] + data[header.first : header.stop], shown)[header.name]
    return samples


def _loadmat_bytes(data: bytes, shown: str) -> dict[str, Any]:
    """``scipy.io.loadmat`` of a MAT file's bytes, the ``__header__``-like entries left out."""
    import io

    import scipy.io

    try:
        variables = scipy.io.loadmat(io.BytesIO(data), squeeze_me=True, simplify_cells=True)
    except Exception as error:  # scipy raises many types for damaged files
        raise CampaignFormatError(
            shown, None, f"cannot read as a MAT file ({type(error).__name__}: {error})"
        ) from None
    return {name: value for name, value in variables.items() if not name.startswith("__")}


_MAT5_NUMERIC_CLASSES = range(6, 16)
"""MATLAB array classes double, single and int8 ... uint64 (mxDOUBLE_CLASS = 6 ... 15)."""
_MI_MATRIX, _MI_COMPRESSED = 14, 15
_HEADER_BYTES = 1024
"""Bytes of an array element read for its header (flags, dimensions, name)."""


@dataclass(frozen=True)
class Mat5VariableHeader:
    """Where one top-level variable of a MAT 5 file lies and what its header says.

    Attributes
    ----------
    name : str
        The variable's name.
    first, stop : int
        Its element (tag included) is ``data[first:stop]`` of the file's bytes.
    plain_vector : bool
        A numeric array (real, complex or logical, which scipy reads as uint8) with one
        dimension above 1: ``loadmat(squeeze_me=True)`` gives a 1-D numeric vector of 2
        samples or more.
    compressed : bool
        The element is miCOMPRESSED (zlib), the array element inside it.
    element_bytes : int
        Bytes of the array element, tag included, once inflated.
    """

    name: str
    first: int
    stop: int
    plain_vector: bool
    compressed: bool
    element_bytes: int


def mat5_variable_headers(data: bytes) -> list[Mat5VariableHeader] | None:
    """Every top-level variable of a MAT 5 file's bytes, from its element tags and the
    first bytes of each (decompressed) array header; None when the bytes are not a MAT 5
    file laid out as MATLAB and scipy write it (version 0x0100, elements of type
    miMATRIX or miCOMPRESSED that end within the file, array flags, dimensions and name in
    that order, distinct names), left to scipy to read or to refuse."""
    import zlib

    if len(data) < 128 or data[126:128] not in (b"IM", b"MI"):
        return None
    order = "<" if data[126:128] == b"IM" else ">"
    if struct.unpack(order + "H", data[124:126])[0] != 0x0100:
        return None
    headers, position = [], 128
    try:
        while position < len(data):
            element_type, size = struct.unpack(order + "II", data[position : position + 8])
            stop = position + 8 + size
            if stop > len(data) or element_type not in (_MI_MATRIX, _MI_COMPRESSED):
                return None
            body = data[position + 8 : stop]
            if element_type == _MI_COMPRESSED:
                body = zlib.decompressobj().decompress(body, _HEADER_BYTES)
            else:
                body = data[position : position + 8 + _HEADER_BYTES]
            header = _array_header(body, order)
            if header is None:
                return None
            name, plain_vector = header
            element_bytes = 8 + struct.unpack(order + "I", body[4:8])[0]
            compressed = element_type == _MI_COMPRESSED
            headers.append(Mat5VariableHeader(name, position, stop, plain_vector, compressed, element_bytes))
            position = stop
    except (struct.error, zlib.error, UnicodeDecodeError):
        return None
    if len({h.name for h in headers}) != len(headers):
        return None
    return headers


def _sub_element(body: bytes, at: int, order: str) -> tuple[int, int, int, int]:
    """Type, first byte and size of the data of the MAT 5 sub-element at ``at`` (small data
    elements keep theirs in the tag's 4 bytes), and the position of the next one."""

    first, second = struct.unpack(order + "II", body[at : at + 8])
    if first >> 16:
        kind, start, size, following = first & 0xFFFF, at + 4, first >> 16, at + 8
    else:
        kind, start, size, following = first, at + 8, second, at + 8 + -(-second // 8) * 8
    if start + size > len(body):
        raise struct.error("sub-element beyond the bytes read")
    return kind, start, size, following


def _array_layout(body: bytes, order: str) -> tuple[str, int, tuple[int, ...], int] | None:
    """Name, array flags word, dimensions and the position of the first data sub-element
    of a miMATRIX element's bytes (tag included), or None when they are not laid out as
    MATLAB writes them."""

    if struct.unpack(order + "I", body[:4])[0] != _MI_MATRIX:
        return None
    flags_type, flags_at, flags_size, at = _sub_element(body, 8, order)
    dims_type, dims_at, dims_size, at = _sub_element(body, at, order)
    name_type, name_at, name_size, at = _sub_element(body, at, order)
    if flags_type != 6 or flags_size != 8 or dims_type != 5 or dims_size % 4 or name_type != 1:
        return None
    if not name_size:  # a MATLAB 7 function workspace, which scipy reads apart
        return None
    flag_word = struct.unpack(order + "I", body[flags_at : flags_at + 4])[0]
    shape = struct.unpack(order + f"{dims_size // 4}i", body[dims_at : dims_at + dims_size])
    return body[name_at : name_at + name_size].decode("latin1"), flag_word, shape, at


def _array_header(body: bytes, order: str) -> tuple[str, bool] | None:
    """Name and plain-vector flag of a miMATRIX element's first bytes (tag included)."""
    layout = _array_layout(body, order)
    if layout is None:
        return None
    name, flag_word, shape, _ = layout
    plain_vector = (
        flag_word & 0xFF in _MAT5_NUMERIC_CLASSES
        and sum(extent > 1 for extent in shape) == 1
        and min(shape) >= 1
    )
    return name, plain_vector


_MAT5_SAMPLE_TYPES = {
    1: "i1",
    2: "u1",
    3: "i2",
    4: "u2",
    5: "i4",
    6: "u4",
    7: "f4",
    9: "f8",
    12: "i8",
    13: "u8",
}
"""NumPy types of the MAT 5 data types miINT8 ... miUINT64 that a numeric array's samples
are stored in (MATLAB may store a double array in a narrower integer type; scipy then
gives that type, as here)."""
_MAT5_COMPLEX_FLAG, _MAT5_LOGICAL_FLAG = 0x800, 0x200


def _real_samples(element: bytes, order: str) -> np.ndarray | None:
    """The samples of a little-endian, real, non-logical numeric array element (inflated,
    tag included) as a 1-D view of its bytes, in the type they are stored in;
    None for anything else."""

    try:
        layout = _array_layout(element, order) if order == "<" and len(element) >= 8 else None
        if layout is None:
            return None
        _, flag_word, shape, at = layout
        kind, start, size, _ = _sub_element(element, at, order)
    except (struct.error, UnicodeDecodeError):
        return None
    if flag_word & (_MAT5_COMPLEX_FLAG | _MAT5_LOGICAL_FLAG) or flag_word & 0xFF not in _MAT5_NUMERIC_CLASSES:
        return None
    sample_type = _MAT5_SAMPLE_TYPES.get(kind)
    count = int(np.prod(shape))
    if sample_type is None or size != count * np.dtype(sample_type).itemsize:
        return None
    return np.frombuffer(element, dtype="<" + sample_type, count=count, offset=start)


def _read_mat73(path: Path, shown: str) -> dict[str, Any]:
    import h5py

    try:
        with h5py.File(path, "r") as handle:
            outside = _outside_reference(handle)
            if outside is None:
                return {
                    name: _hdf5_value(handle, handle[name]) for name in handle if not name.startswith("#")
                }
    except Exception as error:  # h5py raises OSError, KeyError, ... for damaged files
        raise CampaignFormatError(
            shown, None, f"cannot read as a MATLAB 7.3 (HDF5) file ({type(error).__name__}: {error})"
        ) from None
    raise CampaignFormatError(
        shown,
        None,
        f"{outside}: refused, it would read another file (every file read lies in the campaign folder)",
    )


def _outside_reference(handle: Any) -> str | None:
    """The first object of an HDF5 file whose data lie in another file (an external link,
    a dataset stored in external files, a virtual dataset), or None. MATLAB never writes
    them; h5py would follow them out of the campaign folder."""
    import h5py

    found: list[str] = []

    def link(name: str, info: Any) -> bool | None:
        if isinstance(info, h5py.ExternalLink):
            found.append(f"{quoted(name)} is a link to another file")
            return True
        return None

    def dataset(name: str, node: Any) -> bool | None:
        if isinstance(node, h5py.Dataset) and (node.external or node.is_virtual):
            found.append(f"{quoted(name)} holds data stored in other files")
            return True
        return None

    handle.visititems_links(link)
    if not found:
        handle.visititems(dataset)
    return found[0] if found else None


def _hdf5_value(handle: Any, node: Any) -> Any:
    """A MATLAB 7.3 variable as ``loadmat(squeeze_me=True, simplify_cells=True)`` gives it."""
    import h5py

    if isinstance(node, h5py.Group):
        return {name: _hdf5_value(handle, node[name]) for name in node if not name.startswith("#")}
    matlab_class = node.attrs.get("MATLAB_class", b"")
    matlab_class = matlab_class.decode() if isinstance(matlab_class, bytes) else str(matlab_class)
    if node.attrs.get("MATLAB_empty", 0):
        return np.array([])
    data = node[()]
    if matlab_class == "char":
        return "".join(chr(code) for code in np.asarray(data).T.ravel())
    if matlab_class == "cell":
        items = [_hdf5_value(handle, handle[reference]) for reference in np.asarray(data).T.ravel()]
        return items[0] if len(items) == 1 else np.array(items, dtype=object)
    # MATLAB writes column-major: the HDF5 dataset is the transpose of the MATLAB array.
    array = np.asarray(data).T.squeeze()
    return array.item() if array.ndim == 0 else array


def _field(mapping: Any, *keys: str) -> Any:
    for key in keys:
        if not isinstance(mapping, dict) or key not in mapping:
            return None
        mapping = mapping[key]
    return mapping


def _number(value: Any) -> float | None:
    array = np.asarray(value)
    if array.size == 1 and np.issubdtype(array.dtype, np.number) and not np.iscomplexobj(array):
        return float(array.item())
    return None


def _stated_number(group: dict[str, Any], where: str, shown: str, *keys: str) -> float | None:
    """The finite number at ``keys`` of a Test.Lab struct, None when the field is absent;
    a field that holds anything else is an error (never silently replaced)."""
    value = _field(group, *keys)
    if value is None:
        return None
    number = _number(value)
    if number is None or not np.isfinite(number):
        text = quoted(value) if isinstance(value, str) else f"of type {type(value).__name__}"
        raise CampaignFormatError(shown, None, f"{where}: {'.'.join(keys)} is {text}, not a finite number")
    return number


def _testlab_channels(variable: str, group: dict[str, Any], shown: str) -> list[Channel]:
    """The channels of one Test.Lab export struct."""
    where = f"variable {variable!r}"
    values = np.asarray(_field(group, "y_values", "values"))
    if values.size == 0 or not np.issubdtype(values.dtype, np.number):
        raise CampaignFormatError(shown, None, f"{where}: y_values.values holds no numeric samples")
    columns = [values] if values.ndim == 1 else list(values.T)
    names = _field(group, "function_record", "name")
    names = [names] if isinstance(names, str) else [] if names is None else [str(n) for n in np.ravel(names)]
    if len(names) != len(columns):
        raise CampaignFormatError(
            shown,
            None,
            f"{where}: function_record.name gives {len(names)} channel name(s) but y_values.values "
            f"has {len(columns)} column(s) of {values.shape[0]} samples",
        )
    declared = _stated_number(group, where, shown, "x_values", "number_of_values")
    if declared is not None and declared != columns[0].size:
        raise CampaignFormatError(
            shown,
            None,
            f"{where}: x_values.number_of_values says {declared:.0f} samples but y_values.values "
            f"holds {columns[0].size} (truncated or mislabelled export)",
        )
    interval_s = _stated_number(group, where, shown, "x_values", "increment")
    start_s = _stated_number(group, where, shown, "x_values", "start_value")
    label = _field(group, "y_values", "quantity", "label")
    factor = _stated_number(group, where, shown, "y_values", "quantity", "unit_transformation", "factor")
    offset = _stated_number(group, where, shown, "y_values", "quantity", "unit_transformation", "offset")
    factor = 1.0 if factor is None else factor
    offset = 0.0 if offset is None else offset
    created = _field(group, "function_record", "creation_time")
    created = (
        [created] * len(names) if created is None or isinstance(created, str) else list(np.ravel(created))
    )
    if len(created) != len(names):  # not one time per channel: no start time rather than a guess
        created = [None] * len(names)
    channels = []
    for name, column, creation_time in zip(names, columns, created, strict=True):
        samples = np.asarray(column, dtype=np.float64)
        if factor != 1.0 or offset != 0.0:
            samples = samples * factor + offset
        channels.append(
            Channel(
                name=name,
                values=samples,
                record=f"{where} channel {name!r}",
                unit=label if isinstance(label, str) else None,
                sample_interval_s=interval_s,
                interval_source="x_values.increment",
                start_s=start_s,
                role_name=name.removeprefix(_TESTLAB_TIME_FUNCTION),
                record_start=parse_clock_time(creation_time),
            )
        )
    return channels


def channels_from_variables(variables: dict[str, Any], format_name: str, shown: str) -> FileChannels:
    """Channels of a MAT file's variables (see the module's notes).

    Parameters
    ----------
    variables : dict
        Variable name -> value as ``loadmat(squeeze_me=True, simplify_cells=True)`` gives it.
    format_name : str
        For messages (``MAT``, ``MAT 7.3``).
    shown : str
        The path used in error messages.
    """
    channels: list[Channel] = []
    testlab = False
    rates: list[tuple[str, float]] = []
    plain: list[tuple[str, np.ndarray]] = []
    for name, value in variables.items():
        if isinstance(value, _DeferredVector):
            plain.append((name, value))
            continue
        if isinstance(value, dict) and "y_values" in value and "x_values" in value:
            channels += _testlab_channels(name, value, shown)
            testlab = True
            continue
        if name.lower() in _RATE_NAMES_HZ | _INTERVAL_NAMES_S:
            scalar = _number(value) if not isinstance(value, (str, dict)) else None
            if scalar is None or not 0 < scalar < np.inf:
                text = quoted(value) if isinstance(value, str) else f"{value!r:.60}"
                unit = "Hz" if name.lower() in _RATE_NAMES_HZ else "s"
                raise CampaignFormatError(
                    shown, None, f"variable {name!r} is {text}, not a positive number (in {unit})"
                )
            rates.append((name, scalar if name.lower() in _RATE_NAMES_HZ else 1.0 / scalar))
            continue
        if not isinstance(value, (str, dict)) and _number(value) is not None:
            continue
        array = value if isinstance(value, np.ndarray) else None
        if array is not None and array.ndim == 1 and array.size > 1 and np.issubdtype(array.dtype, np.number):
            plain.append((name, array))
    for (name_a, rate_a), (name_b, rate_b) in zip(rates, rates[1:]):
        if abs(rate_a - rate_b) > 1e-6 * max(rate_a, rate_b):
            raise CampaignFormatError(
                shown,
                None,
                f"variable {name_b!r} gives a sample rate of {rate_b:.9g} Hz but variable "
                f"{name_a!r} gives {rate_a:.9g} Hz",
            )
    interval_s = 1.0 / rates[0][1] if rates else None
    for name, array in plain:
        channels.append(
            Channel(
                name=name,
                values=None if isinstance(array, _DeferredVector) else array,
                load=array.load if isinstance(array, _DeferredVector) else None,
                record=f"variable {name!r}",
                sample_interval_s=interval_s,
                interval_source=f"variable {rates[0][0]!r}" if rates else None,
            )
        )
    return FileChannels(f"{format_name} (Test.Lab export)" if testlab else format_name, channels)
