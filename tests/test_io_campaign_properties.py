"""Property-based tests of the run-file reader.

Any well-formed file in any dialect of campaign-format.md reads back its numbers
within print precision; any single corruption of a data row gives a
CampaignFormatError naming exactly that row's line, never another exception and
never a silently different record.
"""

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from workflow.io.campaign import load_campaign
from workflow.io.records import MIN_SAMPLES, CampaignFormatError
from workflow.io.run_files import read_run

SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

ROLE_NAMES = {"time": "Time (s)", "force": "Force (lbf)", "response": "Acceleration (g)"}


@dataclass
class Dialect:
    n_columns: int
    delimiter: str
    newline: str
    scientific: bool
    digits: int
    header: str  # none | keyvalue | names | both | title_names
    force_in_yaml: bool
    yaml_rate: bool
    fs_hz: float
    n_samples: int
    seed: int
    scale: float

    @property
    def roles(self):
        if self.n_columns == 3:
            return ("time", "force", "response")
        if self.n_columns == 2:
            return ("force", "response") if self.force_in_yaml else ("time", "response")
        return ("response",)


@st.composite
def dialects(draw):
    n_columns = draw(st.integers(1, 3))
    force_in_yaml = draw(st.booleans())
    fs_hz = draw(st.sampled_from([512.0, 1024.0, 2560.0, 51200.0]))
    header = draw(st.sampled_from(["none", "keyvalue", "names", "both", "title_names"]))
    dialect = Dialect(
        n_columns=n_columns,
        delimiter=draw(st.sampled_from(["\t", ",", ";", " ", "   "])),
        newline=draw(st.sampled_from(["\n", "\r\n"])),
        scientific=draw(st.booleans()),
        digits=draw(st.integers(3, 9)),
        header=header,
        force_in_yaml=force_in_yaml,
        yaml_rate=draw(st.booleans()),
        fs_hz=fs_hz,
        n_samples=MIN_SAMPLES + draw(st.integers(0, 60)),
        seed=draw(st.integers(0, 2**32 - 1)),
        scale=10.0 ** draw(st.integers(-4, 4)),
    )
    has_time = "time" in dialect.roles
    rate_in_header = header in ("keyvalue", "both")
    # The sample rate must be known from somewhere.
    assume(has_time or dialect.yaml_rate or rate_in_header)
    return dialect


def make_columns(d: Dialect):
    rng = np.random.default_rng(d.seed)
    columns = {
        "time": np.arange(d.n_samples) / d.fs_hz,
        "force": np.abs(rng.normal(scale=d.scale, size=d.n_samples)),
        "response": rng.normal(scale=d.scale, size=d.n_samples),
    }
    columns["response"][rng.integers(0, d.n_samples, 3)] = 0.0
    return [columns[role] for role in d.roles]


def format_cell(value, role, d: Dialect):
    if role == "time":
        return f"{value:.10f}" if not d.scientific else f"{value:.12e}"
    return f"{value:.{d.digits}e}" if d.scientific else f"{value:.{d.digits}f}"


def render(d: Dialect):
    """Header lines and data rows (as lists of cells) of a well-formed file."""
    header = []
    if d.header == "title_names":
        header.append("Exported by a test")
    if d.header in ("keyvalue", "both"):
        header += [f"Sample rate: {d.fs_hz:g} Hz", "Pre-trigger: 25 samples"]
    if d.header in ("names", "both", "title_names"):
        header.append(d.delimiter.join(ROLE_NAMES[role] for role in d.roles))
    columns = make_columns(d)
    rows = [[format_cell(v, role, d) for v, role in zip(values, d.roles)] for values in zip(*columns)]
    return header, rows, columns


def campaign_yaml(d: Dialect):
    lines = ["name: prop", "response: {quantity: acceleration, unit: g}"]
    if d.force_in_yaml:
        lines.append("force: {unit: lbf}")
    if d.yaml_rate:
        lines.append(f"sample_rate_hz: {d.fs_hz:g}")
    lines += ["configurations:", "  cfg: {}"]
    return "\n".join(lines) + "\n"


def read_text(d: Dialect, header, rows):
    text = d.newline.join(header + [d.delimiter.join(row) for row in rows]) + d.newline
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        (root / "campaign.yaml").write_text(campaign_yaml(d))
        (root / "cfg").mkdir()
        (root / "cfg" / "run.txt").write_bytes(text.encode())
        campaign = load_campaign(root)
        return read_run(root, "cfg/run.txt", campaign)


def tolerance(values, d: Dialect):
    """Half a unit of the last written digit, plus the rounding of the parsed float (at most
    half the spacing of doubles at the value; one spacing allowed): a value near 1e4
    written with 9 decimals has 14 significant digits, near the 16 a double holds."""
    spacing = np.spacing(np.abs(values))
    if d.scientific:
        return 0.5 * 10.0 ** (-d.digits) * np.abs(values) * (1 + 1e-9) + spacing
    return 0.5 * 10.0 ** (-d.digits) * (1 + 1e-9) + spacing


@SETTINGS
@given(d=dialects())
def test_well_formed_files_round_trip(d):
    header, rows, columns = render(d)
    record = read_text(d, header, rows)
    assert record.n_samples == d.n_samples
    assert record.sample_rate_hz == pytest.approx(d.fs_hz, rel=1e-6)
    by_role = dict(zip(d.roles, columns))
    response = by_role["response"]
    assert np.all(np.abs(record.response - response) <= tolerance(response, d))
    if "force" in by_role:
        force = by_role["force"]
        assert np.all(np.abs(record.force_lbf - force) <= tolerance(force, d))
    else:
        assert record.force_lbf is None
    if "time" in by_role:
        np.testing.assert_allclose(record.time_s, by_role["time"], atol=1e-9)
    if d.header in ("keyvalue", "both"):
        assert record.pretrigger_samples == 25


JUNK = ["abc", "1.2.3", "--1", "0x1F", "N/A", "#VALUE!", "1e", "e5", ".", "-", "12a", "1..5"]


@SETTINGS
@given(
    d=dialects(),
    kind=st.sampled_from(["text", "nan", "inf", "overflow", "truncate", "extra", "empty", "mixed"]),
    row_fraction=st.floats(0.0, 1.0),
    cell_seed=st.integers(0, 1000),
    junk=st.sampled_from(JUNK),
)
def test_corrupted_row_is_reported_at_its_line(d, kind, row_fraction, cell_seed, junk):
    header, rows, _ = render(d)
    # Rows near the start matter most (they may fall into the header), so draw them often.
    row = 0 if row_fraction < 0.2 else min(int(row_fraction * len(rows)), len(rows) - 1)
    cell = cell_seed % d.n_columns
    spaces = d.delimiter.strip() == ""
    if kind in ("truncate", "mixed"):
        assume(d.n_columns >= 2)
    if kind == "empty":
        assume(d.n_columns >= 2 and not spaces)
    names_line = d.header in ("names", "both", "title_names")
    # A lone text line before one-column numbers is a header line by the contract.
    assume(not (kind == "text" and d.n_columns == 1 and row == 0 and not names_line))

    cells = list(rows[row])
    if kind == "text":
        cells[cell] = junk
    elif kind == "nan":
        cells[cell] = "NaN"
    elif kind == "inf":
        cells[cell] = "-inf"
    elif kind == "overflow":
        cells[cell] = "1e999"
    elif kind == "truncate":
        cells.pop()
    elif kind == "extra":
        cells.append("0.5")
    elif kind == "empty":
        cells[cell] = ""
    bad = d.delimiter.join(cells)
    if kind == "mixed":
        other = {"\t": ";", ",": "\t", ";": ",", " ": ",", "   ": "\t"}[d.delimiter]
        bad = bad.replace(d.delimiter, other, 1)
    rows = list(rows)
    rows[row] = [bad]  # read_text joins a row's cells; this row is already one string

    with pytest.raises(CampaignFormatError) as info:
        read_text(d, header, rows)
    assert info.value.line == len(header) + row + 1, (str(info.value), bad)
    assert info.value.path.endswith("cfg/run.txt")


JUNK_LINE = st.one_of(
    st.text(alphabet="0123456789.,;\t -+eEnaif:xs()", max_size=30),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@SETTINGS
@given(
    junk=st.lists(JUNK_LINE, max_size=12),
    position=st.integers(0, MIN_SAMPLES + 20),
    in_header=st.booleans(),
)
def test_arbitrary_text_gives_a_record_or_a_format_error(junk, position, in_header):
    d = Dialect(1, "\t", "\n", False, 6, "none", False, True, 1024.0, MIN_SAMPLES + 20, 0, 1.0)
    header, rows, _ = render(d)
    printed = np.array([float(row[0]) for row in rows])
    if in_header:
        header = junk
    else:
        rows = rows[:position] + [[line] for line in junk] + rows[position:]
    try:
        record = read_text(d, header, rows)
    except CampaignFormatError as error:
        assert error.path.endswith("cfg/run.txt") and error.problem
        return
    if in_header or position == 0:
        # Text before the numbers is header; numeric-looking lines there start the data.
        assert np.array_equal(record.response[-printed.size :], printed)
    else:
        # Inside the numbers, junk is accepted only when every line of it is a number
        # (or blank at the very end): then it is data, in place.
        inserted = [float(line) for line in junk if line.strip()]
        expected = np.concatenate([printed[:position], inserted, printed[position:]])
        assert np.array_equal(record.response, expected)
