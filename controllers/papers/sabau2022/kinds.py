"""Sabau 2022's designs (Sabau 2022) on the coupled_servo_xy axes: mm units in the design, SI on the bus."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from controllers.blocks import Controller, Linear, cascade, error_feedback, with_feedforward
from controllers.design.pid import pid_tf
from controllers.papers import sabau2022
from controllers.registry import Context, Params, controller_kind


class Sabau2022Params(Params):
    design: str = Field("pi_p_pole_placement", description="one of " + ", ".join(sabau2022.DESIGNS))
    feedforward: bool = Field(True, description="false drops the PI-P designs' reference feedforward")
    velocity_ff: bool = Field(
        False, description="true adds the drive's velocity feedforward ref_vel/K_M (the MC206X's VFF_GAIN)"
    )
    ku_V_per_mm: float | None = Field(
        None, gt=0.0, description="the ZN designs' ultimate gain, V/mm (default: the 10 ms-delay model's)"
    )
    pu_s: float | None = Field(None, gt=0.0, description="the ZN designs' ultimate period, s (with ku_V_per_mm)")


def _state_feedback_mimo(ctx: Context) -> Controller:
    if ctx.axes != ("x", "y"):
        raise ValueError(
            f"axes = {list(ctx.axes)}: the MIMO state feedback serves axes x and y together "
            "([controller], not [controllers.<axis>])"
        )
    gain, prefilter = sabau2022.mimo_pole_placement()
    feedthrough = sabau2022.MM_PER_M * np.hstack([prefilter, -gain[:, [1, 3]], -gain[:, [0, 2]]])
    inputs = ("ref.x", "ref.y", "pos.x", "pos.y", "vel.x", "vel.y")
    block = Linear(
        np.zeros((0, 0)),
        np.zeros((0, 6)),
        np.zeros((2, 0)),
        feedthrough,
        inputs,
        ("u.x", "u.y"),
        name="state_feedback_mimo",
    )
    return Controller([block], ctx.dt, "sabau2022")


def _one_axis(p: Sabau2022Params, ctx: Context, a: str) -> Controller:
    if a not in sabau2022.AXES:
        raise ValueError(f"axis {a!r}: Sabau 2022 models axes x and y")
    mm = sabau2022.MM_PER_M
    g = sabau2022.design_gains(a, p.design, p.ku_V_per_mm, p.pu_s)
    if g["form"] == "pid":
        tf = pid_tf(mm * g["kp"], mm * g["ki"], mm * g["kd"], g["tf_s"])
        return error_feedback(tf, ctx.dt, axes=(a,), method=ctx.method, name=f"sabau2022.{a}")
    if g["form"] == "fo_pi":
        A, B, C, D = sabau2022.fractional_pi_state_space(a)
        return error_feedback((A, B, mm * C, mm * D), ctx.dt, axes=(a,), method=ctx.method, name=f"sabau2022.{a}")
    return cascade(
        pid_tf(g["kp"], g["ki"], g["kd"], g["tf_s"]),
        pid_tf(mm * g["kv"]),
        ctx.dt,
        axis=a,
        velocity_ref_ff=0.0,
        method=ctx.method,
        name=f"sabau2022.{a}",
        position_ref_ff=g["position_ref_ff"] if p.feedforward else 0.0,
    )


@controller_kind("sabau2022", Sabau2022Params)
def build_sabau2022(p: Sabau2022Params, ctx: Context) -> Controller:
    """Sabau 2022's designs on the coupled_servo_xy axes (control_period_s = 1e-3): ZN and modified ZN
    P/PI/PID, cascades, state feedback (pole placement, LQR, LMI) and its PI-P forms, the
    fractional-order PI, the bee-colony cascade and the MIMO state feedback."""
    if p.design not in sabau2022.DESIGNS:
        raise ValueError(f"design = {p.design!r}: use one of {', '.join(sabau2022.DESIGNS)}")
    if (p.ku_V_per_mm is None) != (p.pu_s is None):
        raise ValueError("ku_V_per_mm and pu_s go together")
    if not math.isclose(ctx.dt, sabau2022.DT_S):
        raise ValueError(f"control_period_s = {ctx.dt:g}: Sabau 2022's designs are made for {sabau2022.DT_S:g} s")
    if p.design == "state_feedback_mimo":
        return _state_feedback_mimo(ctx)
    parts = [_one_axis(p, ctx, a) for a in ctx.axes]
    ctrl = Controller([b for c in parts for b in c.blocks], ctx.dt, "sabau2022")
    if p.velocity_ff:  # the drive's VFF_GAIN: u += ref_vel / K_M, K_M = K/a (V per mm/s -> V per m/s)
        gains = [sabau2022.MM_PER_M * sabau2022.MODEL[a][1] / sabau2022.MODEL[a][0] for a in ctx.axes]
        ctrl = with_feedforward(ctrl, gains, 0.0)
    return ctrl
