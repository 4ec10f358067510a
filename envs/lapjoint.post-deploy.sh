#!/usr/bin/env bash
# Runs once in a new conda environment of envs/lapjoint.yaml: installs the lapjoint package
# (the library the rules' scripts import) from the source tree of the running Snakefile,
# which rules/common.smk exports as LAPJOINT_SOURCE. Dependencies come from the yaml.
set -euo pipefail
python -m pip install --no-deps --editable "${LAPJOINT_SOURCE:?LAPJOINT_SOURCE is set by rules/common.smk}"
