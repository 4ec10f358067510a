"""The models stage's sections of config.yaml: ``models`` (the time-domain Dahl and LuGre
fits) and ``discovery`` (the averaged-model fits of :mod:`workflow.models.averaged_fit`,
with the folds and resamples of the diagnosis that runs them).

The stage's functions take their defaults from these classes; :mod:`workflow.config`
validates them at workflow start (types, bounds, unknown keys).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from annotated_types import Ge, Le

from workflow.io.validation import FORBID_UNKNOWN_KEYS, Seed

__all__ = ["ModelSettings", "DiscoverySettings"]


@dataclass(frozen=True)
class ModelSettings:
    """Fitting and simulating the friction models."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    # Each is one simulated ring-down; 256 is 64 times the default's cost, and the best of 16
    # was never chosen on 28 fits.
    global_samples: Annotated[int, Ge(4), Le(256)] = 4
    """Parameter sets tried in the global (quasi-random) stage of each time-domain
    fit, beside the optimum of the averaged model (which has its own global search
    and is far cheaper); they guard against a poor averaged start. Each costs one
    simulated and analysed ring-down. On 28 fits (the demo, two real campaigns,
    hidden-effect campaigns generated with the averaged model and in the time domain)
    the best of 16 had 3 to 874 times the averaged start's cost and was never chosen
    (docs/performance.md)."""

    # Each refined start costs local_iterations batched simulations: 16 is 16 times the default.
    local_starts: Annotated[int, Ge(1), Le(16)] = 1
    """Best candidates refined by the local optimiser."""

    # Each costs one batched simulation; from the averaged start 4 suffice, and 50 (12 times
    # the default's cost) is far past where Levenberg-Marquardt stops improving.
    local_iterations: Annotated[int, Ge(1), Le(50)] = 4
    """Levenberg-Marquardt iterations of the time-domain refinement (each costs
    one batched simulation of every parameter perturbation)."""

    # RK4's error falls as h^4: 128 steps (8 x the default) bring the envelope error below
    # 1e-3 / 8^4 = 2.4e-7, under any recorder's noise, at 8 times the cost (1e9 ran past 300 s).
    steps_per_period: Annotated[int, Ge(8), Le(128)] = 16
    """Fixed RK4 steps per period of the mode (16 keeps the envelope error below
    1e-3 against a tight-tolerance reference: bench/bench_integrator.py)."""

    seed: Seed = 1976


@dataclass(frozen=True)
class DiscoverySettings:
    """Fitting the averaged candidate models and deciding the cause (docs/discovery.md):
    the optimiser settings of :func:`workflow.models.averaged_fit.fit_model` (global
    samples, local starts, seed), the folds of the held-out error and the resamples
    behind each verdict's confidence."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    # Rounded up to a power of two (a Sobol set); 4096 points place a sample within a quarter
    # of each range of a six-parameter box (4096^(-1/6)), at 16 times the default's cost.
    global_samples: Annotated[int, Ge(16), Le(4096)] = 256
    """Quasi-random parameter sets in the global stage of each averaged-model fit."""

    # Each start is one local fit, in every fold and resample: 32 is 8 times the default.
    local_starts: Annotated[int, Ge(1), Le(32)] = 4
    """Best global candidates refined locally."""

    # K = min(folds, number of runs); 50 is more runs than a campaign's configuration
    # holds (the demo's limit is 200 in all), at 10 times the default's cost.
    folds: Annotated[int, Ge(2), Le(50)] = 5
    """Folds over runs for the held-out error (contiguous amplitude blocks with one run)."""

    seed: Seed = 1976

    # Each resample repeats the decision; a confidence's Monte Carlo error is at most
    # 0.5 / sqrt(B): 5 % at the default, 1.6 % at 1000, at 10 times the cost.
    resamples: Annotated[int, Ge(10), Le(1000)] = 100
    """Bayesian-bootstrap reweightings of the runs (of the held-out amplitude blocks with
    one run) behind each verdict's ``confidence`` (docs/discovery.md, Confidence)."""
