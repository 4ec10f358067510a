"""Column names and units of ASCII run files against the grammar of the input contract
(/work/shared/campaign-format.md, "Run files"): a name starting with ``time`` is time; one
containing ``force`` or ``hammer`` is the force; one containing ``acc``, ``vel``, ``resp`` or
``disp`` is the response; a unit may follow in parentheses or brackets, in any spelling the
contract's units have. Expected values are the exact unit definitions, not the reader's
own factors."""

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workflow.io.campaign import load_campaign
from workflow.io.run_files import read_run

LBF_N = 0.45359237 * 9.80665
"""Newtons in one pound-force: 4.4482216152605 N (the avoirdupois pound times standard gravity)."""

FS_HZ = 2560.0
N_SAMPLES = 400


def signals():
    t_s = np.arange(N_SAMPLES) / FS_HZ
    force_lbf = 50.0 * np.exp(-(((t_s - 0.01) / 0.001) ** 2))
    response = 3.0 * np.exp(-2.0 * t_s) * np.sin(2 * np.pi * 125.0 * t_s)
    return t_s, force_lbf, response


def campaign_yaml(quantity: str, unit: str) -> str:
    # No force section: a force column without a unit would be read in the original lab's
    # lbf, so a unit the reader fails to see would show as a wrong force, not an error.
    return (
        f"name: grammar\nsample_rate_hz: {FS_HZ:g}\nresponse: {{quantity: {quantity}, unit: {unit}}}\n"
        "configurations:\n  cfg: {}\n"
    )


def read_text(folder: Path, text: str, yaml_text: str):
    (folder / "cfg").mkdir(parents=True, exist_ok=True)
    (folder / "campaign.yaml").write_text(yaml_text)
    (folder / "cfg" / "run01.txt").write_text(text)
    return read_run(folder, "cfg/run01.txt", load_campaign(folder))


def rows(columns, delimiter="\t"):
    return "".join(delimiter.join(f"{value:.10e}" for value in row) + "\n" for row in zip(*columns))


def test_bracketed_newtons_are_converted_not_read_as_lbf(tmp_path):
    t_s, force_lbf, response = signals()
    text = "Time [s]\tForce [N]\tAcceleration [g]\n" + rows((t_s, force_lbf * LBF_N, response))
    record = read_text(tmp_path, text, campaign_yaml("acceleration", "g"))
    # a 50 lbf pulse, not 222 (its newtons read as lbf)
    np.testing.assert_allclose(record.force_lbf, force_lbf, rtol=1e-9, atol=1e-12)


def test_displacement_columns_are_the_response(tmp_path):
    t_s, force_lbf, response = signals()
    for index, name in enumerate(["Displacement (m)", "Disp", "disp_z [m]", "Laser DISP"]):
        text = f"Time (s)\tForce (lbf)\t{name}\n" + rows((t_s, force_lbf, response))
        record = read_text(tmp_path / str(index), text, campaign_yaml("displacement", "m"))
        assert record.response_quantity == "displacement" and record.response_unit == "m"
        np.testing.assert_allclose(record.response, response, rtol=1e-9, atol=1e-15)


# ---------------------------------------------------------------- the whole grammar

# Spellings of each response quantity's keyword, and of its units with the canonical unit.
RESPONSE_NAMES = {
    "acceleration": ["Acceleration", "Accel", "acc", "ACC", "Accelerometer"],
    "velocity": ["Velocity", "Vel", "velocity", "VEL"],
    "displacement": ["Displacement", "Disp", "disp", "DISPLACEMENT"],
}
NEUTRAL_RESPONSE_NAMES = ["Response", "resp", "RESP"]
RESPONSE_UNITS = {
    "acceleration": [("g", "g"), ("G", "g"), ("m/s^2", "m/s^2"), ("m/s2", "m/s^2"), ("m/s²", "m/s^2")]
    + [("m/s/s", "m/s^2"), ("in/s^2", "in/s^2")],
    "velocity": [("m/s", "m/s"), ("in/s", "in/s"), ("ips", "in/s")],
    "displacement": [("m", "m"), ("in", "in"), ("inch", "in")],
}
FORCE_NAMES = ["Force", "force", "FORCE", "Hammer", "hammer", "Impact Force", "Hammer force"]
# unit -> lbf per unit, from the definitions (1 lbf = 4.4482216152605 N)
FORCE_UNITS = [("lbf", 1.0), ("lb", 1.0), ("lbs", 1.0), ("N", 1 / LBF_N), ("newton", 1 / LBF_N)]
FORCE_UNITS += [("Newtons", 1 / LBF_N)]
TIME_NAMES = ["Time", "time", "TIME", "Time_s"]
TIME_UNITS = [("s", 1.0), ("sec", 1.0), ("seconds", 1.0), ("ms", 1e-3), ("msec", 1e-3)]
# Around a keyword: words holding none of the keywords (a channel label, an axis).
PREFIXES = ["", "Ch1 ", "Sensor "]
SUFFIXES = ["", " 1", "_z", " X"]
BRACKETS = ["{} ({})", "{}({})", "{} [{}]", "{}[{}]", "{} ( {} )"]


@st.composite
def headed_files(draw):
    """(names, columns' roles in order, units, YAML quantity and unit) of a file whose line
    of names follows the contract, with each role's expected factor."""
    quantity = draw(st.sampled_from(sorted(RESPONSE_NAMES)))
    keyword = draw(st.sampled_from(RESPONSE_NAMES[quantity] + NEUTRAL_RESPONSE_NAMES))
    response_name = draw(st.sampled_from(PREFIXES)) + keyword + draw(st.sampled_from(SUFFIXES))
    spelled, canonical = draw(st.sampled_from(RESPONSE_UNITS[quantity]))
    columns = {}
    if draw(st.booleans()):
        response_name = draw(st.sampled_from(BRACKETS)).format(response_name, spelled)
    columns["response"] = (response_name, 1.0)
    if draw(st.booleans()):
        name = draw(st.sampled_from(PREFIXES)) + draw(st.sampled_from(FORCE_NAMES))
        name += draw(st.sampled_from(SUFFIXES))
        lbf_per_unit = 1.0  # no unit and no force in campaign.yaml: the original lab's lbf
        if draw(st.booleans()):
            unit, lbf_per_unit = draw(st.sampled_from(FORCE_UNITS))
            name = draw(st.sampled_from(BRACKETS)).format(name, unit)
        columns["force"] = (name, lbf_per_unit)
    if draw(st.booleans()):
        name = draw(st.sampled_from(TIME_NAMES))
        s_per_unit = 1.0
        if draw(st.booleans()):
            unit, s_per_unit = draw(st.sampled_from(TIME_UNITS))
            name = draw(st.sampled_from(BRACKETS)).format(name, unit)
        columns["time"] = (name, s_per_unit)
    if draw(st.booleans()):
        columns["other"] = (draw(st.sampled_from(["Temperature (C)", "Ch4", "Strain [ue]"])), 1.0)
    order = draw(st.permutations(sorted(columns)))
    delimiter = draw(st.sampled_from(["\t", ",", ";"]))
    return [(role, *columns[role]) for role in order], delimiter, quantity, canonical


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(headed_files())
def test_any_names_and_units_of_the_grammar_give_the_roles_and_factors(case):
    columns, delimiter, quantity, canonical = case
    t_s, force_lbf, response = signals()
    true_values = {"time": t_s, "force": force_lbf, "response": response, "other": np.full(N_SAMPLES, 21.5)}
    # what the file holds: the true value in the column's unit
    file_values = [true_values[role] / factor for role, _, factor in columns]
    header = delimiter.join(name for _, name, _ in columns) + "\n"
    with tempfile.TemporaryDirectory() as folder:
        record = read_text(
            Path(folder), header + rows(file_values, delimiter), campaign_yaml(quantity, canonical)
        )
    roles = {role for role, _, _ in columns}
    assert record.response_quantity == quantity and record.response_unit == canonical
    np.testing.assert_allclose(record.response, response, rtol=1e-9, atol=1e-15)
    if "force" in roles:
        np.testing.assert_allclose(record.force_lbf, force_lbf, rtol=1e-9, atol=1e-12)
    else:
        assert record.force_lbf is None
    if "time" in roles:
        np.testing.assert_allclose(record.time_s, t_s, rtol=1e-9, atol=1e-12)
        assert abs(record.sample_rate_hz - FS_HZ) < 1e-6 * FS_HZ


def test_sample_rates_agree_within_a_thousandth_plus_the_time_columns_resolution():
    from workflow.io.record_rules import rates_agree

    assert rates_agree(10000.0, 10009.0) and not rates_agree(10000.0, 10011.0)  # 0.09 %, 0.11 %
    # A time column printed to 1e-4 s over a 0.1 s record knows its rate to 0.1 %: that
    # widens the agreement to 0.2 %. (The limit itself, <= against <, decides only at
    # float equality of the difference and the tolerance: an equivalent mutant.)
    assert rates_agree(10000.0, 10019.0, extra_rel=1e-3)
    assert not rates_agree(10000.0, 10021.0, extra_rel=1e-3)
