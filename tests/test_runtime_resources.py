"""The memory the run-reading jobs declare (workflow/runtime/resources.py) holds for long
records: a job within its declaration is never killed by a cluster that enforces it."""

import pytest

from workflow.runtime.resources import analyse_runs_mem_mb, identify_mode_mem_mb, samples_at_most

# Peaks (MB, as mem_mb) measured by bench/bench_long_record_memory.py on a 1e7-sample ASCII
# run (362 MB, time, force, response): 2003 in analyse_runs (one run), 976 to read it.
MEASURED_ANALYSE_RUNS_MB = 2003
MEASURED_READ_MB = 976
# On a 5,555,555-sample run (200 MB), whose length NumPy's FFT takes by Bluestein's
# algorithm: 1389 MB in identify_mode holding two such runs and analysing both.
BLUESTEIN_SAMPLES = 5_555_555
MEASURED_IDENTIFY_MODE_TWO_RUNS_ANALYSED_MB = 1389


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_ascii_samples_bounded_by_its_lines_whatever_the_line_ending(tmp_path, newline):
    path = tmp_path / "run.txt"
    rows = [f"{i / 2560:.6f}\t0.1\t-0.2" for i in range(1000)]
    path.write_bytes(newline.join(["Sample rate: 2560 Hz", "Time (s)\tForce (lbf)\tAcc (g)", *rows]).encode())
    assert 1000 <= samples_at_most(path) <= 1003


def test_binary_samples_bounded_by_float32_values(tmp_path):
    # A system format stores at least a float32 (4 bytes) per sample of the response.
    path = tmp_path / "run.tdms"
    path.write_bytes(bytes(4000))
    assert samples_at_most(path) == 1000


def ten_million_sample_file(tmp_path):
    # Only the lines matter to the declaration: 1e7 empty lines stand for the bench's
    # 1e7-sample run at 10 MB instead of 362 MB.
    path = tmp_path / "long.txt"
    path.write_bytes(b"\n" * 10_000_000)
    return path


def test_analyse_runs_declares_the_peak_measured_on_a_long_record(tmp_path):
    long = ten_million_sample_file(tmp_path)
    assert analyse_runs_mem_mb([long]) >= MEASURED_ANALYSE_RUNS_MB
    # Runs of a job are analysed one at a time: the longest sets the need, not their sum.
    short = tmp_path / "short.txt"
    short.write_bytes(b"\n" * 8192)
    assert analyse_runs_mem_mb([long, short, short]) == analyse_runs_mem_mb([long])


def test_identify_mode_declares_every_run_held_at_once(tmp_path):
    long = ten_million_sample_file(tmp_path)
    one, two = identify_mode_mem_mb([long]), identify_mode_mem_mb([long, long])
    assert one >= MEASURED_READ_MB
    # A second 1e7-sample run held as three float64 columns adds 240 MB.
    assert two - one >= 10_000_000 * 3 * 8 / 1e6
    # Its first group analysed from the runs held: the longest analysis above them.
    assert identify_mode_mem_mb([long, long], [long, long]) >= MEASURED_ANALYSE_RUNS_MB + two - one
    bluestein = tmp_path / "bluestein.txt"
    bluestein.write_bytes(b"\n" * (BLUESTEIN_SAMPLES + 1))
    assert (
        identify_mode_mem_mb([bluestein] * 2, [bluestein] * 2) >= MEASURED_IDENTIFY_MODE_TWO_RUNS_ANALYSED_MB
    )


def test_a_usual_run_declares_well_under_a_gigabyte(tmp_path):
    # 8192 samples (the original lab's records) must not ask a cluster for gigabytes.
    path = tmp_path / "run.txt"
    path.write_bytes(b"0.000391\t0.0019\t-0.00021\n" * 8192)
    assert analyse_runs_mem_mb([path]) < 500
    assert identify_mode_mem_mb([path] * 10) < 500
