"""The discrete-time control-block protocol every controller follows.

A block runs at a fixed sample period ``dt`` (s).  At each tick the runner calls
``step(ref, meas)`` with

- ``ref``: ndarray, shape (n_axes, 3): reference position (m), velocity (m/s), acceleration
  (m/s^2) of each axis the block serves;
- ``meas``: ndarray, shape (n_axes, 2): measured position (m) and velocity (m/s);

and the block returns ``u``: ndarray, shape (n_axes,), the control inputs (V).  A SISO block
serves one axis (``n_axes == 1``); a MIMO block serves several.  ``reset()`` clears the state.
Blocks never see the simulator: they only get these arrays.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class ControlBlock(Protocol):
    """Discrete-time controller: ``reset()`` and ``step(ref, meas) -> u`` at period ``dt``."""

    dt: float
    n_axes: int

    def reset(self) -> None: ...

    def step(self, ref: np.ndarray, meas: np.ndarray) -> np.ndarray: ...
