"""What the runner asks of a reference and of a disturbance, as typed protocols.

The runner tells them apart with ``isinstance`` against these protocols (``runtime_checkable``)
rather than by probing one attribute at a time; a class satisfies one by having its members,
without inheriting from it.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Reference(Protocol):
    """A reference trajectory of ``n_axes`` axes.

    ``sample(t)`` returns, at the times ``t`` (s), an array of shape (len(t), n_axes, 3): the
    position (m), velocity (m/s) and acceleration (m/s^2) of each axis.
    """

    n_axes: int

    def sample(self, t: np.ndarray) -> np.ndarray: ...


@runtime_checkable
class ProgramReference(Reference, Protocol):
    """A planned part program (:mod:`twin.references.gcode`): besides the samples, what it says of
    any time ``t`` (s): the program line, the programmed feed (mm/min), the tool's engagement
    with a stock (engaged angle in deg and axial depth in mm; empty without one) and the planned
    axes the machine has not (m); and its lines read (for the progress bar), cycle time (s) and
    line texts.  What is said of the whole program (its warnings, a stock's outlines, each
    line's chatter check) is not the reference's: see :class:`twin.outcome.PlannedProgram`."""

    n_lines: int

    @property
    def duration_s(self) -> float: ...

    @property
    def texts(self) -> dict[int, str]: ...

    def line_at(self, t: float) -> int: ...

    def lines_at(self, t: np.ndarray) -> np.ndarray: ...

    def feeds_at(self, t: np.ndarray) -> np.ndarray: ...

    def engagement_at(self, t: np.ndarray) -> np.ndarray: ...

    def extra_series(self, t: np.ndarray) -> dict[str, np.ndarray]: ...


@runtime_checkable
class InputDisturbance(Protocol):
    """A disturbance added to the drive input: ``input_V(t)`` (V), shape (len(t), n_axes)."""

    def input_V(self, t_s: np.ndarray) -> np.ndarray: ...


@runtime_checkable
class ForceModel(Protocol):
    """A force on the workpiece before each physics step, computed by a compiled kernel:
    ``kernel_arrays(machine)`` gives its kind, parameters and state
    (:func:`twin.machining.cutting.workpiece_forces`)."""

    def kernel_arrays(self, machine) -> tuple[int, np.ndarray, np.ndarray]: ...


#: What ``simulate`` accepts as a disturbance.
Disturbance = InputDisturbance | ForceModel
