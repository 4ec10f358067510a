# Model discovery: where the paper's model is wrong, the cause, the extended model
# and its gain on held-out data (results/diagnosis.json, output contract).


rule diagnose_configuration:
    # One job per configuration, so that the configurations are diagnosed side by side;
    # each reads every segment because the fits' reference velocity is the campaign's.
    # The configuration's time-domain fits (Dahl, LuGre; results/models) follow in the
    # same job: they start from the diagnosis's averaged fits, and in a job of their own
    # half of their time was start-up (pandas, SciPy's stats, Numba) and teardown.
    input:
        segments="results/tables/segments.parquet",
        runs="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        diagnosis="results/interim/diagnosis/{configuration}.npz",
        models="results/models/{configuration}.json",
    log:
        "results/logs/diagnose_configuration/{configuration}.log",
    benchmark:
        "results/benchmarks/diagnose_configuration/{configuration}.tsv"
    # The study's longest chain is a configuration's diagnosis and fits, then figures
    # 14-15 (rules/models.smk): they go before the figures of the measured data, the
    # largest bearing area (the most models to fit) first.
    priority: diagnosis_priority
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=3000,
        runtime=60,
    params:
        analysis=asdict(SETTINGS.analysis),
        discovery=asdict(SETTINGS.discovery),
        models=asdict(SETTINGS.models),
    script:
        "../scripts/diagnose_configuration.py"


rule diagnose_modes:
    # Every mode of one response channel of one configuration (campaign.yaml's modes_hz
    # or auto, response.channels): one job per channel, so that the channels of a hit
    # are diagnosed side by side.
    input:
        segments="results/tables/segments.parquet",
        runs="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        directory("results/interim/diagnosis_modes/{configuration}/{channel_key}"),
    log:
        "results/logs/diagnose_modes/{configuration}/{channel_key}.log",
    benchmark:
        "results/benchmarks/diagnose_modes/{configuration}/{channel_key}.tsv"
    priority: 1
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=3000,
        runtime=60,
    params:
        channel=lambda wildcards: RESPONSE_CHANNELS[channel_index(wildcards.channel_key)],
        analysis=asdict(SETTINGS.analysis),
        discovery=asdict(SETTINGS.discovery),
    script:
        "../scripts/diagnose_modes.py"


rule diagnose_joint:
    # Every mode of one configuration from all its response channels at once: one
    # joint analysis (workflow/discovery/joint.py), one job per configuration.
    input:
        segments="results/tables/segments.parquet",
        runs="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        directory("results/interim/diagnosis_joint/{configuration}"),
    log:
        "results/logs/diagnose_joint/{configuration}.log",
    benchmark:
        "results/benchmarks/diagnose_joint/{configuration}.tsv"
    priority: 1
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=3000,
        runtime=60,
    params:
        channel=None,
        analysis=asdict(SETTINGS.analysis),
        discovery=asdict(SETTINGS.discovery),
    script:
        "../scripts/diagnose_modes.py"


rule diagnose:
    # The campaign's diagnosis from its configurations'. It does not depend on config
    # units: switching them redraws the figures below and re-runs no diagnosis.
    input:
        configurations=expand("results/interim/diagnosis/{configuration}.npz", configuration=CONFIGURATIONS),
        modes_channels=mode_channel_diagnoses(),
        joint=joint_diagnoses(),
        modes="results/tables/modes.parquet",
        segments="results/tables/segments.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        diagnosis=report(
            "results/diagnosis.json",
            caption="../report/diagnosis_json.rst",
            category="5 Diagnosis",
            subcategory="5.2 Candidates and held-out prediction",
            labels={"item": "file: diagnosis.json (download)"},
        ),
        residuals="results/tables/diagnosis_residuals.parquet",
    log:
        "results/logs/diagnose.log",
    benchmark:
        "results/benchmarks/diagnose.tsv"
    # The report and the summary wait for it: ahead of the measured data's figures, so
    # that it does not end the study alone on one core.
    priority: 1
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        channels=list(RESPONSE_CHANNELS),
    script:
        "../scripts/diagnose.py"


rule figures_discovery:
    # Every diagnosis figure, from the two files the diagnosis wrote, in config units.
    input:
        diagnosis="results/diagnosis.json",
        residuals="results/tables/diagnosis_residuals.parquet",
    output:
        residual_figures=[
            report(
                f"results/figures/discovery_residuals_{name}.png",
                caption="../report/discovery_residuals.rst",
                category="5 Diagnosis",
                subcategory="5.1 Residuals per configuration",
                labels={"figure": f"residuals: {name}"},
            )
            for name in CONFIGURATIONS
        ],
        candidates=report(
            "results/figures/discovery_candidates.png",
            caption="../report/discovery_candidates.rst",
            category="5 Diagnosis",
            subcategory="5.2 Candidates and held-out prediction",
            labels={"item": "figure: held-out error of every candidate"},
        ),
        heldout=report(
            "results/figures/discovery_heldout.png",
            caption="../report/discovery_heldout.rst",
            category="5 Diagnosis",
            subcategory="5.2 Candidates and held-out prediction",
            labels={"item": "figure: prediction of a left-out bearing area"},
        ),
    log:
        "results/logs/figures_discovery.log",
    benchmark:
        "results/benchmarks/figures_discovery.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        configurations=CONFIGURATIONS,
        units=SETTINGS.units,
        channels=list(RESPONSE_CHANNELS),
    script:
        "../scripts/figures_discovery.py"
