"""lapjoint from Python: one record's damping and frequency table, and a campaign's results
as objects.

* :func:`ring_down_table`: one ring-down record as arrays in, its damping and frequency
  against velocity amplitude out (the rows ``results/tables/segments.parquet`` holds for a
  run), by the same functions the workflow runs.
* :func:`run_campaign`: the whole workflow (``snakemake all``) on a campaign folder.
* :func:`load_results`: a finished run's tables and diagnosis as a :class:`CampaignResults`.

Examples
--------
A free decay at 125 Hz with 0.5 % of critical damping, recorded in g at 2 kHz:

>>> import numpy as np
>>> from workflow.api import ring_down_table
>>> fs_hz, f_hz, zeta = 2000.0, 125.0, 0.005
>>> t_s = np.arange(int(4 * fs_hz)) / fs_hz
>>> decay = np.exp(-zeta * 2 * np.pi * f_hz * t_s) * np.sin(2 * np.pi * f_hz * t_s)
>>> noise = 1e-6 * np.random.default_rng(0).standard_normal(t_s.size)
>>> table = ring_down_table(2.0 * decay + noise, fs_hz, quantity="acceleration", unit="g")
>>> round(float(table["zeta"].median()), 4), round(float(table["frequency_hz"].median()), 1)
(0.005, 125.0)
>>> list(table.columns[:4])
['t_s', 'response_amplitude', 'velocity_amplitude_in_s', 'velocity_amplitude_m_s']
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from workflow.io.records import RunRecord
from workflow.io.tables import read_table, with_si_columns
from workflow.io.units import normalize_unit
from workflow.measured.mode_identification import identify_mode
from workflow.measured.runs import analyse_run_with_quality
from workflow.measured.settings import AnalysisSettings, QualitySettings

__all__ = ["ring_down_table", "CampaignResults", "load_results", "run_campaign"]

SNAKEFILE = Path(__file__).resolve().parents[1] / "Snakefile"
"""The workflow this package belongs to."""


def ring_down_table(
    response: ArrayLike,
    sample_rate_hz: float,
    *,
    quantity: str = "acceleration",
    unit: str = "g",
    force_lbf: ArrayLike | None = None,
    mode_hz: float | None = None,
    band_hz: tuple[float, float] | None = None,
    analysis: AnalysisSettings | None = None,
    quality: QualitySettings | None = None,
    kept_only: bool = True,
) -> pd.DataFrame:
    """Damping and frequency against velocity amplitude of one ring-down record.

    The mode is found as the workflow finds a configuration's (H1 with the force, the
    response spectrum without; near ``mode_hz`` when given), the record is band-passed
    around it, and its envelope is cut into segments whose log decrement gives the local
    damping and frequency (docs/decay_analysis.md).

    Parameters
    ----------
    response : array_like
        The response over the whole record (pre-trigger included), in ``unit``.
    sample_rate_hz : float
        Samples per second.
    quantity, unit : str
        What the response is (acceleration, velocity or displacement) and its unit (g,
        m/s^2, in/s^2, mm/s^2, m/s, in/s, mm/s, m, in, mm, um).
    force_lbf : array_like, optional
        The hammer force in lbf, same length: the mode is then found from the H1
        frequency response.
    mode_hz : float, optional
        The mode's frequency if known, Hz (it is searched within
        ``analysis.mode_search_fraction`` of it).
    band_hz : (float, float), optional
        Band-pass edges, Hz; default ``mode * (1 -/+ analysis.band_half_width)``.
    analysis, quality : settings, optional
        config.yaml's ``analysis`` and ``quality`` sections (default: their defaults).
    kept_only : bool
        Only the segments the quality rules keep (default), or every segment with
        ``kept`` and ``reject_reason``.

    Returns
    -------
    DataFrame
        One row per segment: ``t_s`` (s from the record's start), ``response_amplitude``
        (``unit``), ``velocity_amplitude_in_s`` and ``velocity_amplitude_m_s``,
        ``frequency_hz``, ``zeta`` (fraction of critical), ``fit_rms``, ``kept``,
        ``reject_reason``. Attributes ``mode_hz`` and ``band_hz`` in ``table.attrs``.

    Raises
    ------
    ValueError
        No resonance in the search range, a band reaching the Nyquist frequency, an
        unknown unit, or a response that is not a finite 1-D array.
    """
    analysis = analysis or AnalysisSettings()
    quality = quality or QualitySettings()
    values = np.asarray(response, dtype=float)
    if values.ndim != 1 or not np.all(np.isfinite(values)):
        raise ValueError(f"response must be a finite 1-D array, got shape {values.shape}")
    force = None if force_lbf is None else np.asarray(force_lbf, dtype=float)
    if force is not None and force.shape != values.shape:
        raise ValueError(f"force_lbf has shape {force.shape}, the response {values.shape}")
    record = RunRecord(
        path="<array>",
        sample_rate_hz=float(sample_rate_hz),
        pretrigger_samples=0,
        time_s=None,
        force_lbf=force,
        response=values,
        response_quantity=quantity,
        response_unit=normalize_unit(unit),
        header={},
        n_samples=values.size,
    )
    window = (0, values.size)
    mode = identify_mode(
        [record],
        windows=[window],
        campaign_mode_hz=mode_hz,
        campaign_band_hz=band_hz,
        band_half_width=analysis.band_half_width,
        mode_search_hz=analysis.mode_search_hz,
        mode_search_fraction=analysis.mode_search_fraction,
        min_mode_prominence=quality.min_mode_prominence,
    )
    columns, _ = analyse_run_with_quality(
        record,
        configuration="",
        run="",
        mode=mode,
        window=window,
        decay_settings=analysis,
        quality_settings=quality,
    )
    table = pd.DataFrame(columns).drop(columns=["configuration", "run", "response_quantity"])
    if kept_only:
        table = table[table["kept"]].reset_index(drop=True)
    table = with_si_columns(table)
    table.attrs.update(mode_hz=mode.mode_hz, band_hz=mode.band_hz)
    return table


@dataclass
class CampaignResults:
    """A finished run's results (``results/`` of its working directory).

    Attributes
    ----------
    folder : Path
        The ``results`` folder.
    diagnosis : dict
        ``results/diagnosis.json`` (output contract): ``cause``, ``confidence``,
        ``configurations`` (each with its cause, discrepancy sentence, baseline and
        extended model, gain and evidence).
    tables : dict of DataFrame
        Every ``results/tables/*.parquet`` by its name (``segments``, ``runs``,
        ``damping_fits``, ``damping_curves``, ``hypotheses``, ``model_fits``, ...);
        units in docs/outputs.md.
    """

    folder: Path
    diagnosis: dict = field(repr=False)
    tables: dict[str, pd.DataFrame] = field(repr=False)

    @property
    def cause(self) -> str:
        """The campaign's cause (``none``, ``microslip_power_law``, ... ``unknown``)."""
        return self.diagnosis.get("cause", "unknown")

    @property
    def causes(self) -> dict[str, str]:
        """Configuration -> its cause."""
        return {name: entry.get("cause") for name, entry in self.diagnosis.get("configurations", {}).items()}

    @property
    def segments(self) -> pd.DataFrame:
        """Every kept segment: damping and frequency against velocity amplitude."""
        return self.tables["segments"]

    @property
    def runs(self) -> pd.DataFrame:
        """Every run file: used or excluded, and why."""
        return self.tables["runs"]

    def discrepancy(self, configuration: str) -> str:
        """What the paper's model gets wrong in ``configuration``, in one sentence."""
        return self.diagnosis["configurations"][configuration]["discrepancy"]


def load_results(workdir: Path | str = ".") -> CampaignResults:
    """The results of a finished run in ``workdir`` (the folder snakemake ran in, ``-d``).

    Raises
    ------
    FileNotFoundError
        When ``workdir/results/diagnosis.json`` is missing (the run has not finished),
        naming the file and the command that makes it.
    """
    folder = Path(workdir) / "results"
    diagnosis_path = folder / "diagnosis.json"
    if not diagnosis_path.is_file():
        raise FileNotFoundError(
            f"{diagnosis_path} not found: run the workflow first (snakemake -c2 all -d {workdir}, "
            "or workflow.api.run_campaign)"
        )
    tables = {path.stem: read_table(path) for path in sorted((folder / "tables").glob("*.parquet"))}
    return CampaignResults(folder, json.loads(diagnosis_path.read_text()), tables)


def run_campaign(
    campaign: Path | str,
    workdir: Path | str,
    *,
    cores: int = 2,
    config: Mapping[str, str] | None = None,
) -> CampaignResults:
    """Run the whole workflow (``snakemake all``) on ``campaign`` in ``workdir``, then
    :func:`load_results`.

    Parameters
    ----------
    campaign : path
        The campaign folder (campaign.yaml and its run files, /work/shared/campaign-format.md).
    workdir : path
        Where ``results/`` is written (created if missing); a second call re-runs only
        what changed.
    cores : int
        Cores Snakemake may use.
    config : mapping, optional
        Further ``--config`` entries, key to value as on the command line
        (``{"units": "si", "fits": "{bootstrap_samples: 50}"}``).

    Raises
    ------
    RuntimeError
        When Snakemake fails, with the end of its log.
    """
    Path(workdir).mkdir(parents=True, exist_ok=True)
    entries = [f"campaign={Path(campaign).resolve()}", *(f"{k}={v}" for k, v in (config or {}).items())]
    command = [
        sys.executable,
        "-m",
        "snakemake",
        "-s",
        str(SNAKEFILE),
        "-d",
        str(workdir),
        f"-c{cores}",
        "all",
        "--config",
        *entries,
    ]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"snakemake failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return load_results(workdir)
