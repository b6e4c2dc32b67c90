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
    with_feedforward,
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
    return each_axis(lambda p, c, a: error_feedback(tf, c.dt, axes=(a,), method=c.method, name=f"C.{a}"), None, ctx)


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
        return cascade(
            outer, inner, ctx.dt, axis=a, velocity_ref_ff=p.velocity_ref_ff, method=ctx.method, name=f"cascade.{a}"
        )

    return each_axis(one, p, ctx)


class ServoCascadeParams(Params):
    kp_pos: float = Field(gt=0.0, description="position loop gain, 1/s")
    kp_vel: float = Field(gt=0.0, description="velocity loop gain, V s/m")
    ti_vel_s: float = Field(0.0, ge=0.0, description="velocity loop integral time, s (0: no integral)")
    velocity_ff: float = Field(1.0, ge=0.0, le=1.0, description="share of the reference velocity fed forward")
    acceleration_ff: float = Field(0.0, ge=0.0, description="drive input per reference acceleration, V s^2/m")
    friction_ff: float = Field(0.0, ge=0.0, description="drive input per reference velocity (viscous), V s/m")
    notch_hz: float = Field(0.0, ge=0.0, description="notch centre on the velocity loop's output, Hz (0: none)")
    notch_depth_db: float = Field(20.0, gt=0.0, le=60.0, description="notch depth, dB")
    notch_width: float = Field(0.5, gt=0.0, le=2.0, description="notch pole damping ratio (its width)")
    lowpass_hz: float = Field(0.0, ge=0.0, description="second-order low-pass (damping 0.7) on it, Hz (0: none)")


def velocity_filter(notch_hz: float, depth_db: float, width: float, lowpass_hz: float) -> SisoTf:
    """The velocity loop's output filter: a notch (s^2 + 2 z_z w s + w^2)/(s^2 + 2 z_p w s + w^2),
    z_z = z_p 10^(-depth/20), and a low-pass w^2/(s^2 + 1.4 w s + w^2); 1 where both are 0."""
    num, den = np.array([1.0]), np.array([1.0])
    if notch_hz:
        w = 2 * np.pi * notch_hz
        zeta_zero = width * 10 ** (-depth_db / 20)
        num, den = np.polymul(num, [1.0, 2 * zeta_zero * w, w * w]), np.polymul(den, [1.0, 2 * width * w, w * w])
    if lowpass_hz:
        w = 2 * np.pi * lowpass_hz
        num, den = np.polymul(num, [w * w]), np.polymul(den, [1.0, 1.4 * w, w * w])
    return SisoTf(num, den)


@controller_kind("servo_cascade", ServoCascadeParams)
def build_servo_cascade(p: ServoCascadeParams, ctx: Context) -> Controller:
    """A drive's cascade as commissioning tools set it: position P, velocity PI with a notch or
    low-pass on its output, velocity, acceleration and viscous feedforward (twin tune writes it)."""

    def one(p, ctx, a):
        pi = pid_tf(p.kp_vel, p.kp_vel / p.ti_vel_s if p.ti_vel_s else 0.0)
        f = velocity_filter(p.notch_hz, p.notch_depth_db, p.notch_width, p.lowpass_hz)
        inner = SisoTf(np.polymul(pi.num, f.num), np.polymul(pi.den, f.den))
        loop = cascade(
            SisoTf((p.kp_pos,), (1.0,)),
            inner,
            ctx.dt,
            axis=a,
            velocity_ref_ff=p.velocity_ff,
            method=ctx.method,
            name=f"servo.{a}",
        )
        return with_feedforward(loop, p.friction_ff, p.acceleration_ff)

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
        lambda p, ctx, a: lure(
            SisoTf(p.num, p.den),
            p.nonlinearity,
            settings=settings,
            dt=ctx.dt,
            axis=a,
            method=ctx.method,
            name=f"lure.{a}",
        ),
        p,
        ctx,
    )


class RelayParams(Params):
    amplitude_V: float = Field(1.0, gt=0.0, description="relay output, +-V")
    hysteresis_m: float = Field(0.0, ge=0.0, description="the error band the relay switches outside, +-m")


@controller_kind("relay", RelayParams)
def build_relay(p: RelayParams, ctx: Context) -> Controller:
    """Relay with hysteresis on the error, for the relay tuning test."""
    return each_axis(
        lambda p, ctx, a: relay_feedback(p.amplitude_V, p.hysteresis_m, dt=ctx.dt, axis=a, name=f"relay.{a}"), p, ctx
    )


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
            block = lti_block(
                (block.A, block.B, block.C, block.D),
                ctx.dt,
                inputs=ins,
                outputs=outs,
                method=ctx.method,
                name=block.name,
            )
        blocks.append(block)
    return Controller(blocks, ctx.dt, "linear")
