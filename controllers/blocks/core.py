"""The block kinds and the controller that wires them to the signal bus.

Each block names the bus signals it reads (``inputs``) and writes (``outputs``); see
:mod:`controllers.blocks.signals` for the loop's signals.  The arithmetic of every kind is a
numba kernel in :mod:`controllers.kernels`, which the compiled loop and the Python loop both
call.  A block holds no run state: the state lives in the controller's compiled
:class:`~controllers.blocks.program.BlockProgram`, so a run (or a batch of runs) owns it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from controllers import kernels

#: Static nonlinearities by name: (kernel code, parameter names).
NONLINEARITIES = {
    "saturation": (kernels.NL_SATURATION, ("limit",)),
    "dead_zone": (kernels.NL_DEAD_ZONE, ("width",)),
    "cosh_gain": (kernels.NL_COSH_GAIN, ("k", "e_max")),
    "relay": (kernels.NL_RELAY, ("amplitude",)),
}


def _names(values) -> tuple[str, ...]:
    return tuple(str(v) for v in values)


@dataclass
class Linear:
    """Discrete state space ``y = C x + D v; x <- A x + B v`` from ``inputs`` v to ``outputs`` y.

    Matrices of shapes (n, n), (n, n_in), (n_out, n), (n_out, n_in); units are those of the
    signals (for example V per m from ``error.x`` to ``u.x``).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    name: str = "linear"
    kind: int = field(default=kernels.LINEAR, init=False)

    def __post_init__(self):
        self.inputs, self.outputs = _names(self.inputs), _names(self.outputs)
        self.A, self.B, self.C, self.D = (np.atleast_2d(np.asarray(m, float)) for m in (self.A, self.B, self.C, self.D))
        n, ni, no = self.A.shape[0], len(self.inputs), len(self.outputs)
        if n == 0:
            self.A, self.B, self.C = np.zeros((0, 0)), np.zeros((0, ni)), np.zeros((no, 0))
        want = {"A": (n, n), "B": (n, ni), "C": (no, n), "D": (no, ni)}
        for key, shape in want.items():
            if getattr(self, key).shape != shape:
                raise ValueError(
                    f"block {self.name!r}: {key} has shape {getattr(self, key).shape}, "
                    f"needs {shape} for {ni} inputs, {no} outputs and order {n}"
                )
            if not np.isfinite(getattr(self, key)).all():
                raise ValueError(f"block {self.name!r}: {key} has non-finite entries")

    @property
    def n_state(self) -> int:
        return self.A.shape[0]

    def params(self) -> np.ndarray:
        return np.concatenate([m.ravel() for m in (self.A, self.B, self.C, self.D)])


@dataclass
class Sum:
    """``output = sum_j weights[j] * inputs[j]``."""

    weights: tuple[float, ...]
    inputs: tuple[str, ...]
    output: str
    name: str = "sum"
    kind: int = field(default=kernels.SUM, init=False)
    n_state: int = field(default=0, init=False)

    def __post_init__(self):
        self.inputs = _names(self.inputs)
        self.weights = tuple(float(w) for w in self.weights)
        if len(self.weights) != len(self.inputs) or not self.inputs:
            raise ValueError(f"block {self.name!r}: needs one weight per input (at least one)")

    @property
    def outputs(self) -> tuple[str, ...]:
        return (self.output,)

    def params(self) -> np.ndarray:
        return np.array(self.weights, float)


@dataclass
class Static:
    """Elementwise static nonlinearity, ``outputs[i] = f(inputs[i])``; ``nonlinearity`` is a key
    of :data:`NONLINEARITIES` and ``settings`` its parameters in that order."""

    nonlinearity: str
    settings: tuple[float, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    name: str = "static"
    kind: int = field(default=kernels.STATIC, init=False)
    n_state: int = field(default=0, init=False)

    def __post_init__(self):
        self.inputs, self.outputs = _names(self.inputs), _names(self.outputs)
        if self.nonlinearity not in NONLINEARITIES:
            raise ValueError(
                f"block {self.name!r}: nonlinearity {self.nonlinearity!r} is not one of {', '.join(NONLINEARITIES)}"
            )
        names = NONLINEARITIES[self.nonlinearity][1]
        self.settings = tuple(float(p) for p in self.settings)
        if len(self.settings) != len(names) or not all(np.isfinite(self.settings)) or min(self.settings) < 0:
            raise ValueError(
                f"block {self.name!r}: {self.nonlinearity} takes {', '.join(names)} "
                f"(finite, >= 0), got {list(self.settings)}"
            )
        if len(self.inputs) != len(self.outputs):
            raise ValueError(f"block {self.name!r}: needs as many outputs as inputs")

    def params(self) -> np.ndarray:
        """``[code, p1, p2]``: the kernel reads two settings, the unused one is 0."""
        return np.array([NONLINEARITIES[self.nonlinearity][0], *self.settings, 0.0, 0.0][:3], float)


@dataclass
class Sequence:
    """Plays ``values[k]`` at tick k (zero after the end), ignoring every measurement.

    ``values``: ndarray, shape (n_ticks, len(outputs)), in the outputs' unit (V for ``u.<a>``).
    """

    values: np.ndarray
    outputs: tuple[str, ...]
    name: str = "open_loop"
    kind: int = field(default=kernels.SEQUENCE, init=False)
    n_state: int = field(default=0, init=False)

    def __post_init__(self):
        self.outputs = _names(self.outputs)
        self.values = np.atleast_2d(np.asarray(self.values, float))
        if self.values.shape[1] != len(self.outputs):
            raise ValueError(
                f"block {self.name!r}: values have {self.values.shape[1]} columns for {len(self.outputs)} outputs"
            )

    @property
    def inputs(self) -> tuple[str, ...]:
        return ("tick",)

    def params(self) -> np.ndarray:
        return self.values.ravel()


@runtime_checkable
class PythonBlock(Protocol):
    """A block written in Python, for experiments: only the Python loop runs it.

    ``step(values)`` gets the current values of ``inputs`` (ndarray) and returns those of
    ``outputs``; ``reset()`` clears its own state before a run.
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    name: str

    def reset(self) -> None: ...

    def step(self, values: np.ndarray) -> np.ndarray: ...


@dataclass
class Controller:
    """Blocks run in order at period ``dt`` (s); together they write ``u.<axis>`` (V) for the
    axes they drive.  A block may read what an earlier block wrote in the same tick."""

    blocks: list
    dt: float
    name: str = "controller"

    def __post_init__(self):
        if not self.dt > 0:
            raise ValueError(f"controller {self.name!r}: dt = {self.dt!r} must be > 0")

    @property
    def inputs(self) -> list[str]:
        """Every signal its blocks read, in order (repeats included)."""
        return [s for b in self.blocks for s in b.inputs]

    @property
    def outputs(self) -> list[str]:
        """Every signal its blocks write, in order."""
        return [s for b in self.blocks for s in b.outputs]

    @property
    def drives(self) -> list[str]:
        """The axes it drives (its ``u.<axis>`` outputs)."""
        return [s.split(".", 1)[1] for s in self.outputs if s.startswith("u.")]

    @property
    def compiled(self) -> bool:
        """Whether every block has a compiled kernel (no :class:`PythonBlock`)."""
        return all(hasattr(b, "kind") for b in self.blocks)
