"""Step and ramp references on chosen axes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from twin.references.kinds import ReferenceSpecBase, per_axis, register
from twin.spec import axes_indices


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
        return per_axis(s, self.n_axes, self.axes)


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
        return per_axis(s, self.n_axes, self.axes)


class StepRef(ReferenceSpecBase):
    """step: amplitude_m at t0_s (default 0) on the listed axes (default all)."""

    type: Literal["step"]
    amplitude_m: float
    t0_s: float = 0.0
    axes: list[str] | None = None


class RampRef(ReferenceSpecBase):
    """ramp: rate_m_per_s from t0_s (default 0) on the listed axes (default all)."""

    type: Literal["ramp"]
    rate_m_per_s: float
    t0_s: float = 0.0
    axes: list[str] | None = None


register(
    "step",
    StepRef,
    lambda spec, ctx: Step(
        spec.amplitude_m, spec.t0_s, len(ctx.axis_names), axes_indices(spec.axes, ctx.axis_names, "reference.axes")
    ),
)
register(
    "ramp",
    RampRef,
    lambda spec, ctx: Ramp(
        spec.rate_m_per_s, spec.t0_s, len(ctx.axis_names), axes_indices(spec.axes, ctx.axis_names, "reference.axes")
    ),
)
