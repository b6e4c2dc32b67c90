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
        d = int(round(steps))
        self.delay_ticks, self.split = divmod(d, self.substeps)
        self._fifo = np.zeros((self.delay_ticks + 2, self.n_axes))
        self._k = 0

    def reset(self) -> None:
        self._fifo[:] = 0.0
        self._k = 0

    def push(self, u: np.ndarray) -> np.ndarray:
        """Queue this tick's command; return the saturated command (V)."""
        if self.saturation_V is not None:
            u = np.clip(u, -self.saturation_V, self.saturation_V)
        self._fifo[self._k % len(self._fifo)] = u
        self._k += 1
        return u

    def segments(self):
        """Inputs applied during the tick just pushed: ``[(n_steps, u), ...]``.

        With a delay of D physics steps = ``delay_ticks`` * substeps + ``split``, the first
        ``split`` steps still see the older command.
        """
        k = self._k - 1
        n = len(self._fifo)
        newer = self._fifo[(k - self.delay_ticks) % n] if k >= self.delay_ticks else None
        older = self._fifo[(k - self.delay_ticks - 1) % n] if k >= self.delay_ticks + 1 else None
        zero = np.zeros(self.n_axes)
        segs = []
        if self.split:
            segs.append((self.split, zero if older is None else older))
        segs.append((self.substeps - self.split, zero if newer is None else newer))
        return segs


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
        self._quantize = bool((self.resolution_m > 0).any())
        self._noisy = bool((self.noise_std_m > 0).any())
        self.reset()

    def reset(self) -> None:
        self.rng = np.random.default_rng(self.seed)

    def measure(self, position_m: np.ndarray) -> np.ndarray:
        """Measured position (m) from true table positions (m)."""
        y = self.gains * position_m
        if self._quantize:
            res = np.where(self.resolution_m > 0, self.resolution_m, 1.0)
            y = np.where(self.resolution_m > 0, np.round(y / res) * res, y)
        if self._noisy:
            y = y + self.noise_std_m * self.rng.standard_normal(y.shape)
        return y


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
