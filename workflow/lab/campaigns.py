"""Virtual lab campaigns: simulated impact-hammer ring-down campaigns with known truth.

:func:`generate_campaign` writes a campaign folder and its truth (one run at a time:
its physics drawn, mode 1 from the averaged tables of :mod:`workflow.lab.configurations`
or integrated in time by :mod:`workflow.lab.time_domain`, recorded by the sensors of
:mod:`workflow.lab.sensors`); :func:`generate_sensor_campaigns` the same campaign seen by
several sensors, :func:`generate_one_hit` one hit recorded by three.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from workflow.lab.acquisition import simulate_run
from workflow.lab.campaign_files import FILE_FORMATS, campaign_yaml, format_run, truth_path, write_run_mat
from workflow.lab.configurations import (
    averaged_mode_response,
    higher_mode_response,
    higher_mode_table,
    mode_table,
    run_dahl_coulomb,
    setup_configuration,
    truth_curves,
)
from workflow.lab.layout import PAPER_CONFIGURATIONS, DemoSettings, run_name
from workflow.lab.sensors import Sensor, sensor_at_gain, sensor_view
from workflow.lab.settings import (
    DEFAULT_EFFECT_SIZES,
    EFFECT_CAUSES,
    EFFECT_SIZE_MEANING,
    INTEGRATORS,
    JOINT_EFFECTS,
    REFERENCE_VELOCITY_IN_S,
    TIME_DOMAIN_EFFECTS,
    LabSettings,
    draw_run_physics,
    true_causes,
)
from workflow.lab.time_domain import time_domain_mode_response

__all__ = [
    "generate_campaign",
    "generate_sensor_campaigns",
    "generate_one_hit",
]


def _check_sensors(sensors) -> tuple[Sensor, ...]:
    sensors = tuple(sensors)
    if not sensors:
        raise ValueError("at least one sensor is needed")
    names = [s.name for s in sensors]
    for name in names:
        if "acc" not in name.lower() or any(c in name for c in "\t\n\r()[],:{}#\"'") or name != name.strip():
            raise ValueError(
                f"sensor name {name!r}: it must contain 'acc' (the response role of campaign-format.md) "
                "and no tab, line break, bracket, comma, colon, brace, quote or '#'"
            )
    if len(set(names)) != len(names):
        raise ValueError(f"sensor names must differ, got {names}")
    return sensors


def generate_campaign(
    out_dir,
    *,
    seed=DemoSettings.seed,
    runs_per_configuration=DemoSettings.runs_per_configuration,
    joint="patches",
    effect=None,
    effect_size=None,
    configurations=None,
    samples_per_run=None,
    settings: LabSettings | None = None,
    integrator="averaged",
    sensors=None,
    noise_stream=0,
    nonlinear_modes=1,
    file_format="txt",
    modes_auto=False,
) -> dict:
    """Write a simulated campaign folder and its truth; return mode 1's truth dict.

    Parameters
    ----------
    out_dir : path
        Campaign folder to create (existing run files in it are overwritten).
    seed : int
        Random seed; the same seed gives byte-identical files.
    runs_per_configuration : int
    joint : {"patches", "dahl"}
        ``patches``: micro-slip contact patches (true cause ``microslip_power_law``);
        ``dahl``: single-state Dahl joint fitted to the same specimen (cause ``none``).
    effect : {None, "quadratic_damping", "stiffness_nonlinearity", "cubic_stiffness", "run_drift", "second_mode"}
        One added effect (``settings.JOINT_EFFECTS``): on the Dahl joint the one cause; on the
        patches (quadratic damping, a stiffness term) a second mechanism beside
        micro-slip, the truth's ``causes`` naming both.
    effect_size : float, optional
        Physical size of the effect (see ``settings.EFFECT_SIZE_MEANING``); default
        ``DEFAULT_EFFECT_SIZES[effect]``.
    configurations : dict, optional
        Name -> bearing area in^2 (or None for a campaign without areas);
        default the paper's three.
    samples_per_run : int, optional
        Samples per record; overrides ``settings.samples_per_run`` (default 8192, as the
        paper's analyser).
    settings : LabSettings, optional
        Instrument, specimen and run-to-run variability (default ``LabSettings()``:
        variability on; ``frequency_spread=0, damping_spread=0, slip_force_spread=0``
        makes every run of a configuration the same beam).
    integrator : {"averaged", "time_domain"}
        ``averaged``: mode 1 from the slow-flow tables (any joint and effect);
        ``time_domain``: the joint's equation of motion integrated in time (effects in
        ``TIME_DOMAIN_EFFECTS[joint]``; about 1 s per patch-joint run).
    sensors : sequence of Sensor, optional
        The accelerometers, each a column of every run file (or a MAT variable), at its
        own point of the beam (every mode at its own shape value there) with its own
        noise; default the reference accelerometer alone. Several sensors: the
        campaign.yaml names them as ``response: {channels: [...]}``.
    noise_stream : int
        Index of the first sensor's noise stream (sensor ``i`` draws from stream
        ``noise_stream + i``): with the same ``seed``, campaigns with different streams
        share the physics and the hammer and differ only in sensor noise.
    nonlinear_modes : {1, 2}
        Flexible modes the joint acts on: 2 gives mode 2 the contact patches too, through
        its own interface slip (``joint="patches"``, no effect, averaged); the
        campaign.yaml lists both modes (``modes_hz``) and mode 2's truth is written to
        ``truth_path(out_dir, 2)``.
    file_format : {"txt", "mat"}
        Run files as ASCII exports or MATLAB 5 MAT files (``t``, ``force``, one variable
        per sensor).
    modes_auto : bool
        campaign.yaml asks for every mode the analysis finds (``modes_hz: auto``) instead
        of listing the simulated ones.

    Examples
    --------
    One run of one configuration (a few seconds); the truth is written beside the folder:

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     truth = generate_campaign(Path(folder) / "demo", runs_per_configuration=1, configurations={"no_washer": 1.36})
    ...     files = sorted(path.relative_to(folder).as_posix() for path in Path(folder).rglob("*.*"))
    >>> files
    ['demo.truth.json', 'demo/campaign.yaml', 'demo/no_washer/run01.txt']
    >>> truth["expected_cause"]
    'microslip_power_law'
    """
    if joint not in ("patches", "dahl"):
        raise ValueError(f"joint must be 'patches' or 'dahl', got {joint!r}")
    if effect not in EFFECT_CAUSES:
        raise ValueError(
            f"effect must be one of {sorted(k for k in EFFECT_CAUSES if k)} or None, got {effect!r}"
        )
    if effect is not None and effect not in JOINT_EFFECTS[joint]:
        raise ValueError(f"the {joint} joint takes an effect in {JOINT_EFFECTS[joint]}, got {effect!r}")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if integrator == "time_domain" and effect not in TIME_DOMAIN_EFFECTS[joint]:
        raise ValueError(
            f"the time-domain path integrates the {joint} joint: it takes effect in "
            f"{TIME_DOMAIN_EFFECTS[joint]}, got {effect!r}"
        )
    if nonlinear_modes not in (1, 2):
        raise ValueError(f"nonlinear_modes must be 1 or 2, got {nonlinear_modes!r}")
    if nonlinear_modes == 2 and (joint != "patches" or effect is not None or integrator != "averaged"):
        raise ValueError("a joint on two modes is the contact patches alone, averaged")
    if file_format not in FILE_FORMATS:
        raise ValueError(f"file_format must be one of {sorted(FILE_FORMATS)}, got {file_format!r}")
    sensors = _check_sensors(sensors if sensors is not None else (Sensor(),))
    if effect is not None and effect_size is None:
        effect_size = DEFAULT_EFFECT_SIZES[effect]
    if effect == "cubic_stiffness" and not effect_size > 0:
        raise ValueError(
            f"cubic_stiffness is a hardening spring (effect_size > 0), got {effect_size!r}: a softening "
            "cubic loses all stiffness at a finite amplitude; use stiffness_nonlinearity"
        )
    if runs_per_configuration < 1:
        raise ValueError("runs_per_configuration must be at least 1")
    configurations = dict(PAPER_CONFIGURATIONS if configurations is None else configurations)
    settings = settings if settings is not None else LabSettings()
    if samples_per_run is not None:
        settings = replace(settings, samples_per_run=samples_per_run)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    root_seq = np.random.SeedSequence(seed)
    children = root_seq.spawn(len(configurations))
    velocity = np.logspace(-3, 2, 101)
    causes = true_causes(joint, effect)
    names = [s.name for s in sensors]
    truth = {
        "campaign_dir": out.name,
        "seed": seed,
        "joint": joint,
        "effect": effect,
        "effect_size": effect_size,
        "effect_size_meaning": EFFECT_SIZE_MEANING.get(effect),
        "reference_velocity_in_s": REFERENCE_VELOCITY_IN_S,
        "expected_cause": causes[0],
        "causes": causes,
        "integrator": integrator,
        "sensors": [
            {**asdict(s), "noise_stream": noise_stream + i, "column": s.name} for i, s in enumerate(sensors)
        ],
        "lab_settings": {k: v for k, v in asdict(settings).items() if k != "joint"},
        "joint_parameters": {k: v for k, v in asdict(settings.joint).items() if k != "geometry"},
        "preload_lbf": settings.joint.preload_lbf,
        "geometry": asdict(settings.joint.geometry),
        "velocity_amplitude_in_s": velocity.tolist(),
        "configurations": {},
    }
    setups = {}
    for cname, area in configurations.items():
        setups[cname] = setup_configuration(cname, area, settings)
    modes_hz = [float(np.mean([s.mode.frequency_hz for s, _ in setups.values()]))]
    if nonlinear_modes == 2:
        modes_hz.append(float(np.mean([s.mode.higher_modes[0].frequency_hz for s, _ in setups.values()])))
    (out / "campaign.yaml").write_text(
        campaign_yaml(
            f"virtual-lab-{joint}-{effect or 'baseline'}-{seed}",
            configurations,
            "auto" if modes_auto else [round(f) for f in modes_hz],
            settings.sample_rate_hz,
            channels=names if len(sensors) > 1 else None,
            file_format=file_format,
        )
    )
    mode2_truth = {**truth, "mode": 2, "mode_hz": modes_hz[-1], "causes": causes, "configurations": {}}
    truth["mode"], truth["mode_hz"] = 1, modes_hz[0]
    for (cname, (setup, curves)), child in zip(setups.items(), children):
        folder = out / cname
        folder.mkdir(exist_ok=True)
        for stale in [*folder.glob("run*.txt"), *folder.glob("run*.mat")]:
            stale.unlink()
        hammer_seq, noise_seq, variability_seq = child.spawn(3)
        rng = np.random.default_rng(hammer_seq)
        noise_rngs = [
            np.random.default_rng(s) for s in noise_seq.spawn(noise_stream + len(sensors))[noise_stream:]
        ]
        runs = draw_run_physics(settings, np.random.default_rng(variability_seq), runs_per_configuration)
        views = tuple(sensor_view(setup.mode, settings, s) for s in sensors)
        base_table = mode_table(setup, curves, settings, joint, effect, effect_size)
        mode = setup.mode
        # the truth's curves are against the first sensor's own velocity amplitude
        first_gain = abs(views[0].mode1_participation / mode.accelerometer_participation)
        zeta, fd = truth_curves(setup, base_table, velocity / first_gain)
        entry = {
            "bearing_area_in2": setup.bearing_area_in2,
            "linear_frequency_hz": mode.frequency_hz,
            "node_positions_in": mode.node_positions_in.tolist(),
            "accelerometer_participation": mode.accelerometer_participation,
            "hammer_participation": mode.hammer_participation,
            "higher_modes_hz": [m.frequency_hz for m in mode.higher_modes],
            "dahl_sigma_modal": setup.dahl_sigma,
            "dahl_coulomb_modal": setup.dahl_coulomb,
            "n_patches_per_interface": int(setup.joint_modes.patches.x_rel_in.size),
            "zeta": zeta.tolist(),
            "damped_frequency_hz": fd.tolist(),
            "channels": _channel_truth(setup, base_table, velocity, sensors, views, 1),
            "runs": [],
        }
        mode2_table = higher_mode_table(setup, settings, 0) if nonlinear_modes == 2 else None
        if mode2_table is not None:
            mode2_truth["configurations"][cname] = {
                "bearing_area_in2": setup.bearing_area_in2,
                "linear_frequency_hz": mode.higher_modes[0].frequency_hz,
                "accelerometer_participation": mode.higher_modes[0].accelerometer_participation,
                "hammer_participation": mode.higher_modes[0].hammer_participation,
                "channels": _channel_truth(setup, mode2_table, velocity, sensors, views, 2),
                "runs": [],
            }
        for i, run in enumerate(runs):
            fraction = i / (runs_per_configuration - 1) if runs_per_configuration > 1 else 0.0
            table = mode_table(setup, curves, settings, joint, effect, effect_size, fraction, run)
            coulomb = run_dahl_coulomb(setup, effect, effect_size, fraction, run.slip_force_factor)
            if integrator == "time_domain":
                response = time_domain_mode_response(setup, joint, coulomb, run, effect, effect_size)
            else:
                response = averaged_mode_response(setup, table, run)
            higher_responses = ()
            if mode2_table is not None:
                mode2_response, run_mode2_table = higher_mode_response(setup, settings, 0, run)
                higher_responses = (mode2_response,)
            ratio = effect_size if effect == "second_mode" else 0.0
            t, f, acc, facts = simulate_run(
                setup,
                response,
                settings,
                rng,
                ratio,
                run=run,
                sensors=views,
                noise_rngs=noise_rngs,
                higher_responses=higher_responses,
            )
            name = run_name(i)
            if file_format == "mat":
                write_run_mat(folder / f"{name}.mat", t, f, acc, names)
            else:
                (folder / f"{name}.txt").write_text(format_run(t, f, acc, settings.sample_rate_hz, names))
            z_run, f_run = truth_curves(setup, table, velocity / first_gain)
            entry["runs"].append(
                {
                    "run": name,
                    **facts,
                    **asdict(run),
                    "linear_frequency_hz": mode.frequency_hz * run.frequency_factor,
                    "dahl_coulomb_modal": coulomb,
                    "zeta": z_run.tolist(),
                    "damped_frequency_hz": f_run.tolist(),
                }
            )
            if mode2_table is not None:
                participation = views[0].participation(2)
                z2, f2 = truth_curves(setup, run_mode2_table, velocity, participation=participation)
                mode2_truth["configurations"][cname]["runs"].append(
                    {"run": name, "zeta": z2.tolist(), "damped_frequency_hz": f2.tolist()}
                )
        truth["configurations"][cname] = entry
    truth_path(out).write_text(json.dumps(truth, indent=1))
    if nonlinear_modes == 2:
        truth_path(out, 2).write_text(json.dumps(mode2_truth, indent=1))
    return truth


def _channel_truth(setup, table, velocity, sensors, views, mode_index) -> dict:
    """Per sensor: the mode's shape at it and the true curves against its own velocity
    amplitude."""
    channels = {}
    for sensor, view in zip(sensors, views, strict=True):
        participation = view.participation(mode_index)
        zeta, fd = truth_curves(setup, table, velocity, participation=participation)
        channels[sensor.name] = {
            "position_in": view.position_in,
            "participation": participation,
            "noise_g": view.noise_g,
            "zeta": zeta.tolist(),
            "damped_frequency_hz": fd.tolist(),
        }
    return channels


def generate_sensor_campaigns(out_root, sensors: Mapping[str, Sensor | float], **campaign_options) -> dict:
    """The same campaign as seen by several sensors: one campaign folder per sensor.

    Every campaign has the same physics, hammer hits and run-to-run variations (same
    ``seed``); each sensor sees every mode at its own shape value and has its own
    independent noise.

    Parameters
    ----------
    out_root : path
        Folder that receives ``<sensor name>/`` campaign folders (truth beside each).
    sensors : mapping of str to Sensor or float
        Sensor name (the campaign folder) -> a :class:`workflow.lab.sensors.Sensor`, or mode 1's amplitude
        relative to the accelerometer (``|phi(x) / phi(x_accelerometer)|``): the sensor
        is then placed at the point of the first configuration's mode 1 with that ratio
        nearest the accelerometer.
    **campaign_options
        Passed to :func:`generate_campaign` (seed, joint, effect, configurations ...).

    Returns
    -------
    dict
        Sensor name -> truth dict of its campaign.
    """
    root = Path(out_root)
    settings = campaign_options.get("settings") or LabSettings()
    configurations = campaign_options.get("configurations") or PAPER_CONFIGURATIONS
    name, area = next(iter(configurations.items()))
    mode = setup_configuration(name, area, settings)[0].mode
    placed = {}
    for name, sensor in sensors.items():
        if not isinstance(sensor, Sensor):
            sensor = sensor_at_gain(mode, settings, float(sensor))
        placed[name] = sensor
    return {
        name: generate_campaign(root / name, sensors=(sensor,), noise_stream=index, **campaign_options)
        for index, (name, sensor) in enumerate(placed.items())
    }


HIT_SENSOR_GAINS = {"acc1": 1.0, "acc2": 0.05, "acc3": 2.0}
"""The one-hit record's sensors: mode 1 at each relative to the reference accelerometer
(acc2 near a node of mode 1, acc3 towards a free end)."""


def generate_one_hit(
    out_dir, *, seed=7, sample_rate_hz=12800.0, duration_s=5.0, bearing_area_in2=1.36
) -> dict:
    """One hammer hit recorded by three accelerometers, as one MAT 5 file.

    The shape of a real multi-sensor impact test: a campaign of one configuration
    (``hit``) and one run, ``hit/run01.mat`` holding ``t``, ``force`` and ``acc1``-``acc3``
    (``HIT_SENSOR_GAINS``), the joint acting on modes 1 and 2, campaign.yaml asking for
    every mode (``modes_hz: auto``) and every channel. Returns mode 1's truth (mode 2's
    is at ``truth_path(out_dir, 2)``).
    """
    settings = LabSettings(
        sample_rate_hz=sample_rate_hz, samples_per_run=int(round(duration_s * sample_rate_hz))
    )
    mode = setup_configuration("hit", bearing_area_in2, settings)[0].mode
    sensors = tuple(sensor_at_gain(mode, settings, gain, name) for name, gain in HIT_SENSOR_GAINS.items())
    return generate_campaign(
        out_dir,
        seed=seed,
        runs_per_configuration=1,
        configurations={"hit": bearing_area_in2},
        settings=settings,
        sensors=sensors,
        nonlinear_modes=2,
        file_format="mat",
        modes_auto=True,
    )
