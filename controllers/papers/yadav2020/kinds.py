"""Yadav 2020's controllers (Yadav, Pathak, Gaur 2020) as printed, on the error of each axis."""

from __future__ import annotations

from controllers.kinds.generic import error_feedback_each_axis
from controllers.papers import yadav2020
from controllers.registry import Context, NoParams, controller_kind


@controller_kind("yadav2020_robust_pi", NoParams)
def build_robust_pi(p: NoParams, ctx: Context):
    """Robust PI 38.33 + 45.65/s (V/m), Yadav 2020 eqs. (18)-(19)."""
    return error_feedback_each_axis(yadav2020.ROBUST_PI, ctx)


@controller_kind("yadav2020_imc", NoParams)
def build_imc(p: NoParams, ctx: Context):
    """IMC (0.21 s + 2)/(s + 2), Yadav 2020 eq. (23)."""
    return error_feedback_each_axis(yadav2020.IMC, ctx)


@controller_kind("yadav2020_hinf", NoParams)
def build_hinf(p: NoParams, ctx: Context):
    """Full 4th-order H-infinity, Yadav 2020 eq. (28)."""
    return error_feedback_each_axis(yadav2020.HINF, ctx)


@controller_kind("yadav2020_hinf_reduced", NoParams)
def build_hinf_reduced(p: NoParams, ctx: Context):
    """Reduced H-infinity 20.97/(s + 5.5), Yadav 2020 eq. (29)."""
    return error_feedback_each_axis(yadav2020.HINF_REDUCED, ctx)
