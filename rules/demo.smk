# The built-in demo: a campaign measured in the virtual lab (workflow/lab/campaigns.py).
# It exists only when config.yaml's campaign points at demo.path.

if USES_DEMO:

    rule demo_campaign:
        output:
            campaign_yaml=CAMPAIGN / "campaign.yaml",
            runs=[CAMPAIGN / run.path for run in RUN_FILES],
            truth=f"{CAMPAIGN}.truth.json",
        log:
            "results/logs/demo_campaign.log",
        benchmark:
            "results/benchmarks/demo_campaign.tsv"
        conda:
            LAPJOINT_ENV
        threads: 1
        resources:
            mem_mb=1000,
            runtime=10,
        params:
            seed=SETTINGS.demo.seed,
            runs_per_configuration=SETTINGS.demo.runs_per_configuration,
            frequency_spread=SETTINGS.demo.frequency_spread,
            damping_spread=SETTINGS.demo.damping_spread,
            slip_force_spread=SETTINGS.demo.slip_force_spread,
        script:
            "../scripts/make_demo_campaign.py"
