"""The generic controller kinds: any PID, transfer function, cascade, Lur'e loop, relay, sum or
state space, with gains in SI units (V per m of error, ...)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from controllers.blocks import (
    NONLINEARITIES,
    Controller,
    Linear,
    cascade,
    error_feedback,
    lti_block,
    lure,
    relay_feedback,
    sum_of,
)
from controllers.design.pid import pid_tf
from controllers.lti import SisoTf
from controllers.registry import Context, NoParams, Params, controller_kind


def each_axis(build_one, p, ctx: Context) -> Controller:
    """One controller ``build_one(p, ctx, axis)`` per served axis, joined into one."""
    parts = [build_one(p, ctx, a) for a in ctx.axes]
    return Controller([b for c in parts for b in c.blocks], ctx.dt, parts[0].name)


def error_feedback_each_axis(tf, ctx: Context) -> Controller:
    """The LTI controller ``tf`` on the error of each served axis."""
    return each_axis(lambda p, c, a: error_feedback(tf, c.dt, (a,), c.method, name=f"C.{a}"), None, ctx)


class PidParams(Params):
    kp: float = Field(0.0, description="proportional gain, V/m")
    ki: float = Field(0.0, description="integral gain, V/(m s)")
    kd: float = Field(0.0, description="derivative gain, V s/m")
    tf_s: float = Field(0.0, ge=0.0, description="derivative filter time constant, s")


@controller_kind("pid", PidParams)
def build_pid(p: PidParams, ctx: Context) -> Controller:
    """kp + ki/s + kd s/(tf_s s + 1) on the error of each axis."""
    return error_feedback_each_axis(pid_tf(p.kp, p.ki, p.kd, p.tf_s), ctx)


class TfParams(Params):
    num: list[float] = Field(description="numerator coefficients, highest power first, V/m")
    den: list[float] = Field(description="denominator coefficients, highest power first")


@controller_kind("tf", TfParams)
def build_tf(p: TfParams, ctx: Context) -> Controller:
    """Any C(s) = num/den on the error of each axis, V/m."""
    return error_feedback_each_axis(SisoTf(p.num, p.den), ctx)


class CascadeParams(Params):
    kp_pos: float = Field(0.0, description="position loop gain, 1/s")
    ki_pos: float = Field(0.0, description="position loop integral gain, 1/s^2")
    kp_vel: float = Field(0.0, description="velocity loop gain, V s/m")
    ki_vel: float = Field(0.0, description="velocity loop integral gain, V/m")
    velocity_ref_ff: float = Field(0.0, description="reference velocity fed into the velocity loop, 1 = all of it")


@controller_kind("cascade", CascadeParams)
def build_cascade(p: CascadeParams, ctx: Context) -> Controller:
    """Position P/PI around velocity P/PI: v_ref = (kp_pos + ki_pos/s) e + velocity_ref_ff ref_vel,
    u = (kp_vel + ki_vel/s)(v_ref - vel)."""

    def one(p, ctx, a):
        outer, inner = pid_tf(p.kp_pos, p.ki_pos), pid_tf(p.kp_vel, p.ki_vel)
        return cascade(outer, inner, ctx.dt, a, p.velocity_ref_ff, ctx.method, f"cascade.{a}")

    return each_axis(one, p, ctx)


class LureParams(Params):
    num: list[float] = Field(description="numerator of the linear part, V/m")
    den: list[float] = Field(description="denominator of the linear part")
    nonlinearity: str = Field(description="saturation, dead_zone or cosh_gain")
    limit: float | None = Field(None, description="saturation limit, m")
    width: float | None = Field(None, description="dead-zone half width, m")
    k: float | None = Field(None, description="cosh_gain's k, 1/m")
    e_max: float | None = Field(None, description="cosh_gain's clip of the error, m")


@controller_kind("lure", LureParams)
def build_lure(p: LureParams, ctx: Context) -> Controller:
    """Lur'e loop: u = num/den (V/m) of f(error), f the nonlinearity with its settings."""
    if p.nonlinearity not in NONLINEARITIES:
        raise ValueError(f"nonlinearity = {p.nonlinearity!r}: use one of {', '.join(NONLINEARITIES)}")
    keys = NONLINEARITIES[p.nonlinearity][1]
    settings = [getattr(p, k) for k in keys]
    if None in settings:
        raise ValueError(f"parameter {keys[settings.index(None)]!r} is needed by the {p.nonlinearity} nonlinearity")
    return each_axis(
        lambda p, ctx, a: lure(SisoTf(p.num, p.den), p.nonlinearity, settings, ctx.dt, a, ctx.method, f"lure.{a}"),
        p,
        ctx,
    )


class RelayParams(Params):
    amplitude_V: float = Field(1.0, gt=0.0, description="relay output, +-V")
    hysteresis_m: float = Field(0.0, ge=0.0, description="the error band the relay switches outside, +-m")


@controller_kind("relay", RelayParams)
def build_relay(p: RelayParams, ctx: Context) -> Controller:
    """Relay with hysteresis on the error, for the relay tuning test."""
    return each_axis(lambda p, ctx, a: relay_feedback(p.amplitude_V, p.hysteresis_m, ctx.dt, a, f"relay.{a}"), p, ctx)


@controller_kind("sum", NoParams)
def build_sum(p: NoParams, ctx: Context) -> Controller:
    """u = the sum of the parts' u: parts = [{ type = ... }, ...], each any kind."""
    if not ctx.parts:
        raise ValueError("a sum needs at least one part")
    return sum_of(ctx.parts, "sum")


Matrix = float | list[float] | list[list[float]]


class LinearParams(Params):
    A: Matrix | None = Field(None, description="state matrix (default: no state)")
    B: Matrix | None = Field(None, description="input matrix")
    C: Matrix | None = Field(None, description="output matrix")
    D: Matrix | None = Field(None, description="feedthrough, output units per input unit")
    inputs: list[str] = Field(["error"], description="input signals; a name without '.axis' is per axis")
    outputs: list[str] = Field(["u"], description="output signals; a name without '.axis' is per axis")
    domain: Literal["discrete", "continuous"] = Field(
        "discrete", description="discrete (at the control period) or continuous"
    )


def _qualify(names, axis):
    return [n if "." in n else f"{n}.{axis}" for n in names]


@controller_kind("linear", LinearParams)
def build_linear(p: LinearParams, ctx: Context) -> Controller:
    """Any state space A, B, C, D from named input signals to output signals."""
    a_mat, b_mat, c_mat, d_mat = (
        np.atleast_2d(np.asarray(np.zeros((0, 0)) if m is None else m, float)) for m in (p.A, p.B, p.C, p.D)
    )
    per_axis = not all("." in n for n in p.inputs + p.outputs)
    blocks = []
    for a in ctx.axes if per_axis else (None,):
        ins, outs = (_qualify(p.inputs, a), _qualify(p.outputs, a)) if a else (p.inputs, p.outputs)
        block = Linear(a_mat, b_mat, c_mat, d_mat, tuple(ins), tuple(outs), name=f"linear.{a}" if a else "linear")
        if p.domain == "continuous":
            block = lti_block((block.A, block.B, block.C, block.D), ctx.dt, ins, outs, ctx.method, block.name)
        blocks.append(block)
    return Controller(blocks, ctx.dt, "linear")
