# The paper's models: friction loops (figures 7, 8), the table of Dahl and LuGre fitted to
# each configuration's damping and frequency curves (by diagnose_configuration,
# rules/discovery.smk, from its averaged fits), and their comparison (figures 14, 15).


rule figure_friction_loops:
    output:
        dahl=report(
            "results/figures/fig07_dahl_loops.png",
            caption="../report/fig07_dahl_loops.rst",
            category="4 Friction models",
            subcategory="4.1 The paper's friction laws (figs. 7, 8)",
            labels={"figure": "fig. 7: Dahl loops"},
        ),
        lugre=report(
            "results/figures/fig08_lugre_loops.png",
            caption="../report/fig08_lugre_loops.rst",
            category="4 Friction models",
            subcategory="4.1 The paper's friction laws (figs. 7, 8)",
            labels={"figure": "fig. 8: LuGre loops"},
        ),
    log:
        "results/logs/figure_friction_loops.log",
    benchmark:
        "results/benchmarks/figure_friction_loops.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    params:
        units=SETTINGS.units,
    script:
        "../scripts/figure_friction_loops.py"


rule figures_models:
    # Figures 14 and 15 of every configuration, and the table of the fitted parameters
    # with its report page, in one job: a job per configuration, or for the table,
    # would spend most of its time starting (Python, matplotlib, pandas).
    input:
        segments="results/tables/segments.parquet",
        fits=expand("results/models/{configuration}.json", configuration=CONFIGURATIONS),
    output:
        table="results/tables/model_fits.parquet",
        page=report(
            "results/report/model_fits.html",
            caption="../report/model_fits.rst",
            category="4 Friction models",
            subcategory="4.3 Fitted parameters",
            labels={"table": "Dahl and LuGre parameters"},
        ),
        dahl=[
            report(
                f"results/figures/fig14_dahl_{name}.png",
                caption="../report/fig_models.rst",
                category="4 Friction models",
                subcategory="4.2 Fitted to the data (figs. 14, 15)",
                labels={"configuration": name, "model": "fig. 14: Dahl"},
            )
            for name in CONFIGURATIONS
        ],
        lugre=[
            report(
                f"results/figures/fig15_lugre_{name}.png",
                caption="../report/fig_models.rst",
                category="4 Friction models",
                subcategory="4.2 Fitted to the data (figs. 14, 15)",
                labels={"configuration": name, "model": "fig. 15: LuGre"},
            )
            for name in CONFIGURATIONS
        ],
    log:
        "results/logs/figures_models.log",
    benchmark:
        "results/benchmarks/figures_models.tsv"
    # The longest job that waits for every configuration's fits: ahead of the diagnosis
    # (which has the report after it, about as long together), so that the two chains end
    # together rather than this job alone on one core.
    priority: 2
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
        "../scripts/figures_models.py"
