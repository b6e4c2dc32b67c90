"""Tuning rules and searches: Ziegler-Nichols from a relay experiment, detuning for an
overshoot target, and the Artificial Bee Colony search (niapy).

References: K. J. Astrom and T. Hagglund, *PID Controllers: Theory, Design and Tuning*
(ISA, 1995), ch. 6 (relay feedback with hysteresis, describing function ``N(a) = 4 d/(pi a)``)
and ch. 4 (Ziegler-Nichols ultimate-cycle rules); D. Karaboga, *An idea based on honey bee
swarm for numerical optimization* (2005) for the bee colony, run with niapy's
``ArtificialBeeColonyAlgorithm``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Ziegler-Nichols ultimate-cycle rules: kind -> (kp / Ku, Ti / Pu, Td / Pu); 0 means no term.
ZIEGLER_NICHOLS = {"P": (0.5, 0.0, 0.0), "PI": (0.45, 1 / 1.2, 0.0), "PID": (0.6, 0.5, 0.125)}


def ziegler_nichols(ku: float, pu_s: float, kind: str) -> tuple[float, float, float]:
    """Ziegler-Nichols gains ``(kp, ki, kd)`` of ``kp + ki/s + kd s`` from the ultimate gain and period.

    Parameters
    ----------
    ku : float
        Ultimate gain (controller units, for example V/mm).
    pu_s : float
        Ultimate period (s).
    kind : {"P", "PI", "PID"}

    Returns
    -------
    kp, ki, kd : float
        In the units of ``ku``, ``ku``/s and ``ku`` s.
    """
    if kind not in ZIEGLER_NICHOLS:
        raise ValueError(f"kind = {kind!r}: use one of {', '.join(ZIEGLER_NICHOLS)}")
    a, ti, td = ZIEGLER_NICHOLS[kind]
    kp = a * ku
    return kp, (kp / (ti * pu_s) if ti else 0.0), kp * td * pu_s


@dataclass
class LimitCycle:
    """A measured oscillation: ``amplitude`` (half the peak-to-peak, the signal's unit),
    ``period_s`` (mean of the full periods between upward crossings of the mean) and the
    number of ``periods`` it was measured over."""

    amplitude: float
    period_s: float
    periods: int


def limit_cycle(t_s: np.ndarray, y: np.ndarray) -> LimitCycle:
    """Amplitude and period of a steady oscillation ``y(t)`` (give the settled part only).

    Raises
    ------
    ValueError
        Fewer than two upward crossings of the mean (no oscillation to measure).
    """
    t, y = np.asarray(t_s, float), np.asarray(y, float)
    v = y - y.mean()
    up = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))
    if len(up) < 2:
        raise ValueError("no sustained oscillation: fewer than two upward crossings of the mean")
    # crossing times interpolated between samples
    tc = t[up] - v[up] * (t[up + 1] - t[up]) / (v[up + 1] - v[up])
    whole = slice(up[0], up[-1] + 1)
    return LimitCycle(float(np.ptp(y[whole]) / 2), float(np.mean(np.diff(tc))), len(up) - 1)


def relay_ultimate_gain(relay_amplitude: float, oscillation_amplitude: float) -> float:
    """Describing-function estimate of the ultimate gain, ``Ku = 4 d / (pi a)``.

    With hysteresis the limit cycle sits where the Nyquist curve meets ``-1/N(a)``, whose
    phase is ``-180 + asin(eps/a)`` degrees; ``4 d/(pi a)`` is ``|N(a)|`` there.
    """
    return 4.0 * relay_amplitude / (math.pi * oscillation_amplitude)


def detune(metric, target: float, *, lo: float = 1e-3, hi: float = 1.0, iterations: int = 40) -> float:
    """The largest factor ``c`` in ``[lo, hi]`` with ``metric(c) <= target``, by bisection.

    ``metric`` must be non-decreasing in ``c`` near the answer (overshoot against a gain
    factor, say).  Returns ``hi`` when ``metric(hi)`` already meets the target.

    Raises
    ------
    ValueError
        When even ``metric(lo)`` misses the target.
    """
    if metric(hi) <= target:
        return hi
    if not metric(lo) <= target:
        raise ValueError(f"no factor in [{lo:g}, {hi:g}] meets {target:g} (at {lo:g}: {metric(lo):g})")
    for _ in range(iterations):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if metric(mid) <= target else (lo, mid)
    return lo


@dataclass
class BeeColonyResult:
    """``x`` (best point), ``cost`` at it, the best point and cost after each iteration
    (``best_x``, ``best_cost``) and the number of cost ``evaluations``."""

    x: np.ndarray
    cost: float
    best_x: list
    best_cost: list
    evaluations: int


def bee_colony_minimize(
    cost, lower, upper, *, iterations: int, seed: int, population: int = 10, limit: int = 20
) -> BeeColonyResult:
    """Minimize ``cost(x)`` over the box ``[lower, upper]`` with niapy's Artificial Bee Colony.

    Parameters
    ----------
    cost : callable
        ``cost(x) -> float`` for a point ``x`` (ndarray); ``inf`` marks an infeasible point.
    lower, upper : sequence of float
        The box.
    iterations : int
        Bee-colony cycles (each: employed, onlooker and scout bees).
    seed : int
        Seed of niapy's generator: the same seed gives the same result.
    population, limit : int
        Colony size and the cycles without improvement before a food source is abandoned.
    """
    from niapy.algorithms.basic import ArtificialBeeColonyAlgorithm
    from niapy.callbacks import Callback
    from niapy.problems import Problem
    from niapy.task import Task

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    count = [0]
    history_x, history_cost = [], []

    class _Cost(Problem):
        def __init__(self):
            super().__init__(len(lower), lower, upper)

        def _evaluate(self, x):
            count[0] += 1
            value = float(cost(np.asarray(x, float)))
            return value if math.isfinite(value) else 1e300

    class _History(Callback):
        def after_iteration(self, population, fitness, best_x, best_fitness, **params):
            history_x.append(np.array(best_x, float))
            history_cost.append(float(best_fitness))

    algorithm = ArtificialBeeColonyAlgorithm(population_size=population, limit=limit, seed=seed, callbacks=[_History()])
    best_x, best_f = algorithm.run(Task(problem=_Cost(), max_iters=iterations))
    if best_x is None:  # niapy keeps an exception raised outside the main thread
        raise algorithm.exception
    return BeeColonyResult(np.asarray(best_x, float), float(best_f), history_x, history_cost, count[0])
