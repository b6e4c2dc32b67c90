"""Observer add-ons (``[controller.observer]``): the inverse-model disturbance observer, the
harmonic disturbance force observer (Maharof 2021) and both together."""

from __future__ import annotations

import numpy as np
from pydantic import Field

from controllers.blocks import Linear, Sum, harmonic_observer, inverse_model_observer
from controllers.lti import SisoTf
from controllers.registry import Context, Params, observer_kind


class InverseModelParams(Params):
    cutoff_hz: float = Field(100.0, description="corner of Q = 1/(tau s + 1)^order, tau = 1/(2 pi cutoff_hz), Hz")
    order: int = Field(2, strict=False, description="order of Q, at least the plant's relative degree")
    num: list[float] | None = Field(None, description="nominal model's numerator, m/V (default: the machine's model)")
    den: list[float] | None = Field(None, description="nominal model's denominator (with num)")
    delay_s: float | None = Field(None, ge=0.0, description="delay of u_prev, s (default: the machine's drive delay)")

    def plant(self, ctx: Context, axis: str) -> SisoTf:
        """The nominal model of ``axis``: ``num/den`` where given, else the machine's."""
        if self.num is not None and self.den is not None:
            return SisoTf(self.num, self.den)
        if (self.num is None) != (self.den is None):
            raise ValueError("num and den go together")
        plant = ctx.plants.get(axis)
        if plant is None:
            raise ValueError(f"no nominal model for axis {axis!r}: give num and den")
        return plant

    def delay(self, ctx: Context) -> float:
        """The delay of u_prev (s)."""
        return ctx.delay_s if self.delay_s is None else self.delay_s


class HarmonicParams(InverseModelParams):
    frequencies_hz: list[float] = Field([], description="the input disturbance's frequencies, Hz")
    bandwidth_hz: float = Field(5.0, gt=0.0, description="bandwidth of the internal model, Hz")


@observer_kind("inverse_model", InverseModelParams)
def build_inverse_model(p: InverseModelParams, ctx: Context) -> list:
    """Inverse-model disturbance observer d = Q P_n^-1 pos - Q z^-m u_prev, u_prev delayed to
    match the drive delay."""
    return [_inverse_model(p, ctx, a) for a in ctx.axes]


def _inverse_model(p: InverseModelParams, ctx: Context, a: str):
    return inverse_model_observer(
        p.plant(ctx, a),
        cutoff_hz=p.cutoff_hz,
        order=p.order,
        dt=ctx.dt,
        axis=a,
        method=ctx.method,
        name=f"observer.{a}",
        delay_s=p.delay(ctx),
    )


def _harmonic(p: HarmonicParams, ctx: Context, a: str, u_signal: str | None = None):
    return harmonic_observer(
        p.plant(ctx, a),
        frequencies_hz=p.frequencies_hz,
        bandwidth_hz=p.bandwidth_hz,
        dt=ctx.dt,
        axis=a,
        method=ctx.method,
        name=f"harmonic.{a}",
        delay_s=p.delay(ctx),
        cutoff_hz=p.cutoff_hz,
        order=p.order,
        u_signal=u_signal,
    )


@observer_kind("harmonic", HarmonicParams)
def build_harmonic(p: HarmonicParams, ctx: Context) -> list:
    """Harmonic disturbance force observer: the input disturbance's sinusoids at frequencies_hz,
    estimated from the inverse-model signal with an internal model of bandwidth_hz and
    predicted over the drive delay."""
    return [_harmonic(p, ctx, a) for a in ctx.axes]


@observer_kind("inverse_model_harmonic", HarmonicParams)
def build_inverse_model_harmonic(p: HarmonicParams, ctx: Context) -> list:
    """Inverse-model observer plus the harmonic observer on what it leaves: u = u_c - d_imbdo -
    d_harmonic."""
    out: list = []
    for a in ctx.axes:
        out.append(_inverse_model(p, ctx, a))
        # the harmonic observer compares the plant with u_prev + the inverse-model estimate of the
        # tick before (already in u_prev), so it estimates what that observer left
        previous, residual = f"harmonic.{a}:imbdo_prev.{a}", f"harmonic.{a}:u_residual.{a}"
        out += [
            Linear(
                np.zeros((1, 1)),
                np.ones((1, 1)),
                np.ones((1, 1)),
                np.zeros((1, 1)),
                (f"observer.{a}:d_hat.{a}",),
                (previous,),
                name=f"imbdo_prev.{a}",
            ),
            Sum((1.0, 1.0), (f"u_prev.{a}", previous), residual, name=f"residual.{a}"),
            _harmonic(p, ctx, a, residual),
        ]
    return out
