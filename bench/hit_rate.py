# ruff: noqa: E402 (the thread settings precede the imports of NumPy)
"""Hit rate and calibration of the model discovery over hidden-effect campaigns and seeds.

For every case of the vocabulary (the six causes and the two combinations: micro-slip
with a velocity-squared loss, micro-slip with a hardening cubic spring), ``--seeds``
campaigns from the virtual lab (effect size and bearing area drawn per seed, see
workflow/lab/hidden_effects.py) go through the measured-data chain and the diagnosis; the
script prints the confusion table (rows: hidden cause, columns: verdict, as rates), the
hit rate per cause (right: the verdict's set of causes is the truth's; also how often its
first cause is one of the truth's), the gain ratios, a reliability table (each verdict's
confidence, binned, against the fraction of those verdicts that were right) with the
Brier score, and the runtime per campaign. Runs differ from run to run as in a real lab
(the lab's default ``LabSettings``); ``--no-variability`` makes every run of a campaign
the same beam, ``--time-domain`` integrates every joint in time instead of the averaged
model (the causes it can hide: none, microslip_power_law, run_drift, unknown and the two
combinations, which are always integrated in time), and ``--random-placement`` records
each campaign with a sensor placed at random on the beam (mode 1 at x0.05 to x8 of the
reference accelerometer against the same noise floor, log-uniform; the other modes at
their own shape values there). ``--runs 1 --sensors 3`` makes each campaign one hit
recorded by three sensors (placed at random with ``--random-placement``): the verdict is
the joint analysis of every sensor, and each sensor's own verdict is checked against the
others and the joint one (how often two are 0.7 sure of different verdicts).

    .venv/bin/python bench/hit_rate.py --seeds 10 --jobs 2

``--keep DIR`` stores what each campaign's decision was taken on (the data, every model's
residuals and held-out residuals; with several sensors each sensor's own under
``DIR/channels/<channel>``); ``--redecide DIR`` takes those decisions and their
confidence again with today's decision rule in seconds, without refitting: the fits do not
depend on the rule.
"""

from __future__ import annotations

import os

# One BLAS thread, as every Snakemake job of the workflow has (its `threads: 1`): the fits'
# linear algebra then rounds as the workflow's does, and a campaign's verdict is the
# workflow's seed by seed. Set before NumPy is imported; the worker processes inherit it.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse
import pickle
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from workflow.discovery.campaign import campaign_document, diagnose_configurations
from workflow.discovery.confidence import verdict_causes as verdict_causes_of
from workflow.discovery.confidence import verdict_key
from workflow.discovery.configuration import conclude
from workflow.discovery.decision import CLEAR_GAIN, extended_model_of
from workflow.discovery.joint import joint_segments
from workflow.discovery.misfit import EXPLAINS_LIMIT, envelope_structure
from workflow.lab.hidden_effects import (
    CASES,
    RUNS,
    campaign_segments,
    case_causes,
    draw_mode1_gain,
    draw_mode1_gains,
    generate_case,
    time_domain_can_hide,
)
from workflow.lab.settings import LabSettings

VERDICTS = [
    "none",
    "microslip_power_law",
    "quadratic_damping",
    "stiffness_nonlinearity",
    "run_drift",
    "unknown",
]


def lab_settings(variability: bool) -> LabSettings:
    """The lab's default settings, or the same without run-to-run variability."""
    if variability:
        return LabSettings()
    return LabSettings(frequency_spread=0.0, damping_spread=0.0, slip_force_spread=0.0)


def verdict_causes(configuration: dict) -> list[str]:
    """The configuration's causes: ``causes`` (the output contract), else its one ``cause``."""
    return list(configuration.get("causes") or [configuration["cause"]])


def verdict_confidence(configuration: dict) -> float | None:
    """The confidence of the configuration's verdict (``confidence`` holds one entry per
    verdict, a combination's keyed by :func:`verdict_key`); 0 when the verdict has none."""
    shares = configuration.get("confidence") or {}
    return float(shares.get(verdict_key(verdict_causes(configuration)), 0.0)) if shares else None


def channel_verdicts(
    segments, keep: Path | None = None, case: dict | None = None
) -> dict[str, tuple[str, float]]:
    """Each sensor's own verdict of a several-sensor campaign's configuration: channel ->
    (verdict key, its confidence), the workflow's ``channels`` consistency check. With
    ``keep`` (a path ``DIR/<cause>_<seed>.pkl``), each sensor's decision evidence is stored
    as ``DIR/channels/<channel>/<cause>_<seed>.pkl``, for ``--redecide``."""
    verdicts = {}
    for channel, rows in segments.groupby(segments["channel"].astype(str)):
        context, details, skipped = diagnose_configurations(rows)
        conf = next(iter(campaign_document("c", context, details, skipped)["configurations"].values()), None)
        if conf:
            key = verdict_key(verdict_causes(conf))
            verdicts[channel] = (key, float(conf["confidence"].get(key, 0.0)))
        if keep is not None and details:
            keep_evidence(
                keep.parent / "channels" / channel / keep.name, case or {}, next(iter(details.values()))
            )
    return verdicts


def _one(args):
    cause, seed, work, variability, integrator, placement, keep, runs, sensors = args
    start, start_cpu = time.perf_counter(), time.process_time()
    record = {
        "cause": cause,
        "seed": seed,
        "verdict": None,
        "causes": [],
        "confidence": None,
        "ratio": None,
        "extended_error": None,
    }
    try:
        if sensors > 1:
            gain = draw_mode1_gains(cause, seed, sensors) if placement else (1.0,) * sensors
        else:
            gain = draw_mode1_gain(cause, seed) if placement else 1.0
        case, out = generate_case(
            cause,
            seed,
            Path(work),
            settings=lab_settings(variability),
            integrator=integrator,
            mode1_gain=gain,
            runs=runs,
        )
        generated = time.perf_counter()
        segments = campaign_segments(out)
        reference = 0
        if sensors > 1:
            record["channels"] = channel_verdicts(
                segments, Path(keep) / f"{cause}_{seed}.pkl" if keep else None, case
            )
            segments, joint = joint_segments(segments)
            names = [s["name"] for s in case["sensors"]]
            reference = names.index(next(iter(joint.values()))["reference_channel"]) if joint else 0
        context, details, skipped = diagnose_configurations(segments)
        doc = campaign_document(out.name, context, details, skipped)
        conf = next(iter(doc["configurations"].values()), None)
        record["verdict"] = doc["cause"] if conf else "no data"
        if conf:  # the hidden cause's own candidate, whatever the verdict
            record.update(
                causes=verdict_causes(conf),
                confidence=verdict_confidence(conf),
                ratio=conf["gain"]["ratio"],
                extended_error=conf["gain"]["extended"],
            )
            own = conf["evidence"]["candidates"].get(case_causes(cause)[-1], {}).get("ratio_to_baseline")
            case = {
                **case,
                "true_candidate_ratio": own,
                "baseline_misfit": conf["evidence"]["baseline_misfit_significant"],
                "explains_data": conf["explains_data"],
                "extended_model": conf["extended_model"]["model"],
            }
            v = segments["velocity_amplitude_in_s"].to_numpy(float)
            v = v[np.isfinite(v) & (v > 0)]
            scatter = conf["evidence"]["scatter"]
            # the truth is against the reference accelerometer's velocity amplitude; with
            # several sensors the amplitudes are on the joint analysis's reference channel
            ratio = case["sensors"][reference]["mode1_ratio"]
            measured = (
                case,
                (float(v.min()) / ratio, float(v.max()) / ratio),
                scatter["ln_zeta_median"],
                scatter["relative_frequency_median"],
            )
            if len(case_causes(cause)) > 1:
                case["truth_added_term"] = round(added_term_on_truth(*measured), 1)
            elif case["integrator"] == "averaged" and (cause in TRUTH_CAUSES or cause == "run_drift"):
                if cause == "run_drift":
                    case["truth_drift_change"] = round(drift_change_on_truth(*measured), 2)
                else:
                    _, worst_zeta, worst_f = baseline_misfit_on_truth(*measured)
                    case["truth_baseline_misfit"] = round(max(worst_zeta, worst_f), 2)
        if keep and details:
            keep_evidence(Path(keep) / f"{cause}_{seed}.pkl", case, next(iter(details.values())))
        record["generate_s"] = generated - start
    except Exception as error:  # report, do not hide
        case = {}
        record["verdict"] = f"error: {error}"
    record["case"] = case
    record["seconds"] = time.perf_counter() - start
    record["cpu_s"] = time.process_time() - start_cpu
    return record


def keep_evidence(path: Path, case: dict, diagnosis) -> None:
    """Store what a campaign's decision was taken on, to re-decide it without refitting."""
    stored = {"case": case, "data": diagnosis.data, "evidence": diagnosis.evidence}
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        pickle.dump(stored, f)


def redecide(path: Path) -> dict:
    """A stored campaign's verdict, confidence and gain ratio under today's decision rule
    and confidence (the same fits: no model is refitted)."""
    with open(path, "rb") as f:
        stored = pickle.load(f)
    cause, seed = path.stem.rsplit("_", 1)
    start = time.perf_counter()
    envelope = envelope_structure(stored["data"])
    result, combinations, confidence, _ = conclude(
        stored["data"], stored["evidence"], envelope_significant=bool(envelope and envelope["significant"])
    )
    verdict = result["verdict"]
    causes = combinations[verdict]["causes"] if verdict in combinations else verdict_causes_of(verdict)
    # the document's extended model: that of the verdict, which the reweightings may have moved
    model = (
        combinations[verdict]["model"]
        if verdict in combinations
        else extended_model_of({**result, "cause": causes[0]})
    )
    base = result["baseline"]
    return {
        "cause": cause,
        "seed": int(seed),
        "verdict": causes[0],
        "causes": list(causes),
        "confidence": float(confidence.get(verdict, 0.0)),
        "ratio": result["errors"][model]["error"] / result["errors"][base]["error"],
        "extended_error": result["errors"][model]["error"],
        "case": stored["case"],
        "seconds": time.perf_counter() - start,
    }


TRUTH_CAUSES = ("microslip_power_law", "quadratic_damping", "stiffness_nonlinearity")
"""Causes whose campaigns have noise-free truth curves (one averaged mode table)."""


def baseline_misfit_on_truth(
    case: dict, velocity_range_in_s: tuple[float, float], scatter_ln_zeta: float, scatter_rel_f: float
) -> tuple[str, float, float]:
    """Is the hidden effect in the data? The baselines fitted to the case's noise-free truth.

    Dahl and LuGre are fitted to the lab's true (displacement-envelope) damping and
    frequency curves of the case's joint, effect and bearing area (the configuration's
    nominal run) over the measured amplitude range, weighted by the measured scatter.
    Returns the best baseline and its largest residuals on both curves, in scatters:
    where both stay within ``EXPLAINS_LIMIT`` the baseline explains the effect-laden
    truth itself, and ``none`` is the contract's reading of any campaign of that case.
    """
    from workflow.lab.configurations import mode_table, setup_configuration, truth_curves
    from workflow.lab.settings import LabSettings
    from workflow.models.averaged_fit import FitContext, fit_model, model_residuals
    from workflow.models.configuration_data import ConfigurationData, Scatter
    from workflow.models.settings import DiscoverySettings

    lab = LabSettings()
    v = np.geomspace(*velocity_range_in_s, 60)
    area = case["bearing_area_in2"]
    noise = Scatter(*(np.full(v.size, x) for x in (scatter_ln_zeta, scatter_rel_f) * 2))
    settings = DiscoverySettings(global_samples=256, local_starts=4)
    setup, curves = setup_configuration("x", area, lab)
    table = mode_table(setup, curves, lab, case["joint"], case["effect"], case["effect_size"])
    zeta, frequency_hz = truth_curves(setup, table, v)
    data = ConfigurationData("x", v, zeta, frequency_hz, np.zeros(v.size, int), ["r"], area, response_order=0)
    context = FitContext(float(np.quantile(v, 0.9)))
    best = None
    for model in ("dahl", "lugre"):
        fit = fit_model(model, data, noise, context, settings=settings, max_nfev=200)
        r = model_residuals(fit, data, noise, context)
        rms = float(np.sqrt(np.mean(0.5 * (r["z_noise"] ** 2 + r["f_noise"] ** 2))))
        if best is None or rms < best[0]:
            best = (rms, model, float(np.max(np.abs(r["z_noise"]))), float(np.max(np.abs(r["f_noise"]))))
    return best[1], best[2], best[3]


def drift_change_on_truth(
    case: dict, velocity_range_in_s: tuple[float, float], scatter_ln_zeta: float, scatter_rel_f: float
) -> float:
    """Is the drift in the data? Its first and last runs' noise-free curves, compared.

    The lab's nominal beam with the friction limit of the first run and of the last (the
    drift alone, no random spread), over the measured amplitude range: the largest change
    of ``ln zeta`` or of the relative frequency between them, in measured scatters.
    """
    from workflow.lab.configurations import mode_table, setup_configuration, truth_curves
    from workflow.lab.settings import LabSettings

    lab = LabSettings()
    v = np.geomspace(*velocity_range_in_s, 60)
    setup, curves = setup_configuration("x", case["bearing_area_in2"], lab)
    first, last = (
        truth_curves(
            setup,
            mode_table(setup, curves, lab, case["joint"], case["effect"], case["effect_size"], fraction),
            v,
        )
        for fraction in (0.0, 1.0)
    )
    change_zeta = np.max(np.abs(np.log(last[0] / first[0]))) / scatter_ln_zeta
    change_f = np.max(np.abs(last[1] / first[1] - 1.0)) / scatter_rel_f
    return float(max(change_zeta, change_f))


def added_term_on_truth(
    case: dict, velocity_range_in_s: tuple[float, float], scatter_ln_zeta: float, scatter_rel_f: float
) -> float:
    """Is a combination's added term in the data? The truth with and without it.

    The lab's nominal beam with the case's joint, with and without its added effect,
    over the measured amplitude range: the largest change of ``ln zeta`` or of the
    relative frequency, in measured scatters.
    """
    from workflow.lab.configurations import mode_table, setup_configuration, truth_curves
    from workflow.lab.settings import LabSettings

    lab = LabSettings()
    v = np.geomspace(*velocity_range_in_s, 60)
    setup, curves = setup_configuration("x", case["bearing_area_in2"], lab)
    alone, both = (
        truth_curves(setup, mode_table(setup, curves, lab, case["joint"], effect, case["effect_size"]), v)
        for effect in (None, case["effect"])
    )
    change_zeta = np.max(np.abs(np.log(both[0] / alone[0]))) / scatter_ln_zeta
    change_f = np.max(np.abs(both[1] / alone[1] - 1.0)) / scatter_rel_f
    return float(max(change_zeta, change_f))


def visibility() -> None:
    """Where are the hidden effects visible? Baselines fitted to the lab's noise-free truth.

    For bearing areas 0.4-1.36 in^2 and quadratic-damping sizes 0.002/0.004/0.006,
    :func:`baseline_misfit_on_truth` over 0.07-3 in/s with the campaigns' typical
    scatter (0.015 in ln zeta, 2e-5 in relative frequency); then the patch joint's
    micro-slip onset and log-log slope per area.
    """
    from workflow.lab.configurations import mode_table, setup_configuration, truth_curves
    from workflow.lab.settings import LabSettings

    lab = LabSettings()
    print("quadratic damping: best baseline's largest residual on the truth curves (scatters)")
    for area in (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.36):
        row = []
        for size in (0.002, 0.004, 0.006):
            case = {
                "joint": "dahl",
                "effect": "quadratic_damping",
                "effect_size": size,
                "bearing_area_in2": area,
            }
            model, worst_zeta, worst_f = baseline_misfit_on_truth(case, (0.07, 3.0), 0.015, 2e-5)
            row.append(f"{size}: {model:5s} max zeta {worst_zeta:5.2f} f {worst_f:5.2f}")
        print(f"  A = {area:.2f} in^2   " + " | ".join(row))
    print("micro-slip (patch joint): onset (joint damping > 0.1 zeta0), decades to 3 in/s, slope")
    vv = np.logspace(-2, 1, 301)
    for area in np.arange(0.6, 1.41, 0.05):
        setup, curves = setup_configuration("x", float(area), lab)
        zeta, _ = truth_curves(setup, mode_table(setup, curves, lab, "patches", None, None), vv)
        excess = zeta - lab.zeta0
        onset = vv[np.argmax(excess > 0.1 * lab.zeta0)]
        sel = (vv >= onset) & (vv <= 3.0)
        slope = np.polyfit(np.log(vv[sel]), np.log(excess[sel]), 1)[0] if sel.sum() > 3 else float("nan")
        print(
            f"  A = {area:.2f} in^2   onset {onset:6.3f} in/s   "
            f"{max(np.log10(3.0 / onset), 0):.2f} decades   slope {slope:.2f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--causes", nargs="*", default=None, help="default: every cause the path can hide")
    parser.add_argument(
        "--no-variability",
        action="store_true",
        help="every run of a campaign from the same beam (no run-to-run variability)",
    )
    parser.add_argument(
        "--time-domain",
        action="store_true",
        help="integrate every joint in time (causes none, microslip_power_law, run_drift, unknown, "
        "and the combinations)",
    )
    parser.add_argument(
        "--random-placement",
        action="store_true",
        help="each campaign recorded by a sensor placed at random (mode 1 x0.05 to x8 of the accelerometer)",
    )
    parser.add_argument(
        "--visibility",
        action="store_true",
        help="print where the hidden effects are visible (truth curves) and exit",
    )
    parser.add_argument(
        "--runs", type=int, default=RUNS, help=f"hits per campaign (default {RUNS}; 1: one hit, no run drift)"
    )
    parser.add_argument(
        "--sensors",
        type=int,
        default=1,
        help="sensors recording each hit (several: the verdict is the joint analysis of every sensor, "
        "each sensor's own verdict checked against the others)",
    )
    parser.add_argument("--keep", metavar="DIR", help="store each campaign's decision evidence in DIR")
    parser.add_argument(
        "--redecide",
        metavar="DIR",
        help="re-decide the campaigns stored by --keep with today's decision rule (no refit)",
    )
    args = parser.parse_args()
    if args.visibility:
        visibility()
        return
    if args.redecide:
        start = time.perf_counter()
        stored = sorted(Path(args.redecide).glob("*.pkl"))
        results = [redecide(p) for p in stored]
        args.causes = [c for c in CASES if any(r["cause"] == c for r in results)]
        seeds = sorted({r["seed"] for r in results})
        print(
            f"re-decided {len(results)} stored campaigns (seeds {seeds[0]}-{seeds[-1]}) from {args.redecide} "
            f"in {time.perf_counter() - start:.1f} s\n"
        )
        report(results, args.causes)
        return
    integrator = "time_domain" if args.time_domain else None
    hideable = [
        c
        for c in CASES
        if (not args.time_domain or time_domain_can_hide(c)) and (args.runs > 1 or c != "run_drift")
    ]
    if args.causes is None:
        args.causes = hideable
    elif set(args.causes) - set(hideable):
        parser.error(f"this path cannot hide {sorted(set(args.causes) - set(hideable))}")
    with tempfile.TemporaryDirectory() as work:
        tasks = [
            (
                c,
                s,
                work,
                not args.no_variability,
                integrator,
                args.random_placement,
                args.keep,
                args.runs,
                args.sensors,
            )
            for c in args.causes
            for s in range(args.first_seed, args.first_seed + args.seeds)
        ]
        start = time.perf_counter()
        with ProcessPoolExecutor(args.jobs) as pool:
            results = list(pool.map(_one, tasks))
        wall = time.perf_counter() - start
    seconds = np.array([r["seconds"] for r in results])
    cpu = np.array([r["cpu_s"] for r in results])
    print(
        f"run-to-run variability {'off' if args.no_variability else 'on'}, "
        f"{'time-domain' if args.time_domain else 'averaged (combinations: time-domain)'} integrator, "
        f"{args.sensors} sensor(s) {'placed at random (mode 1 x0.05-x8)' if args.random_placement else 'at the accelerometer'}, "
        f"{args.runs} hit(s) per campaign; "
        f"{len(results)} campaigns, {args.seeds} seeds per cause, {args.jobs} jobs, wall {wall:.0f} s; "
        f"per campaign (one process): wall median {np.median(seconds):.1f} s, max {seconds.max():.1f} s; "
        f"CPU median {np.median(cpu):.1f} s, max {cpu.max():.1f} s, total {cpu.sum():.0f} s\n"
    )
    report(results, args.causes)
    print("\nseconds per campaign (one process), median: wall to generate / wall in all / CPU in all")
    for cause in args.causes:
        rows = [r for r in results if r["cause"] == cause and "generate_s" in r]
        if rows:
            print(
                f"  {cause:44s} {np.median([r['generate_s'] for r in rows]):5.1f} / "
                f"{np.median([r['seconds'] for r in rows]):5.1f} / {np.median([r['cpu_s'] for r in rows]):5.1f}"
            )


def is_right(record: dict) -> bool:
    """The verdict's set of causes is the hidden one's."""
    return set(record["causes"]) == set(case_causes(record["cause"]))


def first_cause_right(record: dict) -> bool:
    """The verdict's first cause is one of the hidden ones."""
    return bool(record["causes"]) and record["causes"][0] in case_causes(record["cause"])


SHORT_NAMES = {"microslip_power_law": "micro", "quadratic_damping": "quad", "stiffness_nonlinearity": "stiff"}


def short_label(label: str) -> str:
    """A verdict's column heading: a combination's causes shortened, e.g. ``micro+quad``."""
    if "+" not in label:
        return label[:12]
    return "+".join(SHORT_NAMES.get(c, c) for c in label.split("+"))


def verdict_label(record: dict) -> str:
    """The verdict's column: its causes as a ``confidence`` key (:func:`verdict_key`)."""
    return verdict_key(record["causes"]) if record["causes"] else str(record["verdict"])


RELIABILITY_BINS = (0.0, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)
"""Confidence bin edges of the reliability table (the last bin holds 0.95-1.00)."""


def reliability(results: list[dict]) -> tuple[list[tuple], float, int]:
    """Per confidence bin: (low, high, count, mean confidence, fraction right); the Brier
    score of the verdicts (mean of ``(confidence - right)^2``) and how many verdicts had
    a confidence."""
    rated = [(r["confidence"], is_right(r)) for r in results if r["confidence"] is not None]
    rows = []
    edges = RELIABILITY_BINS
    for i, (low, high) in enumerate(zip(edges[:-1], edges[1:])):
        last = i == len(edges) - 2
        inside = [(p, ok) for p, ok in rated if low <= p < high or (last and p == high)]
        if inside:
            p, ok = np.array(inside, dtype=float).T
            rows.append((low, high, len(inside), float(p.mean()), float(ok.mean())))
        else:
            rows.append((low, high, 0, float("nan"), float("nan")))
    brier = float(np.mean([(p - ok) ** 2 for p, ok in rated])) if rated else float("nan")
    return rows, brier, len(rated)


def visibility_key(cause: str) -> str:
    """The case's figure that says whether its effect is in the data (:func:`report`)."""
    if "+" in cause:
        return "truth_added_term"
    return "truth_drift_change" if cause == "run_drift" else "truth_baseline_misfit"


def in_the_data(record: dict) -> bool:
    """Whether the campaign's hidden effect changes its noise-free curves by more than
    ``EXPLAINS_LIMIT`` scatters (False where the bench has no such figure)."""
    return record["case"].get(visibility_key(record["cause"]), 0.0) > EXPLAINS_LIMIT


def report(results: list[dict], causes: list[str]) -> None:
    """Confusion table, hit rates, gain ratios, explains_data, reliability, visibility, misses."""
    labels = VERDICTS + [c for c in causes if "+" in c]
    width = max(len(c) for c in causes) + 2
    header = (
        "hidden cause".ljust(width)
        + "".join(short_label(v).rjust(13) for v in labels)
        + "   other  hit  first"
    )
    print(header)
    for cause in causes:
        rows = [r for r in results if r["cause"] == cause]
        n = len(rows)
        counts = [sum(verdict_label(r) == v for r in rows) / n for v in labels]
        other = sum(verdict_label(r) not in labels for r in rows) / n
        hit = sum(is_right(r) for r in rows) / n
        first = sum(first_cause_right(r) for r in rows) / n
        print(
            cause.ljust(width) + "".join(f"{c:13.2f}" for c in counts) + f"{other:8.2f}{hit:5.2f}{first:7.2f}"
        )
    print("\ngain ratio (extended / baseline held-out error) when the cause was named:")
    for cause in causes:
        ratios = [
            r["ratio"] for r in results if r["cause"] == cause and is_right(r) and r["ratio"] is not None
        ]
        if ratios:
            print(
                f"  {cause:{width}s} median {sorted(ratios)[len(ratios) // 2]:.3f}  "
                f"max {max(ratios):.3f}  (n={len(ratios)})"
            )
    print("\nexplains_data (the extended model within 2 scatters everywhere) when the cause was named:")
    for cause in causes:
        named = [r for r in results if r["cause"] == cause and is_right(r)]
        if named:
            explained = sum(bool(r["case"].get("explains_data")) for r in named)
            print(f"  {cause:{width}s} {explained / len(named):.2f}  (n={len(named)})")
    rows, brier, n_rated = reliability([r for r in results if r["cause"] in causes])
    print(
        f"\nreliability: the verdict's confidence against the fraction of verdicts right "
        f"({n_rated} of {len(results)} verdicts carry a confidence)"
    )
    print("  confidence     n   mean conf   right")
    for low, high, n, mean, right in rows:
        print(f"  {low:.2f}-{high:.2f} {n:5d} {mean:11.3f} {right:7.3f}")
    print(f"  Brier score (mean of (confidence - right)^2): {brier:.4f}")
    print(
        "\nwhere the effect is in the data (the best baseline fitted to the case's noise-free truth "
        f"misses it by more than {EXPLAINS_LIMIT:g} scatters somewhere; run drift: its first and last "
        f"runs' noise-free curves differ by more than {EXPLAINS_LIMIT:g} scatters somewhere; a "
        f"combination: its added term changes the noise-free curves by more than {EXPLAINS_LIMIT:g} scatters):"
    )
    for cause in causes:
        key = visibility_key(cause)
        rows = [r for r in results if r["cause"] == cause and key in r["case"]]
        visible = [r for r in rows if in_the_data(r)]
        if rows:
            hit = sum(is_right(r) for r in visible) / len(visible) if visible else float("nan")
            smallest = min(r["case"][key] for r in rows)
            ratios = sorted(r["ratio"] for r in visible if is_right(r) and r["ratio"] is not None)
            gains = (
                f", gain ratio median {ratios[len(ratios) // 2]:.3f} max {ratios[-1]:.3f}" if ratios else ""
            )
            print(
                f"  {cause:{width}s} in the data {len(visible)}/{len(rows)} (smallest {smallest:g} scatters), "
                f"hit rate there {hit:.2f}{gains}"
            )
    weak = [
        r
        for r in results
        if r["cause"] in causes
        and in_the_data(r)
        and is_right(r)
        and r.get("extended_error") is not None
        and r["ratio"] >= CLEAR_GAIN
    ]
    if weak:
        print(
            f"\nnamed where in the data with a gain ratio of {CLEAR_GAIN:g} or more: the extended model's own "
            "held-out error (scatter units; 1 is a prediction at the noise, so a ratio below "
            f"{CLEAR_GAIN:g} needs a baseline error above about {1 / CLEAR_GAIN:.2f}):"
        )
        for cause in causes:
            rows = sorted((r for r in weak if r["cause"] == cause), key=lambda r: r["ratio"])
            if rows:
                errors = sorted(r["extended_error"] for r in rows)
                print(
                    f"  {cause:{width}s} {len(rows)}: ratios {rows[0]['ratio']:.2f}-{rows[-1]['ratio']:.2f}, "
                    f"extended errors {errors[0]:.2f}-{errors[-1]:.2f}, baseline errors "
                    f"{min(r['extended_error'] / r['ratio'] for r in rows):.2f}-"
                    f"{max(r['extended_error'] / r['ratio'] for r in rows):.2f}"
                )
    several = [r for r in results if r["cause"] in causes and r.get("channels")]
    if several:
        print(
            "\nsensors (each sensor's own verdict beside the joint one): campaigns where two sensors are "
            "0.7 sure of different verdicts; where one is 0.7 sure of another verdict than the joint "
            "verdict (also 0.7 sure); each sensor's verdict right:"
        )
        for cause in causes:
            rows = [r for r in several if r["cause"] == cause]
            if not rows:
                continue
            clash = sum(len({k for k, p in r["channels"].values() if p >= 0.7}) > 1 for r in rows)
            against = sum(
                (r["confidence"] or 0.0) >= 0.7
                and any(p >= 0.7 and k != verdict_label(r) for k, p in r["channels"].values())
                for r in rows
            )
            own = [
                set(k.split("+")) == set(case_causes(cause)) for r in rows for k, _ in r["channels"].values()
            ]
            print(
                f"  {cause:{width}s} {clash}/{len(rows)} sensors sure of different verdicts, {against}/{len(rows)} "
                f"a sensor sure against the joint verdict; sensors right {np.mean(own):.2f}"
            )
        alone = [
            {"cause": r["cause"], "causes": k.split("+"), "confidence": p}
            for r in several
            for k, p in r["channels"].values()
        ]
        rows, brier, _ = reliability(alone)
        print(f"  each sensor alone ({len(alone)} verdicts): confidence against the fraction right")
        print("  confidence     n   mean conf   right")
        for low, high, n, mean, right in rows:
            print(f"  {low:.2f}-{high:.2f} {n:5d} {mean:11.3f} {right:7.3f}")
        print(f"  Brier score: {brier:.4f}")
    print("\nmisses:")
    for r in results:
        if not is_right(r):
            confidence = "n/a" if r["confidence"] is None else f"{r['confidence']:.2f}"
            print(
                f"  {r['cause']:{width}s} seed {r['seed']:3d} -> {verdict_label(r)} (confidence {confidence})"
                f"{'  sensors ' + str(r['channels']) if r.get('channels') else ''}  case {r['case']}"
            )


if __name__ == "__main__":
    main()
