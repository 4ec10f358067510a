"""Rule analyse_run: band-pass, envelope and segmented log decrement of one run."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow.campaign import load_campaign
from workflow.config import QualitySettings
from workflow.logs import setup_script_logging
from workflow.pipeline import ModeInfo, analyse_run, analysis_window, empty_segments, read_and_check
from workflow.tables import write_json, write_table

log = setup_script_logging(snakemake.log[0], "analyse_run")
configuration, run = snakemake.wildcards.configuration, snakemake.wildcards.run
campaign_dir = Path(snakemake.params.campaign)
campaign = load_campaign(campaign_dir)
run_path = Path(snakemake.input.run).relative_to(campaign_dir).as_posix()
quality_settings = QualitySettings(**snakemake.params.quality)
analysis = snakemake.params.analysis
mode_document = json.loads(Path(snakemake.input.mode).read_text())

segments = empty_segments()
record, problems = read_and_check(campaign_dir, run_path, campaign, quality_settings)
if record is not None and not problems:
    if "error" in mode_document:
        problems = [mode_document["error"]]
    else:
        segments, decay_problems = analyse_run(
            record,
            configuration=configuration,
            run=run,
            mode=ModeInfo.from_dict(mode_document),
            window=analysis_window(record, campaign.configurations[configuration].window_s),
            min_snr_db=quality_settings.min_snr_db,
            min_segments=quality_settings.min_segments,
            **analysis,
        )
        problems = [f"{run_path}: {problem}" for problem in decay_problems]

status = {
    "configuration": configuration,
    "run": run,
    "path": run_path,
    "status": "excluded" if problems else "used",
    "reason": "; ".join(problems),
}
if problems:
    log.warning("excluded %s", status["reason"])
    if snakemake.params.strict:
        raise SystemExit(f"strict mode: run excluded: {status['reason']}")
else:
    log.info("%s: %d segments kept of %d", run_path, int(segments["kept"].sum()), len(segments))
write_table(segments, snakemake.output.segments, units={"response_amplitude": record.response_unit if record else ""})
write_json(snakemake.output.status, status)
