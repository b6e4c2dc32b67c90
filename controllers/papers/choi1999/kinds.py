"""Choi 1999's controllers (linear-motor XY table): the MIMO H-infinity loop-shaping controller
and its PID pair, both with ZPETC feedforward; designed in :mod:`controllers.papers.choi1999`
(python-control, cached) on first use."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field

from controllers.blocks import Controller, Sum, lti_block
from controllers.registry import Context, Params, controller_kind


class MimoParams(Params):
    zpetc: bool = Field(True, description="ZPETC feedforward on the reference preview")
    order: Literal["reduced", "full"] = Field(
        "reduced", description="balanced-truncated to order 4, or the full order 8"
    )


class Choi1999PidParams(Params):
    zpetc: bool = Field(True, description="ZPETC feedforward on the reference preview")
    order: Literal["reduced"] = Field("reduced", description="the PIDs are designed against the reduced MIMO loop")
    tuning: str = Field(
        "loop_at_input",
        description="loop_at_input: the crossover and phase margin of the MIMO loop broken at that input, "
        "integral corner a decade below; mimo_diagonal: the MIMO diagonal loop's crossover, kp = the MIMO "
        "controller's static gain",
    )
    ki_scale: float = Field(1.0, description="multiplies the integral gain, 0 to 1000")


def _build(kind: str, *, zpetc: bool, order: str, tuning: str, ki_scale: float, ctx: Context) -> Controller:
    import control

    from controllers.papers import choi1999

    if ctx.axes != ("x", "y"):
        raise ValueError(
            f"axes = {list(ctx.axes)}: Choi 1999's controllers serve axes x and y together "
            "([controller], not [controllers.<axis>])"
        )
    if not math.isclose(ctx.dt, choi1999.DT_S):
        raise ValueError(f"control_period_s = {ctx.dt:g}: Choi 1999's controllers are designed for {choi1999.DT_S:g} s")
    choi1999.check_pid_tuning(tuning, ki_scale)
    errors = [f"error.{a}" for a in ctx.axes]
    blocks = []
    if zpetc:
        errors = [f"zpetc:error.{a}" for a in ctx.axes]
        for a, (filt, _) in zip(ctx.axes, choi1999.zpetc_filters(kind, order, tuning, ki_scale)):
            taps = max(len(filt.num), len(filt.den))
            num, den = (np.pad(c, (0, taps - len(c))) for c in (filt.num, filt.den))
            blocks += [
                lti_block(
                    control.tf(num, den, ctx.dt),
                    ctx.dt,
                    inputs=[f"preview.{a}.{filt.preview}"],
                    outputs=[f"zpetc:ref.{a}"],
                    name=f"zpetc.{a}",
                ),
                Sum((1.0, -1.0), (f"zpetc:ref.{a}", f"pos.{a}"), f"zpetc:error.{a}", name=f"zpetc_error.{a}"),
            ]
    blocks.append(
        lti_block(
            choi1999.controller_si(kind, order, tuning, ki_scale),
            ctx.dt,
            inputs=errors,
            outputs=[f"u.{a}" for a in ctx.axes],
            method=ctx.method,
            name=f"choi1999_{kind}",
        )
    )
    return Controller(blocks, ctx.dt, f"choi1999_{kind}")


@controller_kind("choi1999_mimo", MimoParams)
def build_mimo(p: MimoParams, ctx: Context) -> Controller:
    """Choi 1999's MIMO H-infinity loop-shaping controller (Glover-McFarlane, Ws = diag(990, 660)
    (s+110)/(s+1500), positions in mm) on axes x and y together."""
    defaults = Choi1999PidParams()  # the MIMO design does not depend on the PID's tuning
    return _build("mimo", zpetc=p.zpetc, order=p.order, tuning=defaults.tuning, ki_scale=defaults.ki_scale, ctx=ctx)


@controller_kind("choi1999_pid", Choi1999PidParams)
def build_pid(p: Choi1999PidParams, ctx: Context) -> Controller:
    """A PID per axis for Choi 1999's SISO comparison, designed here (the paper gives no gains)."""
    return _build("pid", zpetc=p.zpetc, order=p.order, tuning=p.tuning, ki_scale=p.ki_scale, ctx=ctx)
