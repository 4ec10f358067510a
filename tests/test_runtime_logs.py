"""Script logging: messages and uncaught errors reach the rule's log, and the log ends
with the script's cost (start-up vs work CPU seconds, peak memory)."""

import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

SCRIPT = """
import sys
sys.path.insert(0, {repo!r})
from workflow.runtime.logs import setup_script_logging
log = setup_script_logging({log!r}, "demo")
log.info("hello")
import numpy as np
x = np.ones(40 * 2**20 // 8)  # 40 MiB held at once
total = 0.0
for _ in range(40):
    total += float((x * 1.0001).sum())
{tail}
"""

COST = re.compile(r"cost: start-up ([0-9.]+) s CPU, work ([0-9.]+) s CPU, peak memory ([0-9]+) MB")


def run_script(tmp_path, tail=""):
    log = tmp_path / "logs" / "demo.log"
    source = SCRIPT.format(repo=str(REPO), log=str(log), tail=tail)
    result = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True)
    return result, log.read_text()


def test_log_ends_with_the_cost_of_start_up_and_work(tmp_path):
    result, text = run_script(tmp_path)
    assert result.returncode == 0, result.stderr
    assert "demo INFO hello" in text
    start_up, work, peak_mb = (float(value) for value in COST.search(text.splitlines()[-1]).groups())
    # numpy is imported after logging is set up, so its import counts as work here:
    # both parts are positive; 40 passes over 40 MiB take well over a millisecond.
    assert start_up > 0 and work > 1e-3
    # The 40 MiB array plus its temporary (another 40 MiB) were resident at once.
    assert 80 <= peak_mb < 400


def test_uncaught_error_is_logged_before_the_cost(tmp_path):
    result, text = run_script(tmp_path, tail="raise ValueError('bad cell in run07')")
    assert result.returncode != 0
    assert "stopped: bad cell in run07" in text
    assert COST.search(text.splitlines()[-1])


def test_a_deliberate_stop_is_logged_without_a_traceback_and_fails(tmp_path):
    tail = (
        "from workflow.runtime.logs import ScriptStop\nraise ScriptStop('strict mode: run excluded: run07')"
    )
    result, text = run_script(tmp_path, tail=tail)
    assert result.returncode == 1
    assert "ERROR stopped: strict mode: run excluded: run07" in text
    assert "Traceback" not in text and "Traceback" not in result.stderr
    assert COST.search(text.splitlines()[-1])


def test_the_process_ends_after_the_cost_line_with_its_output_flushed(tmp_path):
    # The script ends without the interpreter's teardown: what it printed (buffered, as
    # stdout is in a pipe) and every log line must still be written, the status 0;
    # exit handlers registered after logging was set up still run first.
    tail = (
        "import atexit\n"
        "atexit.register(lambda: print('own exit handler'))\n"
        "print('printed ' * 1000)\n"
        "log.info('last message')"
    )
    result, text = run_script(tmp_path, tail=tail)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("printed") == 1000
    assert result.stdout.rstrip().endswith("own exit handler")
    lines = text.splitlines()
    assert "demo INFO last message" in lines[-2] and COST.search(lines[-1])


def test_no_script_raises_system_exit():
    # the end of setup_script_logging cannot see SystemExit's status (it would exit 0)
    for script in sorted((REPO / "scripts").glob("*.py")):
        source = script.read_text()
        assert "SystemExit" not in source and "sys.exit" not in source and "exit(" not in source, script.name


def test_peak_memory_is_the_scripts_own_not_its_parents(tmp_path):
    # A parent holding 300 MiB starts the script (fork + exec, as Snakemake does):
    # the script's reported peak must not include the parent's memory.
    log = tmp_path / "logs" / "demo.log"
    child = SCRIPT.format(repo=str(REPO), log=str(log), tail="")
    parent = (
        f'import subprocess, sys\nblock = b"\\x01" * (300 * 2**20)  # resident: every page written\n'
        f"subprocess.run([sys.executable, '-c', {child!r}], check=True)"
    )
    subprocess.run([sys.executable, "-c", parent], check=True)
    peak_mb = float(COST.search(log.read_text().splitlines()[-1]).group(3))
    assert 80 <= peak_mb < 300


GARBAGE_COLLECTION = """
import gc, sys
sys.path.insert(0, {repo!r})
{preamble}
import workflow
print(gc.isenabled())
from workflow.runtime.logs import setup_script_logging
setup_script_logging(None, "demo")
print(gc.isenabled())
"""


def garbage_collection_states(preamble: str) -> list[str]:
    source = GARBAGE_COLLECTION.format(repo=str(REPO), preamble=preamble)
    result = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout.split()


def test_a_job_script_collects_no_garbage_while_it_imports():
    # Snakemake's script preamble puts its Snakemake object in __main__ before the script runs
    preamble = "from snakemake.iocontainers import Snakemake\nsnakemake = Snakemake.__new__(Snakemake)"
    assert garbage_collection_states(preamble) == ["False", "True"]


def test_importing_the_library_elsewhere_leaves_garbage_collection_on():
    assert garbage_collection_states("") == ["True", "True"]
