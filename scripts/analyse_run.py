"""Rule analyse_run: band-pass, envelope and segmented log decrement of one run,
with its quality checks."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow.campaign import read_validated_campaign
from workflow.config import QualitySettings
from workflow.logs import setup_script_logging
from workflow.pipeline import (ModeInfo, analyse_run_with_quality, analysis_window, empty_segments,
                               failed_checks, read_with_quality)
from workflow.quality import quality_columns
from workflow.tables import write_columns, write_json

log = setup_script_logging(snakemake.log[0], "analyse_run")
configuration, run = snakemake.wildcards.configuration, snakemake.wildcards.run
campaign_dir = Path(snakemake.params.campaign)
campaign = read_validated_campaign(snakemake.input.campaign_settings)
run_path = Path(snakemake.input.run).relative_to(campaign_dir).as_posix()
quality_settings = QualitySettings(**snakemake.params.quality)
mode_document = json.loads(Path(snakemake.input.mode).read_text())

segments = empty_segments()
record, rows = read_with_quality(campaign_dir, run_path, campaign, quality_settings)
problems = failed_checks(run_path, rows)
if record is not None and not problems:
    if "error" in mode_document:
        problems = [mode_document["error"]]
    else:
        segments, decay_rows = analyse_run_with_quality(
            record,
            configuration=configuration,
            run=run,
            mode=ModeInfo.from_dict(mode_document),
            window=analysis_window(record, campaign.configurations[configuration].window_s),
            min_snr_db=quality_settings.min_snr_db,
            min_segments=quality_settings.min_segments,
            **snakemake.params.analysis,
        )
        rows += decay_rows
        problems = failed_checks(run_path, decay_rows)

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
    log.info("%s: %d segments kept of %d", run_path, int(segments["kept"].sum()), len(segments["kept"]))
write_columns(snakemake.output.segments, segments)
write_columns(snakemake.output.quality, quality_columns(configuration, run, rows))
write_json(snakemake.output.status, status)
