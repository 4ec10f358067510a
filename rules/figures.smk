# Figures of the measured-data chain (paper figures 9-13 and the backbones).


rule figure_time_history:
    input:
        runs_table="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_yaml=CAMPAIGN / "campaign.yaml",
    output:
        report(
            "results/figures/fig09_time_history.png",
            caption="../report/fig09_time_history.rst",
            category="2 Measured data",
            subcategory="2.1 Time history (fig. 9)",
            labels={"figure": "fig. 9: raw, band-passed, envelope"},
        ),
    params:
        campaign=str(CAMPAIGN),
        configuration=CONFIGURATIONS[0],
        filter_order=SETTINGS.analysis.filter_order,
        analysis=SETTINGS.analysis.run_parameters(),
    log:
        "results/logs/figure_time_history.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/figure_time_history.py"


rule figure_damping:
    input:
        segments="results/tables/segments.parquet",
        curves="results/tables/damping_curves.parquet",
    output:
        damping=report(
            "results/figures/fig{number}_damping_{configuration}.png",
            caption="../report/fig_damping.rst",
            category="2 Measured data",
            subcategory="2.2 Damping vs amplitude (figs. 10-12)",
            labels={"figure": "fig. {number}: {configuration}"},
        ),
    log:
        "results/logs/figure_damping/fig{number}_{configuration}.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/figure_damping.py"


rule figure_backbone:
    input:
        segments="results/tables/segments.parquet",
    output:
        report(
            "results/figures/backbone_{configuration}.png",
            caption="../report/backbone.rst",
            category="2 Measured data",
            subcategory="2.3 Backbones (frequency vs amplitude)",
            labels={"figure": "backbone: {configuration}"},
        ),
    log:
        "results/logs/figure_backbone/{configuration}.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/figure_backbone.py"


rule figure_area_fits:
    input:
        curves="results/tables/damping_curves.parquet",
        area="results/tables/area_fits.parquet",
    output:
        report(
            "results/figures/fig13_area_fits.png",
            caption="../report/fig13_area_fits.rst",
            category="3 Damping and area fits",
            subcategory="3.1 Damping vs bearing area (fig. 13)",
            labels={"figure": "fig. 13: damping vs bearing area"},
        ),
    params:
        campaign=str(CAMPAIGN),
    log:
        "results/logs/figure_area_fits.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/figure_area_fits.py"
