# ruff: noqa: E402 (the thread settings precede the imports of NumPy)
"""Per-record speed against a published peer method, on that method's own record.

The peer is PFF (peak finding and fitting: Jin, Chen, Brake and Song, "Identification of
instantaneous frequency and damping from transient decay data", J. Vib. Acoust. 142
(2020) 051111), whose sample record ships as a MATLAB file
(../shared/realdata/raw/pff_Sample_LMS_Data.mat: 131,072 samples at 51.2 kHz, mode
near 153.9 Hz). Its Python port (JustinPorter88/pff-analysis, ``pff.py``) carries no
licence, so it is not vendored here: :func:`pff_extraction` re-implements the method
from the paper's description, with the port's settings for this record (band 10 Hz
wide around the spectrum's peak within 20 % of the nominal 151 Hz, order-3 Butterworth
run forward and backward, analysis from 0.05 s after the largest sample to 2.0 s):

1. the spectrum's largest peak near the nominal frequency is the filter's centre;
2. a zero-phase band-pass (``scipy.signal.sosfiltfilt``) isolates the mode;
3. every local maximum and minimum of the filtered signal is refined by the parabola
   through it and its two neighbours (time and value of the vertex);
4. consecutive extrema are half a period apart: ``omega = pi / dt``; the damping ratio
   is the log decrement of each extremum's two neighbours,
   ``zeta = -ln(|a[k+1]| / |a[k-1]|) / (omega (t[k+1] - t[k-1]))``.

The parabolas are solved in closed form for all extrema at once (the port solves a
3 x 3 system per extremum in a Python loop): a peer at least as fast as the published one.
``--published-port DIR`` also times the published port itself, from a copy of its
``pff.py`` that the user puts in DIR (it is not part of this repository): its
``pff_analysis`` as its own test calls it on this record (nominal 153.9 Hz, a half band
of 10/153.9 of the peak, order 3, from 0.05 s after the largest sample to 2.0 s,
``remove_end=20``), after ``scipy.io.loadmat`` of the file, as a third participant in
the same alternation.
On the sample record it reproduces the method's published output
(../shared/realdata/pff-lms-sample.reference.csv) between 0.3 and 1.8 s: damping -1.7 %
in the median (5.5 % median absolute difference, point by point), frequency +0.014 Hz.

The project's work on the same file is what its ``identify_mode`` job does for a
configuration of one run: read the campaign's settings (the JSON that the
``campaign_settings`` job wrote once from campaign.yaml), read the MAT file once
(:func:`read_runs`), find the mode (:func:`identify_configuration_mode`) and run the
decay analysis on the record already read (:func:`analyse_run_file`). Each side is run
in turn, alternating, in this one process after a warm-up of both (imports, caches of
the first call), and the medians are printed with their ratio and the machine's speed
(the reference loop of bench_workflow.py). The synthetic decay of the start-up bias,
kept from a record's probe to its bias, is forgotten before each round: it has the
record's own damping and frequency, and a round that found it kept from the last would
time a repeat that the workflow never makes. The band's power response, which the
records of a configuration share (one length, rate and band), is kept.

Both run single-threaded, as the workflow's jobs do (Snakemake gives a ``threads: 1``
job one BLAS thread): a threaded BLAS call leaves its threads spinning on a loaded
machine, and the next timed work, either side's, pays for them.

    python bench/peer_speed.py [--repeats 7] [--raw ../shared/realdata/raw] [--published-port DIR]
"""

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"  # before NumPy is imported

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.io
from bench_workflow import REFERENCE_ADDITIONS, reference_loop_s
from scipy import signal

from workflow.io.campaign import Campaign, load_campaign
from workflow.io.interim import ConfigurationMode, read_campaign, write_campaign
from workflow.io.run_files import list_runs
from workflow.measured.decay import _decay_from_rest
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import RunAnalysis, analyse_run_file, read_runs
from workflow.measured.settings import AnalysisSettings, QualitySettings

NOMINAL_HZ = 151.0
"""The mode's approximate frequency, as the converted campaign gives it (mode_hz), Hz."""

CAMPAIGN_YAML = f"""name: pff-lms-sample
sample_rate_hz: 51200
mode_hz: {NOMINAL_HZ:g}
response: {{quantity: acceleration, unit: m/s^2, channel: x}}
configurations:
  decay: {{files: "decay/*.mat"}}
"""


def _parabola_vertices(t: np.ndarray, x: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) and value of the vertex of the parabola through samples ``peaks - 1``,
    ``peaks``, ``peaks + 1`` (equally spaced), for every index in ``peaks``."""
    before, at, after = x[peaks - 1], x[peaks], x[peaks + 1]
    curvature = before - 2.0 * at + after
    offset = 0.5 * (before - after) / curvature
    dt = t[1] - t[0]
    return t[peaks] + offset * dt, at - 0.25 * (before - after) * offset


def pff_extraction(
    t: np.ndarray,
    x: np.ndarray,
    *,
    nominal_hz: float,
    band_width_hz: float = 10.0,
    search_fraction: float = 0.2,
    order: int = 3,
    start_s: float,
    stop_s: float,
) -> dict[str, np.ndarray]:
    """Instantaneous frequency (Hz) and damping ratio of a ring-down by PFF (see the
    module's docstring), at the times of the extrema of the filtered signal (s)."""
    inside = (t >= start_s) & (t <= stop_s)
    t, x = t[inside], x[inside] - x[inside].mean()
    fs_hz = 1.0 / (t[1] - t[0])
    frequency_hz = np.fft.rfftfreq(t.size, 1.0 / fs_hz)
    near = np.abs(frequency_hz - nominal_hz) < search_fraction * nominal_hz
    centre_hz = frequency_hz[near][np.argmax(np.abs(np.fft.rfft(x))[near])]
    band_hz = (centre_hz - band_width_hz / 2.0, centre_hz + band_width_hz / 2.0)
    filtered = signal.sosfiltfilt(signal.butter(order, band_hz, "bandpass", fs=fs_hz, output="sos"), x)
    inner = filtered[1:-1]
    maxima = np.flatnonzero((inner > filtered[:-2]) & (inner > filtered[2:])) + 1
    minima = np.flatnonzero((inner < filtered[:-2]) & (inner < filtered[2:])) + 1
    extrema = np.sort(np.concatenate([maxima, minima]))
    peak_t, peak_x = _parabola_vertices(t, filtered, extrema)
    omega = np.pi / np.diff(peak_t)[1:]
    log_amplitude = np.log(np.abs(peak_x))
    zeta = -(log_amplitude[2:] - log_amplitude[:-2]) / (omega * (peak_t[2:] - peak_t[:-2]))
    return {
        "t_s": peak_t[1:-1],
        "amplitude": np.abs(peak_x[1:-1]),
        "frequency_hz": omega / (2.0 * np.pi),
        "zeta": zeta,
    }


def peer_record(mat_path: Path) -> dict[str, np.ndarray]:
    """The peer's whole per-record work: read the MAT file, extract."""
    data = scipy.io.loadmat(mat_path)
    t, x = data["t"].ravel(), data["x"].ravel()
    return pff_extraction(t, x, nominal_hz=NOMINAL_HZ, start_s=t[np.argmax(x)] + 0.05, stop_s=2.0)


def published_port_record(port, mat_path: Path):
    """The published port's per-record work as its own test does it on this record: read
    the MAT file, ``pff_analysis`` (``port``: its imported ``pff`` module)."""
    data = scipy.io.loadmat(mat_path)
    start_s = data["t"][np.argmax(data["x"])] + 0.05
    return port.pff_analysis(data["t"][:, 0], data["x"], 153.9, start_s, 2.0, 10.0 / 153.9, remove_end=20)


def project_record(folder: Path, campaign: Campaign) -> tuple[ConfigurationMode, RunAnalysis]:
    """The project's per-record work on the one run of the campaign in ``folder``, as its
    ``identify_mode`` job does it once the campaign is read: the file read once, the mode
    search and the decay analysis."""
    run_file = list_runs(folder, campaign)[0]
    quality_settings = QualitySettings()
    reads = read_runs(folder, [run_file.path], campaign, quality_settings)
    options = {
        "configuration": run_file.configuration,
        "campaign": campaign,
        "quality_settings": quality_settings,
    }
    mode = identify_configuration_mode(
        folder, [run_file.path], mode_search=AnalysisSettings(), reads=reads, **options
    )
    result = analyse_run_file(
        folder,
        run_file.path,
        mode=mode,
        decay_settings=AnalysisSettings(),
        read=reads[run_file.path],
        **options,
    )
    if result.status["status"] != "used":
        raise RuntimeError(f"the project excluded the record: {result.status['reason']}")
    return mode, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument(
        "--raw", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "realdata" / "raw"
    )
    parser.add_argument(
        "--published-port",
        type=Path,
        help="a folder holding a copy of the published port's pff.py (JustinPorter88/pff-analysis), "
        "timed as a third participant",
    )
    args = parser.parse_args()
    mat_path = args.raw / "pff_Sample_LMS_Data.mat"
    port = None
    if args.published_port is not None:
        import importlib.util

        spec = importlib.util.spec_from_file_location("pff", args.published_port / "pff.py")
        port = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(port)
    before_s = reference_loop_s()
    folder = Path(tempfile.mkdtemp(prefix="lapjoint-peer-speed-"))
    try:
        (folder / "decay").mkdir()
        # a copy: a link leading outside the campaign is not read (docs/input-safety.md)
        shutil.copyfile(mat_path, folder / "decay" / "run01.mat")
        (folder / "campaign.yaml").write_text(CAMPAIGN_YAML)
        # campaign.yaml validated once, as the workflow's campaign_settings job does
        settings_json = folder / "campaign.json"
        write_campaign(settings_json, load_campaign(folder))
        work = {
            "peer (PFF)": lambda: peer_record(mat_path),
            "project": lambda: (
                _decay_from_rest.cache_clear(),
                project_record(folder, read_campaign(settings_json))[1].segments,
            )[1],
        }
        if port is not None:
            work["published port (PFF)"] = lambda: published_port_record(port, mat_path)
        seconds = {name: [] for name in work}
        outputs = {}
        for repeat in range(args.repeats + 1):
            for name, run in work.items():
                start = time.perf_counter()
                outputs[name] = run()
                if repeat:  # the first round is the warm-up
                    seconds[name].append(time.perf_counter() - start)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    kept = outputs["project"]["kept"]
    print(f"| per record, {args.repeats} alternating rounds | median s | range s |")
    print("|---|---|---|")
    for name, values in seconds.items():
        print(f"| {name} | {statistics.median(values):.3f} | {min(values):.3f}-{max(values):.3f} |")
    print()
    for name in seconds:
        if name == "project":
            continue
        ratios = [a / b for a, b in zip(seconds["project"], seconds[name])]
        ratio = statistics.median(seconds["project"]) / statistics.median(seconds[name])
        print(
            f"project / {name.removesuffix(' (PFF)')}: {ratio:.2f} (ratio of medians); the rounds' ratios "
            f"{statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f})"
        )
    pff = outputs["peer (PFF)"]
    print(
        f"peer: {pff['t_s'].size} extrema, median {np.median(pff['frequency_hz']):.2f} Hz, "
        f"zeta {np.median(pff['zeta']):.5f}; project: {int(kept.sum())} of {kept.size} segments kept, "
        f"median {np.median(outputs['project']['frequency_hz'][kept]):.2f} Hz, "
        f"zeta {np.median(outputs['project']['zeta'][kept]):.5f}"
    )
    print(
        f"The machine: {REFERENCE_ADDITIONS:,} integer additions in a Python loop took "
        f"{before_s:.2f} s of CPU before these runs and {reference_loop_s():.2f} s after (medians of 3)."
    )


if __name__ == "__main__":
    main()
