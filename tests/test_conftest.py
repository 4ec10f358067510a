"""A test group CI is meant to run fails the run when it is skipped (tests/conftest.py)."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

SKIPPING_TEST = """
import pytest

@pytest.mark.group("chromium")
@pytest.mark.skipif(True, reason="no chromium here")
def test_in_a_browser():
    pass

@pytest.mark.group("realdata")
def test_on_real_data():
    pytest.skip("real data not present")

def test_plain():
    pass
"""


def run_pytest(folder: Path, **variables: str) -> subprocess.CompletedProcess:
    env = {key: value for key, value in os.environ.items() if not key.startswith("LAPJOINT_REQUIRE_")}
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rA", str(folder)],
        capture_output=True,
        text=True,
        env={**env, **variables},
        cwd=folder,
    )


@pytest.fixture
def suite(tmp_path):
    shutil.copyfile(TESTS / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_groups.py").write_text(SKIPPING_TEST)
    return tmp_path


def test_a_skipped_group_passes_where_it_is_not_required(suite):
    result = run_pytest(suite)
    assert result.returncode == 0, result.stdout
    assert "1 passed, 2 skipped" in result.stdout


@pytest.mark.parametrize(
    "variable, failing",
    [("LAPJOINT_REQUIRE_CHROMIUM", "test_in_a_browser"), ("LAPJOINT_REQUIRE_REALDATA", "test_on_real_data")],
)
def test_a_skipped_group_fails_where_it_is_required(suite, variable, failing):
    result = run_pytest(suite, **{variable: "1"})
    assert result.returncode == 1, result.stdout
    # A skip at setup (skipif) is reported as an error, one in the test's body as a failure.
    assert f"test_groups.py::{failing} - {variable}=1" in result.stdout
    assert "1 passed, 1 skipped" in result.stdout
    assert f"{variable}=1, but the test was skipped" in result.stdout


def test_an_unknown_group_is_an_error_not_a_silent_pass(suite):
    (suite / "test_groups.py").write_text(
        'import pytest\n\n@pytest.mark.group("chromiun")\ndef test_typo():\n    pytest.skip("x")\n'
    )
    result = run_pytest(suite, LAPJOINT_REQUIRE_CHROMIUM="1")
    assert result.returncode != 0
    assert "unknown test group ['chromiun']" in result.stdout + result.stderr
