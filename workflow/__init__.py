"""lapjoint: ring-down analysis of bolted lap joints.

The importable, tested library behind the Snakemake workflow. Modules hold small
numerical functions (arrays in, arrays out); the scripts in ``scripts/`` only map
Snakemake's inputs, params and outputs onto them.

Internal units are inch, second and pound-force (in, in/s, in/s^2, lbf), the units
of the original study.
"""

__all__ = ["ring_down_table", "load_results", "run_campaign", "CampaignResults"]


def __getattr__(name: str):
    # the API (workflow.api) is imported on first use: `import workflow` stays cheap
    if name in __all__:
        from workflow import api

        return getattr(api, name)
    raise AttributeError(f"module 'workflow' has no attribute {name!r}")
