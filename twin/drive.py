"""Drive and sensor models between the controller and MuJoCo.

Drive: saturation of the control input (V), an input disturbance (V) and a transport delay
realized at the physics timestep (a whole number of steps). Sensor: encoder quantization
(resolution in m) and Gaussian measurement noise from a seeded generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.errors import TwinInputError


@dataclass
class Drive:
    """Saturation and transport delay between controller and actuator.

    The input applied at physics step ``j`` (counted from the start of the run) is the
    saturated command of tick ``(j - delay_steps) // substeps``, or zero before the first
    delayed command arrives; a delay that is not a whole number of ticks falls inside one.

    Parameters
    ----------
    n_axes : int
    substeps : int
        Physics steps per control period.
    timestep_s : float
        Physics timestep (s).
    delay_s : float
        Transport delay (s); rounded to whole physics steps (must be within 1e-9 s of one).
    saturation_V : float or None
        Symmetric limit on the applied input (V); None for none.
    """

    n_axes: int
    substeps: int
    timestep_s: float
    delay_s: float = 0.0
    saturation_V: float | None = None

    def __post_init__(self):
        steps = self.delay_s / self.timestep_s
        if self.delay_s < 0 or abs(steps - round(steps)) * self.timestep_s > 1e-9:
            raise TwinInputError("drive.delay_s", self.delay_s,
                                 f"must be >= 0 and a whole multiple of the timestep {self.timestep_s:g} s")
        if self.saturation_V is not None and self.saturation_V <= 0:
            raise TwinInputError("drive.saturation_V", self.saturation_V, "must be > 0")
        self.delay_steps = int(round(steps))
        self.delay_ticks, self.split = divmod(self.delay_steps, self.substeps)

    @property
    def limit_V(self) -> float:
        """Saturation limit (V); ``inf`` when there is none."""
        return math.inf if self.saturation_V is None else float(self.saturation_V)

    def saturate(self, u: np.ndarray) -> np.ndarray:
        """Clip a command to the saturation limit (V)."""
        return np.clip(u, -self.limit_V, self.limit_V)

    def segments(self, k: int) -> list[tuple[int, int]]:
        """Physics steps of tick ``k`` as ``[(n_steps, source_tick), ...]``.

        ``source_tick`` is the tick whose command acts during those steps, -1 for none yet:
        the first ``split`` steps still see the older command.
        """
        newer = k - self.delay_ticks
        segs = [(self.split, newer - 1)] if self.split else []
        segs.append((self.substeps - self.split, newer))
        return [(n, src if src >= 0 else -1) for n, src in segs]


@dataclass
class Encoder:
    """Quantized, noisy position measurement.

    Parameters
    ----------
    resolution_m : ndarray, shape (n_axes,)
        Encoder resolution (m); 0 for ideal.
    noise_std_m : ndarray, shape (n_axes,)
        Standard deviation of additive Gaussian noise (m).
    gains : ndarray, shape (n_axes,)
        Sensor gain (the machine's H1).
    seed : int
        Seed of the noise generator.
    """

    resolution_m: np.ndarray
    noise_std_m: np.ndarray
    gains: np.ndarray
    seed: int = 0

    def __post_init__(self):
        for name in ("resolution_m", "noise_std_m"):
            arr = np.asarray(getattr(self, name), float)
            if (arr < 0).any() or not np.isfinite(arr).all():
                raise TwinInputError(f"sensors.{name}", arr.tolist(), "must be finite and >= 0")
            setattr(self, name, arr)
        self.gains = np.asarray(self.gains, float)

    def noise_m(self, n_ticks: int) -> np.ndarray:
        """The run's measurement noise (m), shape (n_ticks, n_axes), drawn from ``seed``."""
        draws = np.random.default_rng(self.seed).standard_normal((n_ticks, len(self.gains)))
        return draws * self.noise_std_m

    def measure(self, position_m: np.ndarray, noise_m: np.ndarray) -> np.ndarray:
        """Measured position (m) from true table positions (m) and this tick's noise (m)."""
        y = self.gains * position_m
        quantized = np.rint(y / np.where(self.resolution_m > 0, self.resolution_m, 1.0)) * self.resolution_m
        return np.where(self.resolution_m > 0, quantized, y) + noise_m


def substeps_per_tick(control_period_s: float, timestep_s: float) -> int:
    """Whole number of physics steps per control period.

    Raises
    ------
    TwinInputError
        If the control period is not a whole multiple of the timestep.
    """
    if timestep_s <= 0 or not math.isfinite(timestep_s):
        raise TwinInputError("timestep_s", timestep_s, "must be > 0")
    ratio = control_period_s / timestep_s
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-6:
        raise TwinInputError("control_period_s", control_period_s,
                             f"must be a whole multiple of timestep_s = {timestep_s:g} s")
    return int(n)
