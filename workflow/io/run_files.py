"""A campaign's run files: finding them (each configuration's glob, what is excluded and
why) and reading one (:func:`read_run`, by its extension: the ASCII reader of
:mod:`workflow.io.readers.ascii` or a system format's, :mod:`workflow.io.readers`).

Run files are matched by the configuration's glob; names starting with ``.`` (e.g.
macOS ``._run01.txt`` companions), and files in folders whose names start with ``.``
(``.ipynb_checkpoints/``) unless the glob names such a folder, are skipped, as a shell
glob would. Runs are sorted by plain (lexical) run name, the file name without its
extension, which is the name every table and the run order use.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from workflow.io.campaign import CAMPAIGN_FILE, Campaign, frequency_problem
from workflow.io.limits import name_length_problem, quoted, shortened
from workflow.io.path_checks import unreadable_reason
from workflow.io.readers.ascii import read_ascii_run
from workflow.io.records import CampaignFormatError, RunFile, RunRecord

__all__ = [
    "SYSTEM_FORMAT_EXTENSIONS",
    "ExcludedPath",
    "scan_campaign",
    "list_runs",
    "read_run",
]


SYSTEM_FORMAT_EXTENSIONS: frozenset[str] = frozenset({".mat", ".uff", ".unv", ".tdms"})
"""Run-file extensions read by the acquisition-system readers (workflow/io/readers);
every other extension is read as ASCII."""


# --------------------------------------------------------------------------------------
# Run discovery


@dataclass(frozen=True)
class ExcludedPath:
    """A path a configuration's glob leads to that is not read, or a glob that matches
    nothing: a row of runs.parquet with status ``excluded`` and the reason."""

    configuration: str
    run: str
    """File name without extension (empty for a glob that matches nothing)."""
    path: str
    """Path relative to the campaign folder, or the glob that matched nothing."""
    reason: str

    def status(self) -> dict[str, str]:
        """The runs-table row (the keys of the analysis jobs' status documents)."""
        return {**asdict(self), "status": "excluded"}


def scan_campaign(campaign_dir: str | Path, campaign: Campaign) -> tuple[list[RunFile], list[ExcludedPath]]:
    """The run files of every configuration, and what its glob leads to that is not read.

    Only regular, readable files whose real path (symbolic links followed) lies inside
    the campaign folder are run files. Directories, links leading outside, other
    special files and unreadable files are excluded with their reason; a glob that
    matches nothing gives one excluded entry that names ``configurations.<name>.files``.
    Names starting with ``.``, and folders starting with ``.`` that the glob does not
    name, are skipped, as a shell glob would.

    Parameters
    ----------
    campaign_dir : str or Path
        The campaign folder.
    campaign : Campaign
        Its validated campaign.yaml.

    Returns
    -------
    runs : list of RunFile
        Configurations in campaign.yaml order, runs sorted by run name (the file name
        without its extension: the file-name run order).
    excluded : list of ExcludedPath
        Everything else the globs lead to, in the same order.

    Raises
    ------
    CampaignFormatError
        Two runs of one configuration with the same name (their rows would collide), or
        a glob that pathlib cannot use.
    """
    root = Path(campaign_dir)
    root_resolved = root.resolve()
    runs: list[RunFile] = []
    excluded: list[ExcludedPath] = []
    for configuration, spec in campaign.configurations.items():
        # a shell's * leaves out dot-names; pathlib's does not
        names_dot_folder = any(part.startswith(".") for part in Path(spec.files).parts[:-1])
        try:
            matches = sorted(
                (
                    p
                    for p in root.glob(spec.files)
                    if not p.name.startswith(".")
                    and (
                        names_dot_folder
                        or not any(part.startswith(".") for part in p.relative_to(root).parts)
                    )
                ),
                key=lambda p: (p.stem, p.as_posix()),
            )
        except (ValueError, NotImplementedError, IndexError) as error:
            raise CampaignFormatError(
                root / CAMPAIGN_FILE,
                None,
                f"configurations.{configuration}.files: {quoted(spec.files)} is not a usable glob ({error})",
            ) from None
        if not matches:
            excluded.append(
                ExcludedPath(
                    configuration,
                    "",
                    spec.files,
                    f"configurations.{configuration}.files: the glob {quoted(spec.files)} matches no "
                    f"file in the campaign folder {root.as_posix()}",
                )
            )
        seen: dict[str, str] = {}
        for match in matches:
            relative = match.relative_to(root).as_posix()
            reason = unreadable_reason(match, root_resolved)
            long_name = name_length_problem("run file name", match.name)
            if long_name is not None:
                # the name itself is not repeated in full anywhere
                shown = shortened(relative)
                excluded.append(
                    ExcludedPath(
                        configuration, shortened(match.stem), shown, f"{shown}: not read: {long_name}"
                    )
                )
                continue
            if reason is not None:
                excluded.append(
                    ExcludedPath(
                        configuration, match.stem, relative, f"{root.as_posix()}/{relative}: {reason}"
                    )
                )
                continue
            if match.stem in seen:
                raise CampaignFormatError(
                    root / CAMPAIGN_FILE,
                    None,
                    f"configurations.{configuration}.files matches two runs named "
                    f"{quoted(match.stem)}: {seen[match.stem]} and {relative}",
                )
            seen[match.stem] = relative
            runs.append(RunFile(configuration, match.stem, relative))
    return runs, excluded


def list_runs(campaign_dir: str | Path, campaign: Campaign) -> list[RunFile]:
    """The run files of :func:`scan_campaign` (regular, readable files inside the campaign
    folder), configurations in campaign.yaml order, runs sorted by run name."""
    return scan_campaign(campaign_dir, campaign)[0]


def _checked_against_band(record: RunRecord, campaign: Campaign, shown: str) -> RunRecord:
    """A system-format record whose own sample rate cannot hold campaign.yaml's band and
    mode is refused, as an ASCII one is."""
    problem = frequency_problem(campaign, record.sample_rate_hz, f"the file's {record.sample_rate_source}")
    if problem is not None:
        raise CampaignFormatError(shown, None, f"campaign.yaml {problem}")
    return record


def read_run(
    campaign_dir: str | Path, run_file_or_path: RunFile | str | Path, campaign: Campaign
) -> RunRecord:
    """Read one run file and check it against the input contract.

    Parameters
    ----------
    campaign_dir : str or Path
        The campaign folder.
    run_file_or_path : RunFile, str or Path
        The run, or its path (relative to ``campaign_dir``, or absolute).
    campaign : Campaign
        The campaign's validated campaign.yaml.

    Returns
    -------
    RunRecord
        Response in the campaign's unit, force in lbf, time in s.

    Raises
    ------
    CampaignFormatError
        Any malformed input; the message names the file (as
        ``campaign_dir/relative path``), the line and the problem.
    """
    root = Path(campaign_dir)
    given = Path(run_file_or_path.path if isinstance(run_file_or_path, RunFile) else run_file_or_path)
    full = given if given.is_absolute() else root / given
    try:
        relative = full.relative_to(root).as_posix()
    except ValueError:
        relative = full.as_posix()
    shown = full.as_posix()
    if not full.exists():
        raise CampaignFormatError(shown, None, "no such file")
    reason = unreadable_reason(full, root.resolve())
    if reason is not None:
        raise CampaignFormatError(shown, None, reason)
    if full.suffix.lower() in SYSTEM_FORMAT_EXTENSIONS:
        from workflow.io.readers import read_system_run

        return _checked_against_band(read_system_run(full, relative, shown, campaign), campaign, shown)
    return read_ascii_run(full, relative, shown, campaign)
