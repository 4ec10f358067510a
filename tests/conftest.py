"""Test-session settings."""

import os

from hypothesis import settings

# Under CI the property tests draw the same examples on every run, so that a failure there
# reproduces; elsewhere they draw new ones each run and keep searching.
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")
