"""Test-session settings: the property tests' profile, and test groups CI may require."""

import os

# Tests that diagnose in-process use one BLAS thread, as every Snakemake job does: the
# diagnosis's many small matrix products slow down by an order of magnitude when OpenBLAS
# threads compete on a busy 2-core machine. Set before anything imports NumPy.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

# Under CI the property tests draw the same examples on every run, so that a failure there
# reproduces; elsewhere they draw new ones each run and keep searching.
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


REQUIRED_GROUP_VARIABLES = {
    "chromium": "LAPJOINT_REQUIRE_CHROMIUM",
    "slurm": "LAPJOINT_REQUIRE_SLURM",
    "realdata": "LAPJOINT_REQUIRE_REALDATA",
}
"""Test group -> the variable that, set to 1 (as .ci/run does where the machine can provide
the group), turns a skip of any test of the group into a failure: a group CI is meant to
run never passes unseen."""


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "group(name): the test needs what group `name` provides (chromium, slurm, realdata); "
        "with LAPJOINT_REQUIRE_<NAME>=1 its skip is a failure",
    )


def required_groups(item) -> list[str]:
    """The groups of ``item`` whose LAPJOINT_REQUIRE_ variable is set to 1."""
    groups = [mark.args[0] for mark in item.iter_markers("group")]
    unknown = [group for group in groups if group not in REQUIRED_GROUP_VARIABLES]
    if unknown:
        raise pytest.UsageError(f"{item.nodeid}: unknown test group {unknown}")
    return [group for group in groups if os.environ.get(REQUIRED_GROUP_VARIABLES[group]) == "1"]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    report = (yield).get_result()
    if report.skipped and not hasattr(report, "wasxfail"):
        required = required_groups(item)
        if required:
            reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
            variables = ", ".join(f"{REQUIRED_GROUP_VARIABLES[group]}=1" for group in required)
            report.outcome = "failed"
            report.longrepr = f"{variables}, but the test was skipped: {reason}"
