# Measured-data chain: raw ASCII -> first mode -> each run's band-pass, envelope,
# segmented log decrement -> Parquet tables -> damping fits and hypotheses.


rule campaign_settings:
    input:
        campaign_yaml=campaign_yaml,
    output:
        "results/interim/campaign.json",
    log:
        "results/logs/campaign_settings.log",
    benchmark:
        "results/benchmarks/campaign_settings.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    script:
        "../scripts/campaign_settings.py"


# identify_mode also analyses the configuration's first group of runs (analyse_runs's
# work) with the runs it has read for the mode search: no file of that group is read
# twice, and a configuration of at most runs_per_job runs is one job.
ruleorder: identify_mode > analyse_runs


rule identify_mode:
    input:
        campaign_settings="results/interim/campaign.json",
        runs=configuration_run_files,
    output:
        mode="results/interim/mode/{configuration}.json",
        segments=f"results/interim/segments/{{configuration}}/{FIRST_RUN_GROUP}.npz",
        quality=f"results/interim/quality/{{configuration}}/{FIRST_RUN_GROUP}.npz",
        status=f"results/interim/status/{{configuration}}/{FIRST_RUN_GROUP}.json",
    log:
        "results/logs/identify_mode/{configuration}.log",
    benchmark:
        "results/benchmarks/identify_mode/{configuration}.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=lambda wildcards, input: identify_mode_mem_mb(input.runs, first_run_group_files(wildcards)),
        runtime=10,
    params:
        campaign=str(CAMPAIGN),
        first_group=lambda wildcards: [str(path) for path in first_run_group_files(wildcards)],
        strict=SETTINGS.strict,
        analysis=asdict(SETTINGS.analysis),
        quality=asdict(SETTINGS.quality),
    script:
        "../scripts/identify_mode.py"


rule analyse_runs:
    input:
        campaign_settings="results/interim/campaign.json",
        runs=run_group_files,
        mode="results/interim/mode/{configuration}.json",
    output:
        segments="results/interim/segments/{configuration}/{group}.npz",
        quality="results/interim/quality/{configuration}/{group}.npz",
        status="results/interim/status/{configuration}/{group}.json",
    log:
        "results/logs/analyse_runs/{configuration}/{group}.log",
    benchmark:
        "results/benchmarks/analyse_runs/{configuration}/{group}.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=lambda wildcards, input: analyse_runs_mem_mb(input.runs),
        runtime=10,
    params:
        campaign=str(CAMPAIGN),
        strict=SETTINGS.strict,
        analysis=asdict(SETTINGS.analysis),
        quality=asdict(SETTINGS.quality),
    script:
        "../scripts/analyse_runs.py"


rule collect_tables:
    input:
        segments=run_group_outputs("segments", "npz"),
        quality=run_group_outputs("quality", "npz"),
        status=run_group_outputs("status", "json"),
        modes=expand("results/interim/mode/{configuration}.json", configuration=CONFIGURATIONS),
        campaign_settings="results/interim/campaign.json",
    output:
        segments="results/interim/segments.parquet",
        rejected="results/tables/segments_rejected.parquet",
        runs="results/tables/runs.parquet",
        runs_csv="results/tables/runs.csv",
        quality="results/tables/quality.parquet",
        modes="results/tables/modes.parquet",
    log:
        "results/logs/collect_tables.log",
    benchmark:
        "results/benchmarks/collect_tables.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    params:
        excluded_paths=[entry.status() for entry in EXCLUDED_PATHS],
    script:
        "../scripts/collect_tables.py"


# Every later step reads the kept segments: when there are none, the workflow stops here
# with one message (which runs, why, what to change) instead of in whichever step runs first.
rule usable_segments:
    input:
        segments="results/interim/segments.parquet",
        runs="results/tables/runs.parquet",
        rejected="results/tables/segments_rejected.parquet",
    output:
        "results/tables/segments.parquet",
    log:
        "results/logs/usable_segments.log",
    benchmark:
        "results/benchmarks/usable_segments.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/usable_segments.py"


rule fit_curves:
    input:
        segments="results/tables/segments.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        fits="results/tables/damping_fits.parquet",
        curves="results/tables/damping_curves.parquet",
        hypotheses="results/tables/hypotheses.parquet",
        area="results/tables/area_fits.parquet",
    log:
        "results/logs/fit_curves.log",
    benchmark:
        "results/benchmarks/fit_curves.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,
    params:
        fits=asdict(SETTINGS.fits),
    script:
        "../scripts/fit_curves.py"
