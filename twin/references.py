"""Reference signals: position with velocity and acceleration for feedforward.

Every reference has ``n_axes`` and ``sample(t) -> ndarray (len(t), n_axes, 3)`` with columns
position (m), velocity (m/s), acceleration (m/s^2).  One-axis signals (step, ramp, sines) drive
the axes listed in ``axes`` (indices) and hold the others at zero; paths (circle, square,
polyline) need two axes and are given in mm and mm/min as machinists state them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def _per_axis(signal: np.ndarray, n_axes: int, axes: tuple[int, ...] | None) -> np.ndarray:
    out = np.zeros((signal.shape[0], n_axes, 3))
    for a in range(n_axes) if axes is None else axes:
        out[:, a, :] = signal
    return out


@dataclass
class Step:
    """Step of ``amplitude_m`` at ``t0_s``."""

    amplitude_m: float
    t0_s: float = 0.0
    n_axes: int = 1
    axes: tuple[int, ...] | None = None

    def sample(self, t):
        t = np.asarray(t, float)
        s = np.zeros((t.size, 3))
        s[:, 0] = np.where(t >= self.t0_s, self.amplitude_m, 0.0)
        return _per_axis(s, self.n_axes, self.axes)


@dataclass
class Ramp:
    """Ramp of slope ``rate_m_per_s`` from ``t0_s``."""

    rate_m_per_s: float
    t0_s: float = 0.0
    n_axes: int = 1
    axes: tuple[int, ...] | None = None

    def sample(self, t):
        t = np.asarray(t, float)
        on = t >= self.t0_s
        s = np.zeros((t.size, 3))
        s[:, 0] = np.where(on, self.rate_m_per_s * (t - self.t0_s), 0.0)
        s[:, 1] = np.where(on, self.rate_m_per_s, 0.0)
        return _per_axis(s, self.n_axes, self.axes)


#: Most sines a sum-of-sines reference may hold (each is evaluated at every tick).
MAX_SINES = 100


@dataclass
class SumOfSines:
    """Sum of sines: x(t) = sum_i A_i sin(2 pi f_i t + phi_i), at most :data:`MAX_SINES` terms."""

    amplitudes_m: tuple[float, ...]
    frequencies_hz: tuple[float, ...]
    phases_rad: tuple[float, ...] | None = None
    n_axes: int = 1
    axes: tuple[int, ...] | None = None

    def sample(self, t):
        t = np.asarray(t, float)
        s = np.zeros((t.size, 3))
        phases = self.phases_rad or (0.0,) * len(self.amplitudes_m)
        for a, f, ph in zip(self.amplitudes_m, self.frequencies_hz, phases):
            w = 2 * math.pi * f
            arg = w * t + ph
            s[:, 0] += a * np.sin(arg)
            s[:, 1] += a * w * np.cos(arg)
            s[:, 2] += -a * w * w * np.sin(arg)
        return _per_axis(s, self.n_axes, self.axes)


@dataclass
class Circle:
    """Circle of ``radius_mm`` at ``feed_mm_per_min``, starting at the origin going counter-clockwise.

    The centre is at (-R, 0) so the path starts where the table stands; the feed starts at t = 0.
    """

    radius_mm: float
    feed_mm_per_min: float
    n_axes: int = 2

    def sample(self, t):
        t = np.asarray(t, float)
        r = self.radius_mm * 1e-3
        w = self.feed_mm_per_min * 1e-3 / 60.0 / r
        out = np.zeros((t.size, 2, 3))
        c, s = np.cos(w * t), np.sin(w * t)
        out[:, 0] = np.stack([r * c - r, -r * w * s, -r * w * w * c], axis=1)
        out[:, 1] = np.stack([r * s, r * w * c, -r * w * w * s], axis=1)
        return out

    @property
    def period_s(self) -> float:
        """Time for one revolution (s)."""
        return 2 * math.pi * self.radius_mm / (self.feed_mm_per_min / 60.0)


@dataclass
class Polyline:
    """Straight segments through ``points_mm`` at constant ``feed_mm_per_min``.

    Velocity is piecewise constant; acceleration is zero (corners are velocity steps).
    After the last point the reference holds still.
    """

    points_mm: list[tuple[float, float]]
    feed_mm_per_min: float
    n_axes: int = 2
    _knots_s: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        p = np.asarray(self.points_mm, float) * 1e-3
        if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
            raise ValueError("points_mm must hold at least two (x, y) points")
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        if not (seg > 0).all():
            raise ValueError(f"points_mm: point {int(np.argmin(seg > 0)) + 1} repeats the one before it")
        self._p = p
        self._knots_s = np.concatenate([[0.0], np.cumsum(seg)]) / (self.feed_mm_per_min * 1e-3 / 60.0)

    @property
    def duration_s(self) -> float:
        """Time to traverse the path (s)."""
        return float(self._knots_s[-1])

    def sample(self, t):
        t = np.asarray(t, float)
        k = self._knots_s
        out = np.zeros((t.size, 2, 3))
        for a in range(2):
            out[:, a, 0] = np.interp(t, k, self._p[:, a])
        idx = np.clip(np.searchsorted(k, t, side="right") - 1, 0, len(k) - 2)
        vel = np.diff(self._p, axis=0) / np.diff(k)[:, None]
        moving = t < k[-1]
        out[:, :, 1] = np.where(moving[:, None], vel[idx], 0.0)
        return out


def square(side_mm: float, feed_mm_per_min: float) -> Polyline:
    """Square of ``side_mm`` starting and ending at the origin, counter-clockwise."""
    s = side_mm
    return Polyline([(0, 0), (s, 0), (s, s), (0, s), (0, 0)], feed_mm_per_min)
