# Figures of the measured-data chain (paper figures 9-13 and the backbones).


rule figure_time_history:
    input:
        runs_table="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_yaml=CAMPAIGN / "campaign.yaml",
    output:
        "results/figures/fig09_time_history.png",
    params:
        campaign=str(CAMPAIGN),
        configuration=CONFIGURATIONS[0],
        filter_order=SETTINGS.analysis.filter_order,
        analysis=SETTINGS.analysis.model_dump(exclude={"band_half_width", "mode_search_hz", "mode_search_fraction"}),
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
        damping="results/figures/fig{number}_damping_{configuration}.png",
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
        "results/figures/backbone_{configuration}.png",
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
        "results/figures/fig13_area_fits.png",
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
