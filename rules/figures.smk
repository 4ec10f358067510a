# Figures of the measured-data chain (paper figures 9-13 and the backbones).


rule figure_time_history:
    input:
        runs_table="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        report(
            "results/figures/fig09_time_history.png",
            caption="../report/fig09_time_history.rst",
            category="2 Measured data",
            subcategory="2.1 Time history (fig. 9)",
            labels={"figure": "fig. 9: raw, band-passed, envelope"},
        ),
    log:
        "results/logs/figure_time_history.log",
    benchmark:
        "results/benchmarks/figure_time_history.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    params:
        campaign=str(CAMPAIGN),
        configuration=CONFIGURATIONS[0],
        decay=asdict(SETTINGS.analysis.decay()),
    script:
        "../scripts/figure_time_history.py"


rule figures_damping:
    # Figures 10-13 of every configuration in one job: they read the same campaign-wide
    # tables, so a job per figure would only repeat start-up (Python, matplotlib, pandas).
    input:
        segments="results/tables/segments.parquet",
        curves="results/tables/damping_curves.parquet",
        area="results/tables/area_fits.parquet",
        campaign_settings="results/interim/campaign.json",
    output:
        damping=[
            report(
                path,
                caption="../report/fig_damping.rst",
                category="2 Measured data",
                subcategory="2.2 Damping vs amplitude (figs. 10-12)",
                labels={"figure": f"fig. {damping_figure_number(name)}: {name}"},
            )
            for name, path in zip(CONFIGURATIONS, damping_figures())
        ],
        area=report(
            "results/figures/fig13_area_fits.png",
            caption="../report/fig13_area_fits.rst",
            category="3 Damping and area fits",
            subcategory="3.1 Damping vs bearing area (fig. 13)",
            labels={"figure": "fig. 13: damping vs bearing area"},
        ),
    log:
        "results/logs/figures_damping.log",
    benchmark:
        "results/benchmarks/figures_damping.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        units=SETTINGS.units,
        configurations=CONFIGURATIONS,
    script:
        "../scripts/figures_damping.py"


rule figures_backbone:
    # The backbones need only the segments: apart from figures_damping, they are drawn
    # while fit_curves runs.
    input:
        segments="results/tables/segments.parquet",
    output:
        backbones=[
            report(
                path,
                caption="../report/backbone.rst",
                category="2 Measured data",
                subcategory="2.3 Backbones (frequency vs amplitude)",
                labels={"figure": f"backbone: {name}"},
            )
            for name, path in zip(CONFIGURATIONS, backbone_figures())
        ],
    log:
        "results/logs/figures_backbone.log",
    benchmark:
        "results/benchmarks/figures_backbone.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        units=SETTINGS.units,
        configurations=CONFIGURATIONS,
    script:
        "../scripts/figures_backbone.py"
