"""lapjoint: ring-down analysis of bolted lap joints.

The importable, tested library behind the Snakemake workflow. Modules hold small
numerical functions (arrays in, arrays out); the scripts in ``scripts/`` only map
Snakemake's inputs, params and outputs onto them.

Internal units are inch, second and pound-force (in, in/s, in/s^2, lbf), the units
of the original study.
"""

import gc
import sys

__all__ = ["ring_down_table", "load_results", "run_campaign", "CampaignResults"]

if type(getattr(sys.modules["__main__"], "snakemake", None)).__module__ == "snakemake.iocontainers":
    # A job's script (Snakemake's preamble has put its `snakemake` object in __main__):
    # no garbage collection while the job imports its libraries, whose objects all live
    # as long as the job (a tenth of a figure job's CPU went to collecting them);
    # workflow.runtime.logs.setup_script_logging turns it back on after the imports.
    gc.disable()


def __getattr__(name: str):
    # the API (workflow.api) is imported on first use: `import workflow` stays cheap
    if name in __all__:
        from workflow import api

        return getattr(api, name)
    raise AttributeError(f"module 'workflow' has no attribute {name!r}")
