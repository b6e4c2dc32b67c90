"""Disturbance signals added to the drive input (V), as the runner's ``input_V(t)`` hook.

The runner samples them once per chunk of ticks (vectorized numpy, the same arrays for the
compiled and the Python loop); they have no state, so a chunked evaluation equals a whole one.

Forces on the workpiece (cutting) are in :mod:`twin.machining.cutting`; sensor noise is the encoder's
(:class:`twin.sim.drive.Encoder`, seeded).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import Field, PositiveFloat

from twin.disturbances.kinds import DisturbanceSpecBase, register
from twin.errors import TwinInputError
from twin.spec import axes_indices


def _axis_mask(axes: tuple[int, ...] | None, n_axes: int) -> np.ndarray:
    """1.0 on the disturbed axes (all when ``axes`` is None), shape (n_axes,)."""
    if axes is None:
        return np.ones(n_axes)
    mask = np.zeros(n_axes)
    mask[list(axes)] = 1.0
    return mask


@dataclass(frozen=True)
class VoltageStep:
    """Input (voltage) disturbance: ``amplitude_V`` added from ``start_s`` on.

    Yadav 2020 (Figs. 12-13) perturbs the input voltage; its figure is lost in the extraction, so
    the shape (a step) and its size are the twin's choice, stated where used.

    Parameters
    ----------
    amplitude_V, start_s : float
    n_axes : int
    axes : tuple of int or None
        Disturbed axes (indices); None for all.
    """

    amplitude_V: float
    start_s: float
    n_axes: int = 1
    axes: tuple[int, ...] | None = None

    def __post_init__(self):
        if not np.isfinite(self.amplitude_V):
            raise TwinInputError("disturbance.amplitude_V", self.amplitude_V, "must be finite")
        if not self.start_s >= 0:
            raise TwinInputError("disturbance.start_s", self.start_s, "must be >= 0")

    def input_V(self, t_s: np.ndarray) -> np.ndarray:
        """Disturbance (V), shape (len(t_s), n_axes)."""
        on = (np.asarray(t_s) >= self.start_s).astype(float) * self.amplitude_V
        return on[:, None] * _axis_mask(self.axes, self.n_axes)


#: Most sines a harmonic input disturbance may sum: every chunk of ticks holds one column per sine.
MAX_INPUT_HARMONICS = 100


@dataclass(frozen=True)
class HarmonicInput:
    """Sum of sines added to the drive input (V): Maharof 2021's harmonic input disturbances.

    ``d(t) = sum_i A_i sin(2 pi f_i t + phase_i)``; Maharof 2021 uses one, two and three harmonics
    at 0.2, 0.5 and 0.8 Hz.  Its amplitudes are not in the extraction: they are the
    scenario's choice.

    Parameters
    ----------
    amplitudes_V, frequencies_hz : tuple of float
    phases_rad : tuple of float or None
        None draws each phase uniformly in [0, 2 pi) from ``seed``.
    n_axes : int
    axes : tuple of int or None
        Disturbed axes (indices); None for all.
    start_s : float
    seed : int
    """

    amplitudes_V: tuple[float, ...]
    frequencies_hz: tuple[float, ...]
    phases_rad: tuple[float, ...] | None = None
    n_axes: int = 1
    axes: tuple[int, ...] | None = None
    start_s: float = 0.0
    seed: int = 0

    def __post_init__(self):
        if len(self.amplitudes_V) != len(self.frequencies_hz) or not self.amplitudes_V:
            raise TwinInputError(
                "disturbance.frequencies_hz", list(self.frequencies_hz), "needs one entry per amplitude (at least one)"
            )
        if len(self.amplitudes_V) > MAX_INPUT_HARMONICS:
            raise TwinInputError(
                "disturbance.amplitudes_V", list(self.amplitudes_V), f"at most {MAX_INPUT_HARMONICS} harmonics"
            )
        if not all(math.isfinite(a) for a in self.amplitudes_V):
            raise TwinInputError("disturbance.amplitudes_V", list(self.amplitudes_V), "must be finite")
        if not all(f > 0 and math.isfinite(f) for f in self.frequencies_hz):
            raise TwinInputError("disturbance.frequencies_hz", list(self.frequencies_hz), "must be > 0")
        if self.phases_rad is not None and len(self.phases_rad) != len(self.amplitudes_V):
            raise TwinInputError("disturbance.phases_rad", list(self.phases_rad), "needs one entry per amplitude")
        if not self.start_s >= 0:
            raise TwinInputError("disturbance.start_s", self.start_s, "must be >= 0")

    def phases(self) -> np.ndarray:
        """The phases in use (rad): given, or drawn from ``seed``."""
        if self.phases_rad is not None:
            return np.asarray(self.phases_rad, float)
        return np.random.default_rng(self.seed).uniform(0.0, 2.0 * math.pi, len(self.amplitudes_V))

    def input_V(self, t_s: np.ndarray) -> np.ndarray:
        """Disturbance (V), shape (len(t_s), n_axes)."""
        t = np.asarray(t_s, float)[:, None]
        wave = (
            np.asarray(self.amplitudes_V) * np.sin(2 * math.pi * np.asarray(self.frequencies_hz) * t + self.phases())
        ).sum(axis=1)
        wave = np.where(t[:, 0] >= self.start_s, wave, 0.0)
        return wave[:, None] * _axis_mask(self.axes, self.n_axes)


class HarmonicInputSpec(DisturbanceSpecBase):
    """harmonic_input: a sum of sines on the drive input, V (HarmonicInput; Maharof 2021)."""

    type: Literal["harmonic_input"]
    amplitudes_V: list[float] = Field(max_length=MAX_INPUT_HARMONICS)
    frequencies_hz: list[PositiveFloat] = Field(max_length=MAX_INPUT_HARMONICS)
    phases_rad: list[float] | None = Field(
        None, max_length=MAX_INPUT_HARMONICS, description="None: drawn from the seed"
    )
    axes: list[str] | None = None
    start_s: float = Field(0.0, ge=0)
    seed: int | None = Field(None, ge=0)


class VoltageStepSpec(DisturbanceSpecBase):
    """voltage_step: a step on the drive input, V (VoltageStep; Yadav 2020)."""

    type: Literal["voltage_step"]
    amplitude_V: float
    start_s: float = Field(0.0, ge=0)
    axes: list[str] | None = None


def _harmonic_input_from(spec: HarmonicInputSpec, axis_names: list[str], seed: int, field: str) -> HarmonicInput:
    return HarmonicInput(
        tuple(spec.amplitudes_V),
        tuple(spec.frequencies_hz),
        tuple(spec.phases_rad) if spec.phases_rad is not None else None,
        len(axis_names),
        axes_indices(spec.axes, axis_names, f"{field}.axes"),
        spec.start_s,
        seed,
    )


def _voltage_step_from(spec: VoltageStepSpec, axis_names: list[str], seed: int, field: str) -> VoltageStep:
    return VoltageStep(
        spec.amplitude_V, spec.start_s, len(axis_names), axes_indices(spec.axes, axis_names, f"{field}.axes")
    )


register("harmonic_input", HarmonicInputSpec, _harmonic_input_from)
register("voltage_step", VoltageStepSpec, _voltage_step_from)
