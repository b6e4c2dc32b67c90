"""Anang 2017's controllers (Anang et al.): the eq. (6) PID and the nonlinear PID of eqs. (6)-(8)."""

from __future__ import annotations

from pydantic import Field

from controllers.blocks import lure
from controllers.kinds.generic import each_axis, error_feedback_each_axis
from controllers.papers import anang2017
from controllers.registry import Context, Params, controller_kind


class Anang2017PidParams(Params):
    tf_s: float = Field(1e-4, gt=0.0, description="derivative filter time constant, s (ours: the paper gives none)")


@controller_kind("anang2017_pid", Anang2017PidParams)
def build_pid(p: Anang2017PidParams, ctx: Context):
    """PID 0.8998 + 0.005155 s + 0.0006077/s (V/mm), Anang 2017 eq. (6), on each axis."""
    return error_feedback_each_axis(anang2017.pid(p.tf_s), ctx)


class NpidParams(Anang2017PidParams):
    ko_per_mm: float = Field(anang2017.KO_PER_MM, gt=0.0, description="KO of Ke(e) = cosh(KO e), 1/mm")
    e_max_mm: float = Field(anang2017.E_MAX_MM, gt=0.0, description="the error is clipped at +-e_max, mm")


@controller_kind("anang2017_npid", NpidParams)
def build_npid(p: NpidParams, ctx: Context):
    """Nonlinear PID, Anang 2017 eqs. (6)-(8): the eq. (6) PID behind Ke(e) = cosh(KO e), e clipped
    at e_max."""
    settings = (p.ko_per_mm * 1e3, p.e_max_mm * 1e-3)
    return each_axis(
        lambda p, ctx, a: lure(
            anang2017.pid(p.tf_s),
            "cosh_gain",
            settings=settings,
            dt=ctx.dt,
            axis=a,
            method=ctx.method,
            name=f"npid.{a}",
        ),
        p,
        ctx,
    )
