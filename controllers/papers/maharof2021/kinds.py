"""Maharof 2021's cascade (Googol thesis), designed on the machine's model for the thesis's margins."""

from __future__ import annotations

from pydantic import Field

from controllers.blocks import cascade
from controllers.design.pid import pid_tf
from controllers.kinds.generic import each_axis
from controllers.papers import maharof2021
from controllers.registry import Context, Params, controller_kind


class Maharof2021CascadeParams(Params):
    velocity_ref_ff: float = Field(
        0.0, ge=0.0, le=2.0, description="reference velocity fed into the velocity loop (ours; the thesis states none)"
    )


@controller_kind("maharof2021_cascade", Maharof2021CascadeParams)
def build_cascade(p: Maharof2021CascadeParams, ctx: Context):
    """Maharof 2021's cascade: velocity PI for GM 9.37 dB and PM 56.4 deg, position P for PM 67.1 deg
    (thesis Figs. 4.3, 4.7), designed on the machine's model with its delay and the encoder's
    backward-difference velocity."""

    def one(p, ctx, a):
        if a not in ctx.plants:
            raise ValueError(f"no model of axis {a!r} to design the cascade on")
        gains = maharof2021.design_cascade(ctx.plants[a], ctx.delay_s, ctx.dt)
        outer, inner = pid_tf(gains["kp_pos"]), pid_tf(gains["kp_vel"], gains["ki_vel"])
        return cascade(
            outer, inner, ctx.dt, axis=a, velocity_ref_ff=p.velocity_ref_ff, method=ctx.method, name=f"cascade.{a}"
        )

    return each_axis(one, p, ctx)
