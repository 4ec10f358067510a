"""Every figure a reader sees can be taken in at a glance: no overlapping text, plain tick
labels, no empty panel without a note, and a note wherever a fitted curve misses the data.

The checker (workflow/outputs/readability.py) is first shown to catch each problem; then
every figure of the demo campaign and of a one-configuration campaign is rendered by the
real workflow, whose ``figures.save`` logs each problem it finds in the rule's log.
"""

from __future__ import annotations

import functools

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from helpers import CHEAP, REALDATA, needs_realdata, run_snakemake  # noqa: E402

from workflow.io.units import SI  # noqa: E402
from workflow.lab.campaigns import generate_campaign  # noqa: E402
from workflow.outputs import figures  # noqa: E402
from workflow.outputs.readability import readability_problems  # noqa: E402

snakemake = functools.partial(run_snakemake, timeout=1800)


# ------------------------------------------------------------------ the checker itself
def test_checker_finds_overlapping_tick_labels():
    figure, axis = plt.subplots(figsize=(2.0, 2.0))
    axis.plot([1, 2], [1, 2])
    axis.set_xticks([1.0, 1.05], ["a long label", "another long label"])
    problems = readability_problems(figure)
    assert any("overlap" in problem and "another long label" in problem for problem in problems)


def test_save_logs_the_problems_of_the_figure_as_saved(tmp_path, caplog):
    # save checks the layout its own saving makes (no layout of its own): the same
    # problem is found, logged once, and the PNG is written
    figure, axis = plt.subplots(figsize=(2.0, 2.0))
    axis.plot([1, 2], [1, 2])
    axis.set_xticks([1.0, 1.05], ["a long label", "another long label"])
    with caplog.at_level("WARNING"):
        figures.save(figure, tmp_path / "crowded.png")
    warnings = [record.getMessage() for record in caplog.records if "hard to read" in record.getMessage()]
    assert len(warnings) == 1 and "texts overlap" in warnings[0] and "another long label" in warnings[0]
    assert warnings[0].startswith("figure crowded.png is hard to read")
    assert (tmp_path / "crowded.png").read_bytes().startswith(b"\x89PNG")
    figure, axis = plt.subplots()
    axis.plot([1, 2], [1, 2])
    caplog.clear()
    figures.save(figure, tmp_path / "plain.png")
    assert not [record for record in caplog.records if "hard to read" in record.getMessage()]


def test_save_keeps_the_canvas_of_a_laid_out_figure_and_crops_one_that_spills(tmp_path):
    # a laid-out figure is saved at its own size (no cropping pass); one whose legend
    # reaches past its edge is saved again with everything it draws
    from PIL import Image

    dpi = figures.STYLE["savefig.dpi"]
    with plt.rc_context(figures.STYLE):
        figure, axis = plt.subplots(figsize=(4.0, 3.0))
        axis.plot([1, 2], [1, 2], label="a line")
        figures.legend_beside(axis)
        figures.lay_out(figure)
        figures.save(figure, tmp_path / "inside.png")
        figure, axis = plt.subplots(figsize=(4.0, 3.0))
        axis.plot([1, 2], [1, 2], label="a line with a long name")
        axis.legend(loc="upper left", bbox_to_anchor=(1.3, 1.0))
        figures.save(figure, tmp_path / "spills.png")
    assert Image.open(tmp_path / "inside.png").size == (round(4.0 * dpi), round(3.0 * dpi))
    width, _ = Image.open(tmp_path / "spills.png").size
    assert width > 4.0 * dpi * 1.2  # the canvas and the legend beyond it


def test_a_layout_with_notes_measures_each_panel_once_and_places_it_as_matplotlib_does():
    def two_panels_with_labels():
        figure, axes = plt.subplots(1, 2, figsize=(6.0, 3.0))
        for axis in axes:
            axis.semilogx([0.1, 10.0], [1.0, 2.0])
            figures.amplitude_axis(axis)
            axis.set_ylabel("damping ratio (%)")
            axis.set_title("a panel")
        return figure

    with plt.rc_context(figures.STYLE):
        reference = two_panels_with_labels()
        reference.tight_layout(rect=(0.0, 0.2, 1.0, 1.0))
        figure = two_panels_with_labels()
        calls = []
        measure = type(figure.axes[0]).get_tightbbox
        for axis in figure.axes:
            axis.get_tightbbox = functools.partial(
                lambda axis, *args, **kwargs: calls.append(axis) or measure(axis, *args, **kwargs), axis
            )
        with figures.bounding_boxes_measured_once(figure):
            figure.tight_layout(rect=(0.0, 0.2, 1.0, 1.0))
    # matplotlib's two passes into the rectangle measured each panel once
    assert calls == figure.axes
    # the panels land where matplotlib puts them, to the bit
    assert [axis.get_position().bounds for axis in figure.axes] == [
        axis.get_position().bounds for axis in reference.axes
    ]
    # and measure themselves afterwards as before the block (here: through the counter)
    figure.axes[0].get_tightbbox()
    assert calls[-1] is figure.axes[0] and len(calls) == 3


@pytest.mark.parametrize("notes", [(), ("a note under the panels",)])
def test_a_laid_out_figure_is_placed_as_tight_layout_places_it_and_drawn_once_when_saved(tmp_path, notes):
    def panel():
        figure, axis = plt.subplots(figsize=(5.0, 3.0))
        axis.semilogx([0.1, 10.0], [1.0, 2.0], label="a line")
        figures.amplitude_axis(axis)
        axis.set_ylabel("damping ratio (%)")
        return figure

    with plt.rc_context(figures.STYLE):
        reference = panel()
        bottom = 0.0
        if notes:  # lay_out's rectangle above one line of notes
            bottom = (0.2 + 0.16) / reference.get_size_inches()[1]
        reference.tight_layout(rect=(0.0, bottom, 1.0, 1.0) if notes else None)
        figure = panel()
        figures.lay_out(figure, notes)
        draws = []
        figure.canvas.mpl_connect("draw_event", draws.append)
        figures.save(figure, tmp_path / "panel.png")
    assert figure.axes[0].get_position().bounds == reference.axes[0].get_position().bounds
    # matplotlib's tight_layout leaves a placeholder engine, and savefig then draws twice
    assert len(draws) == 1


def test_checker_finds_an_empty_panel_and_accepts_a_note():
    figure, (left, right) = plt.subplots(1, 2)
    left.plot([1, 2], [1, 2])
    assert any("no data" in problem for problem in readability_problems(figure))
    right.text(0.5, 0.5, "not applicable: one configuration", transform=right.transAxes, ha="center")
    right.set_axis_off()
    assert readability_problems(figure) == []


def test_checker_finds_power_and_offset_notation():
    figure, axis = plt.subplots()
    axis.plot([0.01, 100.0], [1000.0, 1000.001])
    axis.set_xscale("log")
    with plt.rc_context({"axes.formatter.useoffset": True}):
        problems = readability_problems(figure)
    assert any("power notation" in problem for problem in problems)
    assert any("offset notation" in problem for problem in problems)


def test_amplitude_axis_labels_are_plain_and_do_not_crowd():
    for low, high in ((0.3, 0.6), (1.9, 7.4), (0.1, 1.0), (0.05, 3.0), (0.01, 400.0)):
        with plt.rc_context(figures.STYLE):
            figure, axis = plt.subplots()
            axis.plot([low, high], [1.0, 2.0])
            figures.amplitude_axis(axis)
            assert readability_problems(figure) == [], (low, high)
            labels = [label.get_text() for label in axis.get_xticklabels(which="both") if label.get_text()]
            assert len(labels) >= 2, (low, high, labels)


def test_misfit_ranges_find_a_curve_that_misses_and_pass_one_that_fits():
    rng = np.random.default_rng(3)
    amplitude = np.logspace(-1, 1, 400)
    truth = 1.0 + 0.5 * np.log10(amplitude) ** 2
    measured = truth + rng.normal(0.0, 0.02, amplitude.size)
    assert figures.misfit_ranges(amplitude, measured, truth) == []
    # a straight line through the parabola misses its ends and its middle
    line = np.full_like(amplitude, truth.mean())
    ranges = figures.misfit_ranges(amplitude, measured, line)
    assert ranges and ranges[0][0] == pytest.approx(0.1, rel=0.01)
    assert all(offset > 2.0 for _, _, offset in ranges)


def test_misfit_ranges_judge_the_sparse_top_of_a_ring_down():
    # PFF, figure 15: LuGre 12 % above the measured damping at 1.4-4 in/s, where the decay is
    # quickest and an eighth decade holds two or three segments; the note named only the
    # frequency. Segments 0.065 decade apart at the top, 0.01 at the bottom.
    rng = np.random.default_rng(4)
    spacing = np.linspace(0.01, 0.065, 60)
    amplitude = 0.1 * 10 ** np.cumsum(spacing)
    truth = np.log(0.0015) + 0.3 * np.log10(amplitude / 0.1)
    measured = truth + rng.normal(0.0, 0.03, amplitude.size)
    model = truth + np.where((amplitude > 1.4) & (amplitude < 4.0), 0.12, 0.0)
    top = amplitude > 1.4
    assert np.sum(top & (amplitude < 4.0)) < 2 * 5  # fewer than 5 per eighth decade there
    ranges = figures.misfit_ranges(amplitude, measured, model)
    assert any(low < 2.0 and high > 3.0 for low, high, _ in ranges), ranges
    # nowhere else: the model is the truth below 1.4 in/s
    assert all(low >= 1.0 for low, _, _ in ranges)


def test_damping_figure_says_where_its_fit_misses():
    amplitude = np.logspace(-1, 0.5, 300)
    zeta = 0.001 * (1.0 + amplitude**2)
    segments = pd.DataFrame(
        {
            "run": np.repeat(["run01", "run02", "run03"], 100),
            "velocity_amplitude_in_s": amplitude,
            "zeta": zeta * (1 + np.random.default_rng(1).normal(0, 0.01, amplitude.size)),
        }
    )
    flat = pd.DataFrame(
        {"velocity_amplitude_in_s": amplitude, "zeta": np.full_like(amplitude, zeta.mean())}
    ).assign(zeta_low=lambda frame: frame["zeta"] * 0.99, zeta_high=lambda frame: frame["zeta"] * 1.01)
    figure = figures.damping_vs_amplitude(segments, title="t", curve=flat)
    notes = " ".join(text.get_text() for text in figure.texts)
    assert "The polynomial fit misses the measured damping" in notes and " in/s" in notes
    assert readability_problems(figure) == []
    # in SI the same bins are found and said in m/s
    si_notes = " ".join(
        text.get_text()
        for text in figures.damping_vs_amplitude(segments, title="t", curve=flat, units=SI).texts
    )
    assert "misses the measured damping" in si_notes and " m/s" in si_notes and "in/s" not in si_notes
    assert "at 0.0254-0.0508 m/s:" in figures.misfit_sentence("M", "damping", [(1.0, 2.0, 3.0)], SI)
    figure = figures.damping_vs_amplitude(segments, title="t", curve=flat.assign(zeta=zeta))
    assert not figure.texts


def test_friction_model_parameters_are_said_with_their_units():
    assert figures.parameter_text({"sigma": 39.5, "fc": 38.0}) == "σ = 39.5 lbf/in, Fc = 38 lbf"
    assert figures.parameter_text({"sigma": 39.5, "fc": 38.0}, SI) == "σ = 6.92e+03 N/m, Fc = 169 N"


# ------------------------------------------------------------------ the workflow's figures
def hard_to_read(workdir) -> list[str]:
    """The readability warnings ``figures.save`` logged in any rule's log."""
    return [
        line
        for path in sorted((workdir / "results" / "logs").rglob("*.log"))
        for line in path.read_text().splitlines()
        if "is hard to read" in line
    ]


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("demo")
    result = snakemake(workdir, "-c2", "all", "--config", "demo={runs_per_configuration: 3}", *CHEAP)
    assert result.returncode == 0, result.stderr[-4000:]
    return workdir


@pytest.fixture(scope="module")
def one_configuration(tmp_path_factory):
    """A one-configuration campaign through ``all`` in SI units (``units: si``), so that the
    SI figures are checked too (the demo is drawn in the default inch-second units)."""
    root = tmp_path_factory.mktemp("single")
    campaign = root / "campaign"
    generate_campaign(campaign, seed=5, runs_per_configuration=3, configurations={"no_washer": 1.36})
    workdir = root / "work"
    workdir.mkdir()
    result = snakemake(workdir, "-c2", "all", "--config", f"campaign={campaign}", "units=si", *CHEAP)
    assert result.returncode == 0, result.stderr[-4000:]
    return workdir


@pytest.mark.parametrize(("campaign", "configurations"), [("demo", 3), ("one_configuration", 1)])
def test_every_workflow_figure_is_readable(campaign, configurations, request):
    workdir = request.getfixturevalue(campaign)
    drawn = sorted(path.name for path in (workdir / "results" / "figures").glob("*.png"))
    # figures 7, 8, 9, 13, candidates, held-out; per configuration figures 10-12, 14, 15,
    # backbone and residuals
    assert len(drawn) == 6 + 5 * configurations, drawn
    assert hard_to_read(workdir) == []


def test_si_run_writes_model_parameters_and_residuals_in_si(one_configuration):
    fits = pd.read_parquet(one_configuration / "results/tables/model_fits.parquet")
    assert (
        {"N/m", "N", "N s/m", "m/s"}
        <= set(fits["unit_si"])
        <= {"N/m", "N", "N s/m", "m/s", "1", "rad/s", "Hz"}
    )
    # The definitions, not the module's factors: 1 in = 0.0254 m, 1 lbf = 0.45359237 kg x 9.80665 m/s^2.
    inch_m, lbf_n = 0.0254, 0.45359237 * 9.80665
    for parameter, factor in (("sigma", lbf_n / inch_m), ("fc", lbf_n), ("v0", inch_m), ("zeta0", 1.0)):
        rows = fits[fits["parameter"] == parameter]
        np.testing.assert_array_equal(rows["value_si"], rows["value"] * factor)
    residuals = pd.read_parquet(one_configuration / "results/tables/diagnosis_residuals.parquet")
    np.testing.assert_array_equal(
        residuals["velocity_amplitude_m_s"], residuals["velocity_amplitude_in_s"] * inch_m
    )
    verdict = (one_configuration / "results/report/verdict.html").read_text()
    assert "area (m²)" in verdict and " m/s" in verdict


@needs_realdata("unesp-bolted-beam")
def test_unesp_figures_are_readable(tmp_path):
    campaign = REALDATA / "unesp-bolted-beam"
    targets = [
        "results/figures/fig10_damping_t5nm.png",
        "results/figures/fig13_area_fits.png",
        "results/figures/backbone_t5nm.png",
        "results/figures/discovery_residuals_t5nm.png",
        "results/figures/discovery_candidates.png",
        "results/figures/discovery_heldout.png",
    ]
    result = snakemake(tmp_path, "-c2", *targets, "--config", f"campaign={campaign}", *CHEAP)
    assert result.returncode == 0, result.stderr[-4000:]
    assert hard_to_read(tmp_path) == []


def test_area_axis_in_square_metres_has_short_plain_ticks():
    # the demo's areas (0.17, 0.66, 1.36 in²) are 1e-4 m²: labels like 0.000443 ran together
    curves, rows = [], []
    for name, area_in2 in (("no_washer", 1.36), ("large_washer", 0.66), ("small_washer", 0.17)):
        amplitude = np.logspace(-1.3, 0.6, 30)
        zeta = 1e-3 * (1 + area_in2 * amplitude / 5)
        curves.append(
            pd.DataFrame(
                {
                    "configuration": name,
                    "bearing_area_in2": area_in2,
                    "velocity_amplitude_in_s": amplitude,
                    "zeta": zeta,
                    "zeta_low": 0.9 * zeta,
                    "zeta_high": 1.1 * zeta,
                }
            )
        )
        rows += [
            {
                "velocity_amplitude_in_s": v,
                "bearing_area_in2": area_in2,
                "zeta": 1e-3 * (1 + area_in2 * v / 5),
            }
            for v in (0.2, 0.63, 1.5)
        ]
    figure = figures.area_fits(pd.concat(curves), pd.DataFrame(rows), title="t", units=SI)
    figure.canvas.draw()
    labels = [label.get_text() for label in figure.axes[1].get_xticklabels() if label.get_text()]
    assert 3 <= len(labels) <= 7 and all(len(label) <= 6 for label in labels), labels
    assert readability_problems(figure) == []
