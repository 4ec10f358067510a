# The report: the verdict page and readable tables (results/report/*.html), marked with
# the figures for `snakemake --report results/report.html` (captions in report/).
#
# The report's first page (its workflow description) is report/workflow.rst; once
# report_summary has written results/report/landing.rst (the verdict in a few lines,
# then report/workflow.rst), that file is the first page instead, so the reader opens
# the report on the verdict.

if LANDING_PAGE.exists():
    workflow.report(str(LANDING_PAGE.resolve()))
else:

    report: "../report/workflow.rst"


rule report_summary:
    # The report's pages, then results/summary.txt (the Snakefile's onsuccess prints it
    # once every job of `all` has ended). One job for both: the summary alone was a job of
    # start-up. It reads tables and the diagnosis only, so it runs beside the figures.
    input:
        diagnosis="results/diagnosis.json",
        runs="results/tables/runs.parquet",
        segments="results/tables/segments.parquet",
        rejected="results/tables/segments_rejected.parquet",
        quality="results/tables/quality.parquet",
        hypotheses="results/tables/hypotheses.parquet",
        damping_fits="results/tables/damping_fits.parquet",
        description=workflow.source_path("../report/workflow.rst"),
    output:
        summary="results/summary.txt",
        landing=str(LANDING_PAGE),
        verdict=report(
            "results/report/verdict.html",
            caption="../report/verdict.rst",
            category="1 Verdict",
            labels={"page": "verdict: what the paper's model gets wrong and why"},
        ),
        hypotheses=report(
            "results/report/hypotheses.html",
            caption="../report/hypotheses.rst",
            category="3 Damping and area fits",
            subcategory="3.2 Tables",
            labels={"table": "hypotheses H1, H2"},
        ),
        runs=report(
            "results/report/runs.html",
            caption="../report/runs.rst",
            category="6 Quality",
            labels={"table": "runs: used or excluded, with the reason"},
        ),
        quality=report(
            "results/report/quality.html",
            caption="../report/quality.rst",
            category="6 Quality",
            labels={"table": "quality checks of every run (values and limits)"},
        ),
        rejected=report(
            "results/report/rejected_segments.html",
            caption="../report/rejected_segments.rst",
            category="6 Quality",
            labels={"table": "segments dropped, by rule"},
        ),
        damping_fits=report(
            "results/report/damping_fits.html",
            caption="../report/damping_fits.rst",
            category="3 Damping and area fits",
            subcategory="3.2 Tables",
            labels={"table": "polynomial damping fits"},
        ),
        candidates=report(
            "results/report/diagnosis_candidates.html",
            caption="../report/diagnosis_candidates.rst",
            category="5 Diagnosis",
            subcategory="5.2 Candidates and held-out prediction",
            labels={"item": "table: every candidate model, held-out errors"},
        ),
    log:
        "results/logs/report_summary.log",
    benchmark:
        "results/benchmarks/report_summary.tsv"
    conda:
        LAPJOINT_ENV
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    params:
        units=SETTINGS.units,
        channels=list(RESPONSE_CHANNELS),
    script:
        "../scripts/report_summary.py"
