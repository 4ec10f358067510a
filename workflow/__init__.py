"""lapjoint: ring-down analysis of bolted lap joints.

The importable, tested library behind the Snakemake workflow. Modules hold small
numerical functions (arrays in, arrays out); the scripts in ``scripts/`` only map
Snakemake's inputs, params and outputs onto them.

Internal units are inch, second and pound-force (in, in/s, in/s^2, lbf), the units
of the original study.
"""
