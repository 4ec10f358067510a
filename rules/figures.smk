# Figures of the measured-data chain (paper figures 9-13 and the backbones).


rule figures_measured:
    # Every figure of the measured data in one job: figure 9 (the first used run of the
    # first configuration), figures 10-13 and the backbones of every configuration. A job
    # per figure, or per group of them, spent more of its time starting (Python,
    # matplotlib, pandas) than drawing.
    input:
        segments="results/tables/segments.parquet",
        curves="results/tables/damping_curves.parquet",
        area="results/tables/area_fits.parquet",
        runs_table="results/tables/runs.parquet",
        modes="results/tables/modes.parquet",
        campaign_settings="results/interim/campaign.json",
        campaign_yaml=campaign_yaml,
    output:
        time_history=report(
            "results/figures/fig09_time_history.png",
            caption="../report/fig09_time_history.rst",
            category="2 Measured data",
            subcategory="2.1 Time history (fig. 9)",
            labels={"figure": "fig. 9: raw, band-passed, envelope"},
        ),
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
        modes_channels=[
            report(
                path,
                caption="../report/modes_channels.rst",
                category="2 Measured data",
                subcategory="2.4 Every mode and channel",
                labels={"figure": "damping and frequency of every mode and channel"},
            )
            for path in modes_channels_figures()
        ],
    log:
        "results/logs/figures_measured.log",
    benchmark:
        "results/benchmarks/figures_measured.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        units=SETTINGS.units,
        configurations=CONFIGURATIONS,
        analysis=asdict(SETTINGS.analysis),
        channels=list(RESPONSE_CHANNELS),
    script:
        "../scripts/figures_measured.py"
