"""Mode 1 of the virtual lab integrated in time, for test campaigns.

``generate_campaign(integrator="time_domain")`` integrates the joint's equation of motion
in time (contact patches: :func:`patch_mode_response_time_domain`; Dahl:
:func:`workflow.models.ringdown.simulate_ringdown`) instead of the averaged equations of
:mod:`workflow.lab.configurations`, so that the discovery is not tested only on the model
it fits.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from workflow.lab.configurations import JointSetup, ModeResponse, effect_coefficients
from workflow.lab.pulse import half_sine_response, half_sine_spectral_factor
from workflow.lab.settings import RunPhysics
from workflow.models import ringdown

__all__ = [
    "dahl_mode_response_time_domain",
    "patch_mode_response_time_domain",
    "time_domain_mode_response",
]


def dahl_mode_response_time_domain(
    t_s, sigma, coulomb, omega0_rad_s, zeta0, modal_peak, duration_s, oversampling=8, steps_per_period=64
):
    """Modal acceleration of mode 1 with a Dahl joint, integrated in time.

    The equation of motion ``xi'' + 2 zeta0 omega0 xi' + (omega0^2 - sigma) xi + F = 0``,
    ``dF/dxi = sigma (1 - F sign(xi') / Fc)`` (the stuck stiffness ``sigma`` is part of
    ``omega0``, as in the averaged tables) is integrated by the compiled Lawson RK4 of
    :func:`workflow.models.ringdown.simulate_ringdown`, from the pulse centre with the
    pulse's impulse at the stuck frequency; during the pulse (a tenth of a cycle) the mode
    responds as the stuck linear oscillator.

    Parameters
    ----------
    t_s : ndarray
        Times from the pulse start, s (uniform).
    sigma : float
        Dahl rest stiffness in modal units, 1/s^2.
    coulomb : float
        Dahl friction limit ``Fc`` in modal units (modal force per unit mass).
    omega0_rad_s : float
        Stuck-joint natural frequency, rad/s.
    zeta0 : float
        Linear modal damping ratio (of ``omega0``).
    modal_peak : float
        Peak modal force of the half-sine pulse (per unit modal mass).
    duration_s : float
        Pulse duration, s.
    oversampling : int
        Integrator output samples per sample of ``t_s``: the pulse centre falls on the
        output grid within ``dt / (2 oversampling)`` (phase error < 0.01 rad at 125 Hz).
    steps_per_period : int
        Minimum integration steps per period (envelope error < 1e-4 at 64,
        bench/bench_integrator.py).

    Returns
    -------
    ndarray
        Modal acceleration at ``t_s``.
    """
    t = np.asarray(t_s, dtype=float)
    if omega0_rad_s**2 <= sigma:
        raise ValueError("the Dahl stiffness sigma must be below omega0^2 (the stuck mode includes it)")
    omega_free = np.sqrt(omega0_rad_s**2 - sigma)
    impulse = 2.0 * modal_peak * duration_s / np.pi
    v0 = impulse * half_sine_spectral_factor(omega0_rad_s, duration_s)
    dt = t[1] - t[0]
    fs_fine = oversampling / dt
    centre = 0.5 * duration_s
    n_fine = int(np.ceil((t[-1] - centre) * fs_fine)) + 2
    out = ringdown.simulate_ringdown(
        "dahl",
        {"sigma": sigma, "fc": coulomb},
        omega_rad_s=omega_free,
        zeta0=zeta0 * omega0_rad_s / omega_free,  # same damping force 2 zeta0 omega0 xi'
        initial_velocity=v0,
        fs_out_hz=fs_fine,
        duration_s=n_fine / fs_fine,
        steps_per_period=steps_per_period,
    )
    acc_fine = out["acceleration"][0]
    _, _, acc = half_sine_response(t, omega0_rad_s, zeta0, modal_peak, duration_s)
    after = t > duration_s
    index = np.round((t[after] - centre) * fs_fine).astype(int)
    acc[after] = acc_fine[np.minimum(index, n_fine - 1)]
    return acc


_FREEZE_MARGIN = 1.05
"""A patch is frozen once the amplitude is this factor below its slip onset (the
energy amplitude ``sqrt(x^2 + (x'/omega0)^2)`` varies within a cycle by the joint's
< 1 % softening)."""


@numba.njit(cache=True, error_model="numpy")
def _patch_ringdown_kernel(
    s, k, fs, onset, stiffness, damping, quadratic, cubic, e00, e01, e10, e11, v0, n_steps, h, acc
):
    """Kick-drift-kick ring-down of ``x'' + damping x' + stiffness x + R = 0`` from
    ``x = 0, x' = v0``, ``R = sum s (f - k s x) + quadratic x'|x'| + cubic x^3`` with
    Jenkins forces ``f``; writes ``acc``.

    Patches sorted by ``onset``. Once the amplitude has fallen below a patch's onset it
    never slips again: stuck, its ``s (f - k s x)`` is constant, so it is summed once
    (``frozen``) and leaves the loop.
    """
    f = np.zeros(s.size)
    x, eta, x_prev = 0.0, v0, 0.0
    n_active = s.size
    frozen = 0.0
    for j in range(n_steps):
        dx = x - x_prev
        remainder = frozen + quadratic * eta * abs(eta) + cubic * x * x * x
        for i in range(n_active):
            trial = f[i] + k[i] * s[i] * dx
            f[i] = min(max(trial, -fs[i]), fs[i])
            remainder += s[i] * (f[i] - k[i] * s[i] * x)
        amplitude = math.sqrt(x * x + eta * eta / stiffness)
        while n_active > 0 and onset[n_active - 1] > _FREEZE_MARGIN * amplitude:
            n_active -= 1
            frozen += s[n_active] * (f[n_active] - k[n_active] * s[n_active] * x)
        x_prev = x
        if j > 0:
            eta -= 0.5 * h * remainder  # second half kick of the previous step
        acc[j] = -stiffness * x - damping * eta - remainder
        eta -= 0.5 * h * remainder
        x, eta = e00 * x + e01 * eta, e10 * x + e11 * eta


def patch_mode_response_time_domain(
    t_s,
    slip_per_xi,
    stiffness_lbf_in,
    slip_force_lbf,
    omega0_rad_s,
    zeta0,
    modal_peak,
    duration_s,
    oversampling=4,
    quadratic=0.0,
    cubic=0.0,
):
    """Modal acceleration of mode 1 with the contact patches, integrated in time.

    ``xi'' + 2 zeta0 omega0 xi' + omega0^2 xi + sum s (f - k s xi) + c2 xi'|xi'| + k3 xi^3
    = 0`` (the stuck patch stiffness is part of ``omega0``), every patch a Jenkins element
    (``f`` clipped at its slip force). The linear oscillator's flow over a step is exact;
    the nonlinear remainder (the patches' part zero while they stick) is applied as two
    half kicks per step (second order, Strang). Starts at the pulse centre with the pulse's impulse at the stuck
    frequency; during the pulse the stuck linear oscillator. Patches whose slip onset lies
    above the initial amplitude never slip and are left out (their remainder is zero).

    Parameters
    ----------
    t_s : ndarray
        Times from the pulse start, s (uniform).
    slip_per_xi, stiffness_lbf_in, slip_force_lbf : ndarray
        Slip per unit modal coordinate (in), tangential stiffness (lbf/in) and slip force
        (lbf) of every patch (broadcast together).
    omega0_rad_s, zeta0, modal_peak, duration_s
        As :func:`dahl_mode_response_time_domain`.
    oversampling : int
        Steps per sample of ``t_s`` (4 at 2560 samples/s: 80 steps per period at 126 Hz;
        8 changes the damping by < 0.03 % and the frequency by < 1e-6, measured).
    quadratic, cubic : float
        ``c2`` (1/in) and ``k3`` (1/(in^2 s^2)) of an added velocity-squared loss and
        cubic spring (:func:`workflow.lab.configurations.effect_coefficients`); 0 for the joint alone.

    Returns
    -------
    ndarray
        Modal acceleration at ``t_s``.
    """
    t = np.asarray(t_s, dtype=float)
    s, k, fs = (
        np.ascontiguousarray(x, dtype=float).ravel()
        for x in np.broadcast_arrays(np.abs(slip_per_xi), stiffness_lbf_in, slip_force_lbf)
    )
    v0 = 2.0 * modal_peak * duration_s / np.pi * half_sine_spectral_factor(omega0_rad_s, duration_s)
    with np.errstate(divide="ignore"):
        onset = fs / (k * s)  # modal amplitude at which each patch starts slipping
    # sorted by onset; those above the initial amplitude never slip
    order = np.argsort(onset)
    order = order[onset[order] < _FREEZE_MARGIN * v0 / omega0_rad_s]
    dt = t[1] - t[0]
    h = dt / oversampling
    centre = 0.5 * duration_s
    n_steps = int(np.ceil((t[-1] - centre) / h)) + 2
    stiffness, damping = omega0_rad_s**2, 2.0 * zeta0 * omega0_rad_s
    e00, e01, e10, e11 = (float(e) for e in ringdown.oscillator_propagator(stiffness, damping, h))
    acc_fine = np.empty(n_steps)
    _patch_ringdown_kernel(
        s[order],
        k[order],
        fs[order],
        onset[order],
        stiffness,
        damping,
        float(quadratic),
        float(cubic),
        e00,
        e01,
        e10,
        e11,
        v0,
        n_steps,
        h,
        acc_fine,
    )
    _, _, acc = half_sine_response(t, omega0_rad_s, zeta0, modal_peak, duration_s)
    after = t > duration_s
    index = np.round((t[after] - centre) / h).astype(int)
    acc[after] = acc_fine[np.minimum(index, n_steps - 1)]
    return acc


def time_domain_mode_response(
    setup: JointSetup, joint: str, coulomb: float, run: RunPhysics, effect=None, effect_size=None
) -> ModeResponse:
    """Mode 1 with the run's joint (``patches`` or ``dahl`` with friction limit
    ``coulomb``) integrated in time; with the patches, an added ``quadratic_damping`` or
    ``cubic_stiffness`` is a term of the equation of motion."""
    omega0 = setup.omega0_rad_s * run.frequency_factor
    patches = setup.joint_modes.patches
    quadratic, cubic = effect_coefficients(setup, effect, effect_size)

    def response(tau, modal_peak, duration):
        if joint == "patches":
            return patch_mode_response_time_domain(
                tau,
                setup.joint_modes.slip_per_xi,
                patches.stiffness_lbf_in,
                patches.slip_force_lbf * run.slip_force_factor,
                omega0,
                run.zeta0,
                modal_peak,
                duration,
                quadratic=quadratic,
                cubic=cubic,
            )
        return dahl_mode_response_time_domain(
            tau, setup.dahl_sigma, coulomb, omega0, run.zeta0, modal_peak, duration
        )

    return response
