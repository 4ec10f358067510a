"""The real ``snakemake`` on a campaign whose runs are Test.Lab MAT, UFF58 (ASCII and binary),
TDMS and ASCII files: the same tables as the same samples in ASCII, and a damaged file
excluded with its reason while the others complete."""

import functools

import pandas as pd
from helpers import checksums, run_snakemake
from system_format_files import write_mixed_format_copy

from workflow.lab.virtual_lab import generate_campaign

snakemake = functools.partial(run_snakemake, timeout=900)


def test_mixed_format_campaign_gives_the_tables_of_its_ascii_copy(tmp_path):
    ascii_campaign = tmp_path / "ascii"
    generate_campaign(ascii_campaign, seed=7, runs_per_configuration=5, configurations={"no_washer": 1.36})
    mixed_campaign = tmp_path / "mixed"
    formats = write_mixed_format_copy(ascii_campaign, mixed_campaign)
    assert sorted(formats.values()) == ["ascii", "mat", "tdms", "uff", "uff58b"]
    # a cut-off copy of the UFF run: excluded with file, line and problem
    uff = (mixed_campaign / "no_washer" / "run03.uff").read_bytes()
    (mixed_campaign / "no_washer" / "run06.uff").write_bytes(uff[: len(uff) // 2])
    before = checksums(mixed_campaign)

    tables = {}
    for name, campaign in (("ascii", ascii_campaign), ("mixed", mixed_campaign)):
        workdir = tmp_path / f"work_{name}"
        workdir.mkdir()
        result = snakemake(workdir, "-c2", "measured", "--config", f"campaign={campaign}")
        assert result.returncode == 0, result.stderr[-4000:]
        tables[name] = {
            table: pd.read_parquet(workdir / f"results/tables/{table}.parquet")
            for table in ("segments", "runs", "quality", "modes")
        }

    runs = tables["mixed"]["runs"].set_index("run")
    assert runs.loc["run06", "status"] == "excluded"
    assert "no_washer/run06.uff:" in runs.loc["run06", "reason"]
    assert "truncated" in runs.loc["run06", "reason"]
    assert (runs.drop(index="run06")["status"] == "used").all()
    assert runs.loc["run02", "path"] == "no_washer/run02.mat"

    for table in ("segments", "modes"):
        pd.testing.assert_frame_equal(tables["mixed"][table], tables["ascii"][table])
    quality_mixed = tables["mixed"]["quality"]
    quality_mixed = quality_mixed[quality_mixed["run"] != "run06"].reset_index(drop=True)
    pd.testing.assert_frame_equal(quality_mixed, tables["ascii"]["quality"].reset_index(drop=True))
    assert checksums(mixed_campaign) == before
