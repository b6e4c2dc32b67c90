"""Seed 001's designs (Sabau 2022) on the sabau_xy axes: mm units in the design, SI on the bus."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from controllers.blocks import Controller, Linear, cascade, error_feedback, with_feedforward
from controllers.design.pid import pid_tf
from controllers.papers import seed001
from controllers.registry import Context, Params, controller_kind


class Seed001Params(Params):
    design: str = Field("pi_p_pole_placement", description="one of " + ", ".join(seed001.DESIGNS))
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
    gain, prefilter = seed001.mimo_pole_placement()
    feedthrough = seed001.MM_PER_M * np.hstack([prefilter, -gain[:, [1, 3]], -gain[:, [0, 2]]])
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
    return Controller([block], ctx.dt, "seed001")


def _one_axis(p: Seed001Params, ctx: Context, a: str) -> Controller:
    if a not in seed001.AXES:
        raise ValueError(f"axis {a!r}: seed 001 models axes x and y")
    mm = seed001.MM_PER_M
    g = seed001.design_gains(a, p.design, p.ku_V_per_mm, p.pu_s)
    if g["form"] == "pid":
        tf = pid_tf(mm * g["kp"], mm * g["ki"], mm * g["kd"], g["tf_s"])
        return error_feedback(tf, ctx.dt, (a,), ctx.method, name=f"seed001.{a}")
    if g["form"] == "fo_pi":
        A, B, C, D = seed001.fractional_pi_state_space(a)
        return error_feedback((A, B, mm * C, mm * D), ctx.dt, (a,), ctx.method, name=f"seed001.{a}")
    return cascade(
        pid_tf(g["kp"], g["ki"], g["kd"], g["tf_s"]),
        pid_tf(mm * g["kv"]),
        ctx.dt,
        a,
        0.0,
        ctx.method,
        f"seed001.{a}",
        position_ref_ff=g["position_ref_ff"] if p.feedforward else 0.0,
    )


@controller_kind("seed001", Seed001Params)
def build_seed001(p: Seed001Params, ctx: Context) -> Controller:
    """Seed 001's designs on the sabau_xy axes (control_period_s = 1e-3): ZN and modified ZN
    P/PI/PID, cascades, state feedback (pole placement, LQR, LMI) and its PI-P forms, the
    fractional-order PI, the bee-colony cascade and the MIMO state feedback."""
    if p.design not in seed001.DESIGNS:
        raise ValueError(f"design = {p.design!r}: use one of {', '.join(seed001.DESIGNS)}")
    if (p.ku_V_per_mm is None) != (p.pu_s is None):
        raise ValueError("ku_V_per_mm and pu_s go together")
    if not math.isclose(ctx.dt, seed001.DT_S):
        raise ValueError(f"control_period_s = {ctx.dt:g}: seed 001's designs are made for {seed001.DT_S:g} s")
    if p.design == "state_feedback_mimo":
        return _state_feedback_mimo(ctx)
    parts = [_one_axis(p, ctx, a) for a in ctx.axes]
    ctrl = Controller([b for c in parts for b in c.blocks], ctx.dt, "seed001")
    if p.velocity_ff:  # the drive's VFF_GAIN: u += ref_vel / K_M, K_M = K/a (V per mm/s -> V per m/s)
        gains = [seed001.MM_PER_M * seed001.MODEL[a][1] / seed001.MODEL[a][0] for a in ctx.axes]
        ctrl = with_feedforward(ctrl, gains, 0.0)
    return ctrl
