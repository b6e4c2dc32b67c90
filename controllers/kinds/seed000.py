"""Seed 000's controllers (Yadav, Pathak, Gaur 2020) as printed, on the error of each axis."""

from __future__ import annotations

from controllers.kinds.generic import error_feedback_each_axis
from controllers.papers import seed000
from controllers.registry import Context, NoParams, controller_kind


@controller_kind("seed000_robust_pi", NoParams)
def build_robust_pi(p: NoParams, ctx: Context):
    """Robust PI 38.33 + 45.65/s (V/m), seed 000 eqs. (18)-(19)."""
    return error_feedback_each_axis(seed000.ROBUST_PI, ctx)


@controller_kind("seed000_imc", NoParams)
def build_imc(p: NoParams, ctx: Context):
    """IMC (0.21 s + 2)/(s + 2), seed 000 eq. (23)."""
    return error_feedback_each_axis(seed000.IMC, ctx)


@controller_kind("seed000_hinf", NoParams)
def build_hinf(p: NoParams, ctx: Context):
    """Full 4th-order H-infinity, seed 000 eq. (28)."""
    return error_feedback_each_axis(seed000.HINF, ctx)


@controller_kind("seed000_hinf_reduced", NoParams)
def build_hinf_reduced(p: NoParams, ctx: Context):
    """Reduced H-infinity 20.97/(s + 5.5), seed 000 eq. (29)."""
    return error_feedback_each_axis(seed000.HINF_REDUCED, ctx)
