"""Parquet tables: units in the schema, atomic writes."""

import numpy as np
import pandas as pd
import pytest

from workflow.io.tables import (
    column_units,
    concatenate_columns,
    read_columns,
    read_table,
    table_rows,
    with_si_columns,
    write_columns,
    write_json,
    write_table,
)


def test_units_round_trip_as_field_metadata(tmp_path):
    frame = pd.DataFrame({"velocity_amplitude_in_s": [0.1, 1.0], "zeta": [0.01, 0.02], "run": ["a", "b"]})
    path = tmp_path / "t.parquet"
    write_table(frame, path, units={"run": "label"})
    units = column_units(path)
    assert units["velocity_amplitude_in_s"] == "in/s"
    assert units["run"] == "label"
    pd.testing.assert_frame_equal(read_table(path)[list(frame.columns)], frame)


def test_table_rows_counts_what_read_table_reads(tmp_path):
    for n in (0, 1, 37):
        path = tmp_path / f"t{n}.parquet"
        write_table(pd.DataFrame({"zeta": np.linspace(0.01, 0.02, n)}), path)
        assert table_rows(path) == len(read_table(path)) == n


def test_failed_write_leaves_no_file(tmp_path):
    path = tmp_path / "t.parquet"
    with pytest.raises(Exception):  # noqa: B017 - any failure of the write must leave no file
        write_table(pd.DataFrame({"x": [object()]}), path)
    assert list(tmp_path.iterdir()) == []


def test_json_rejects_nan(tmp_path):
    with pytest.raises(ValueError):
        write_json(tmp_path / "x.json", {"value": float("nan")})
    write_json(tmp_path / "y.json", {"value": np.float64(1.5), "array": np.arange(2)})
    assert (tmp_path / "y.json").read_text().count("1.5") == 1


def test_columns_round_trip_in_order_with_their_types(tmp_path):
    columns = {
        "run": np.array(["run01", "run10"]),
        "zeta": np.array([0.01, np.nan]),
        "kept": np.array([True, False]),
        "reason": np.array(["", "noise_floor"]),
        "empty": np.array([], dtype=float),
    }
    path = tmp_path / "c.npz"
    write_columns(path, columns)
    back = read_columns(path)
    assert list(back) == list(columns)
    for name, column in columns.items():
        assert back[name].dtype == column.dtype
        np.testing.assert_array_equal(back[name], column)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.npz"]  # no temporary left


def test_concatenated_columns_stack_rows_and_keep_types():
    first = {
        "run": np.array(["run01", "run01"]),
        "zeta": np.array([0.01, 0.02]),
        "kept": np.array([True, False]),
    }
    empty = {
        "run": np.array([], dtype=str),
        "zeta": np.array([], dtype=float),
        "kept": np.array([], dtype=bool),
    }
    second = {"run": np.array(["run10"]), "zeta": np.array([0.03]), "kept": np.array([True])}
    stacked = concatenate_columns([first, empty, second])
    assert list(stacked) == ["run", "zeta", "kept"]
    assert stacked["run"].tolist() == ["run01", "run01", "run10"]
    np.testing.assert_array_equal(stacked["zeta"], [0.01, 0.02, 0.03])
    assert stacked["kept"].dtype == bool and stacked["kept"].tolist() == [True, False, True]
    with pytest.raises(ValueError, match="columns differ"):
        concatenate_columns([first, {"run": first["run"], "zeta": first["zeta"]}])


def test_tables_carry_si_twin_columns_with_their_units(tmp_path):
    frame = pd.DataFrame(
        {
            "configuration": ["a", "a"],
            "velocity_amplitude_in_s": [0.1, 3.7],
            "zeta": [0.01, 0.02],
            "amplitude_low_in_s": [0.2, 0.3],
            "bearing_area_in2": [1.36, 1.36],
        }
    )
    path = tmp_path / "si.parquet"
    write_table(frame, path)
    back = read_table(path)
    assert list(back.columns) == [
        "configuration",
        "velocity_amplitude_in_s",
        "velocity_amplitude_m_s",
        "zeta",
        "amplitude_low_in_s",
        "amplitude_low_m_s",
        "bearing_area_in2",
        "bearing_area_m2",
    ]
    np.testing.assert_array_equal(back["velocity_amplitude_m_s"], frame["velocity_amplitude_in_s"] * 0.0254)
    np.testing.assert_array_equal(back["bearing_area_m2"], frame["bearing_area_in2"] * 0.0254**2)
    units = column_units(path)
    assert units["velocity_amplitude_in_s"] == "in/s" and units["velocity_amplitude_m_s"] == "m/s"
    assert units["amplitude_low_m_s"] == "m/s" and units["bearing_area_m2"] == "m^2"


def test_si_model_parameters_carry_their_units():
    table = pd.DataFrame(
        {"parameter": ["sigma", "fc", "sigma1", "v0", "zeta0"], "value": [2.0] * 5, "std": [0.5] * 5}
    )
    si = with_si_columns(table)
    assert list(si["unit"]) == ["lbf/in", "lbf", "lbf s/in", "in/s", "1"]
    assert list(si["unit_si"]) == ["N/m", "N", "N s/m", "m/s", "1"]
    lbf_n = 0.45359237 * 9.80665
    np.testing.assert_allclose(
        si["value_si"], 2.0 * np.array([lbf_n / 0.0254, lbf_n, lbf_n / 0.0254, 0.0254, 1.0])
    )
    np.testing.assert_allclose(si["std_si"], si["value_si"] / 4)
    with pytest.raises(ValueError, match="stribeck"):
        with_si_columns(pd.DataFrame({"parameter": ["stribeck"], "value": [1.0], "std": [0.1]}))
