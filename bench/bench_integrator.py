"""Benchmark: 1000 batched Dahl ring-downs against one solve_ivp reference.

Prints, per steps_per_period setting: median wall time of 1000 batched ring-downs
(3.2 s at 2560 Hz, f = 125 Hz), median time of one solve_ivp (LSODA) simulation in
the same run, their ratio per ring-down, and the worst relative envelope error over a
few parameter sets checked against a tight-tolerance reference.

Usage: .venv/bin/python bench/bench_integrator.py [--repeats 3] [--check 4]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from workflow.models.ringdown import envelope_relative_error, reference_ringdown, simulate_ringdown

FS, DURATION, OMEGA, V0 = 2560.0, 3.2, 2 * np.pi * 125.0, 10.0


def campaign(n, seed=0):
    """Dahl sets spanning the fit domain: friction share 1-10 %, knees 0.1-10 in/s."""
    rng = np.random.default_rng(seed)
    r = 10 ** rng.uniform(-2, -1, n)
    knee = 10 ** rng.uniform(-1, 1, n)
    sigma = r * OMEGA**2
    return {"sigma": sigma, "fc": sigma * knee / OMEGA}, 10 ** rng.uniform(-3, -2.3, n)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--check", type=int, default=4, help="sets checked against solve_ivp")
    ap.add_argument("--batch", type=int, default=1000)
    args = ap.parse_args()
    params, zeta0 = campaign(args.batch)
    check = np.linspace(0, args.batch - 1, args.check).astype(int)
    refs, t_ref = [], []
    for i in check:
        t0 = time.perf_counter()
        refs.append(
            reference_ringdown(
                "dahl",
                {k: v[i] for k, v in params.items()},
                omega_rad_s=OMEGA,
                zeta0=zeta0[i],
                initial_velocity=V0,
                fs_out_hz=FS,
                duration_s=DURATION,
                method="LSODA",
                rtol=1e-10,
            )["displacement"]
        )
        t_ref.append(time.perf_counter() - t0)
    t_one = float(np.median(t_ref))
    print(f"solve_ivp LSODA rtol 1e-10, one ring-down: median {t_one:.3f} s")
    print(
        f"{'steps/period':>12} {'actual':>7} {'t(1000) s':>10} {'per ring-down s':>16} "
        f"{'speed-up':>9} {'env. error':>11}"
    )
    for spp in (16, 32, 64):
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            sim = simulate_ringdown(
                "dahl",
                params,
                omega_rad_s=OMEGA,
                zeta0=zeta0,
                initial_velocity=V0,
                fs_out_hz=FS,
                duration_s=DURATION,
                steps_per_period=spp,
            )
            times.append(time.perf_counter() - t0)
        t_med = float(np.median(times)) * 1000 / args.batch
        err = max(float(envelope_relative_error(sim["displacement"][i], ref)) for i, ref in zip(check, refs))
        print(
            f"{spp:>12} {sim['steps_per_period']:>7.1f} {t_med:>10.3f} {t_med / 1000:>16.2e} "
            f"{t_one / (t_med / 1000):>9.0f} {err:>11.2e}"
        )


if __name__ == "__main__":
    main()
