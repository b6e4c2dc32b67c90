"""Sum-of-sines reference on chosen axes."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import Field, PositiveFloat

from twin.references.kinds import ReferenceContext, ReferenceSpecBase, per_axis, register
from twin.spec import axes_indices

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
        return per_axis(s, self.n_axes, self.axes)


class SinesRef(ReferenceSpecBase):
    """sines: amplitudes_m at frequencies_hz (phases_rad, default 0) on the listed axes (default all)."""

    type: Literal["sines"]
    amplitudes_m: list[float] = Field(max_length=MAX_SINES)
    frequencies_hz: list[PositiveFloat] = Field(max_length=MAX_SINES)
    phases_rad: list[float] | None = Field(None, max_length=MAX_SINES)
    axes: list[str] | None = None


def build(spec: SinesRef, ctx: ReferenceContext) -> SumOfSines:
    """The sum of sines; amplitudes and frequencies must pair up."""
    from twin.errors import TwinInputError

    if len(spec.amplitudes_m) != len(spec.frequencies_hz):
        raise TwinInputError("reference.frequencies_hz", spec.frequencies_hz, "needs as many entries as amplitudes_m")
    return SumOfSines(
        tuple(spec.amplitudes_m),
        tuple(spec.frequencies_hz),
        tuple(spec.phases_rad) if spec.phases_rad else None,
        len(ctx.axis_names),
        axes_indices(spec.axes, ctx.axis_names, "reference.axes"),
    )


register("sines", SinesRef, build)
