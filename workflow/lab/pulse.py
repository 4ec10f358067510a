"""The hammer's half-sine pulse: a linear mode's response to it, its samples and its spectrum."""

from __future__ import annotations

import numpy as np

__all__ = [
    "half_sine_response",
    "boxcar_half_sine",
    "half_sine_spectral_factor",
]


def half_sine_response(t_s, omega_rad_s, zeta, peak, duration_s):
    """Response of ``q'' + 2 zeta w q' + w^2 q = f(t)`` to a half-sine pulse.

    ``f = peak sin(pi t / duration)`` for ``0 <= t <= duration``, else 0; the
    oscillator is at rest before ``t = 0``.  Closed form of the Duhamel
    integral with the complex pole ``lam = -zeta w + i w_d``.

    Returns
    -------
    q, q_dot, q_ddot : ndarray

    Examples
    --------
    After the pulse the mode rings as if struck by the impulse ``2 peak duration / pi``,
    times :func:`half_sine_spectral_factor`, at the pulse centre (exactly without
    damping; a damping ratio of 0.005 leaves 1.5e-4 of the amplitude):

    >>> omega_rad_s, zeta, peak, duration_s = 2 * np.pi * 125.0, 0.005, 10.0, 1e-3
    >>> t_s = np.linspace(0.002, 0.05, 200)
    >>> q, _, _ = half_sine_response(t_s, omega_rad_s, zeta, peak, duration_s)
    >>> impulse = 2 * peak * duration_s / np.pi * half_sine_spectral_factor(omega_rad_s, duration_s)
    >>> wd, tc = omega_rad_s * np.sqrt(1 - zeta**2), t_s - duration_s / 2
    >>> ringing = impulse / wd * np.exp(-zeta * omega_rad_s * tc) * np.sin(wd * tc)
    >>> bool(np.max(np.abs(q - ringing)) < 1e-3 * np.max(np.abs(ringing)))
    True
    """
    t = np.asarray(t_s, dtype=float)
    wd = omega_rad_s * np.sqrt(1.0 - zeta**2)
    lam = -zeta * omega_rad_s + 1j * wd
    big_omega = np.pi / duration_s
    tc = np.clip(t, 0.0, duration_s)
    integral = (
        np.exp(-lam * tc) * (-lam * np.sin(big_omega * tc) - big_omega * np.cos(big_omega * tc)) + big_omega
    ) / (lam**2 + big_omega**2)
    z = np.exp(lam * np.clip(t, 0.0, None)) * integral * peak / wd
    q = z.imag
    qd = (lam * z).imag
    force = np.where((t >= 0) & (t <= duration_s), peak * np.sin(big_omega * tc), 0.0)
    qdd = force - 2 * zeta * omega_rad_s * qd - omega_rad_s**2 * q
    started = t >= 0
    return q * started, qd * started, qdd * started


def boxcar_half_sine(t_start_s, dt_s, t0_s, peak, duration_s):
    """Mean of a half-sine pulse over each sample interval ``[t, t + dt)``.

    An ideal integrating ADC: the sum of the samples times dt is the impulse.
    """
    big_omega = np.pi / duration_s

    def primitive(t):  # integral of the pulse from t0 to t
        tc = np.clip(t - t0_s, 0.0, duration_s)
        return peak / big_omega * (1.0 - np.cos(big_omega * tc))

    return (primitive(t_start_s + dt_s) - primitive(t_start_s)) / dt_s


def half_sine_spectral_factor(omega_rad_s, duration_s):
    """``|F(omega)| / impulse`` of a half-sine pulse (1 for an ideal impulse).

    After the pulse, a linear oscillator struck by it rings exactly as if struck by an
    impulse this much smaller at the pulse centre (the pulse is symmetric).
    """
    x = omega_rad_s * duration_s / np.pi
    return float(np.cos(0.5 * omega_rad_s * duration_s) / (1.0 - x**2)) if abs(x - 1) > 1e-9 else np.pi / 4
