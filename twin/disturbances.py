"""Disturbance signals added to the drive input (V), as the runner's ``input_V(t)`` hook."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.errors import TwinInputError


@dataclass(frozen=True)
class VoltageStep:
    """Input (voltage) disturbance: ``amplitude_V`` added to every axis from ``start_s`` on.

    Seed 000 (Figs. 12-13) perturbs the input voltage; its figure is lost in the extraction, so
    the shape (a step) and its size are the twin's choice, stated where used.
    """

    amplitude_V: float
    start_s: float
    n_axes: int = 1

    def __post_init__(self):
        if not np.isfinite(self.amplitude_V):
            raise TwinInputError("disturbance.amplitude_V", self.amplitude_V, "must be finite")
        if not self.start_s >= 0:
            raise TwinInputError("disturbance.start_s", self.start_s, "must be >= 0")

    def input_V(self, t_s: np.ndarray) -> np.ndarray:
        """Disturbance (V), shape (len(t_s), n_axes)."""
        on = (np.asarray(t_s) >= self.start_s).astype(float) * self.amplitude_V
        return np.repeat(on[:, None], self.n_axes, axis=1)
