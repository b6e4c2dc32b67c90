"""Identified X/Y servo axes with cross-coupling (``coupled_servo_xy``), Sabau 2022.

Source: Sabau (Morar) (2022): eqs. (1)-(5) omega_x/u_x =
1054/(s + 40.85), omega_y/u_y = 2188/(s + 87.81), position the integral of velocity; eq. (6)
adds H_wx_uy = 15 (u_y accelerates X) and H_wy_ux = 24.5 (u_x accelerates Y), entering the
velocity derivatives directly.  Units are not stated: u in V and positions in mm are assumed,
so the SI gains are 1.054 and 2.188 m/(V s^2).

Realization: each carriage has a (assumed) mass M_i; joint damping a_i M_i; the drive of axis
i acts on a fixed tendon over both slides with gain K_i M_i and a coefficient on the other
slide sized so that it gets the eq. (6) cross-acceleration.
"""

from __future__ import annotations

from controllers.lti import SisoTf
from twin.machines.base import (
    Axis,
    Machine,
    MotionLimits,
    Parameter,
    check_stacked_masses,
    coulomb_friction_parameters,
    register_machine,
    set_mass,
)

SOURCE = "Sabau (2022)"


def _boxed(value: float, unit: str, description: str, positive: bool = True) -> Parameter:
    """A model parameter with section 5.3's +-10 % uncertainty box."""
    return Parameter(value, unit, f"{description}; box +-10 %, section 5.3", (0.9 * value, 1.1 * value), positive)


@register_machine
class CoupledServoXY(Machine):
    name = "coupled_servo_xy"
    xml = "coupled_servo_xy/coupled_servo_xy.xml"
    summary = "Sabau 2022 identified X/Y axes 1054/(s+40.85), 2188/(s+87.81) with eq. (6) coupling"
    parameters = {
        "K_x": _boxed(1054.0, "mm/(V s^2)", f"K_Mx/T_Mx, eq. (1), {SOURCE}"),
        "a_x": _boxed(40.85, "1/s", f"1/T_Mx, eq. (1), {SOURCE}"),
        "K_y": _boxed(2188.0, "mm/(V s^2)", f"K_My/T_My, eq. (3), {SOURCE}"),
        "a_y": _boxed(87.81, "1/s", f"1/T_My, eq. (3), {SOURCE}"),
        "H_wx_uy": _boxed(15.0, "mm/(V s^2)", f"u_y to X acceleration, eq. (6), {SOURCE}", positive=False),
        "H_wy_ux": _boxed(24.5, "mm/(V s^2)", f"u_x to Y acceleration, eq. (6), {SOURCE}", positive=False),
        "m_x": Parameter(25.0, "kg", "mass moved by X, Y carriage included (assumed)"),
        "m_y": Parameter(10.0, "kg", "mass moved by Y, workpiece included (assumed)"),
        "m_workpiece": Parameter(2.0, "kg", "workpiece mass (assumed)"),
        **coulomb_friction_parameters(("x", "y")),
    }
    #: ours: Sabau 2022 gives no limits; 12 m/min, 2 m/s^2, 50 m/s^3 as a small 3-axis CNC
    motion_limits = {a: MotionLimits(0.2, 2.0, 50.0, "ours: a small 3-axis CNC") for a in ("x", "y")}
    axes = (Axis("x", "x_drive", "x_table"), Axis("y", "y_drive", "y_table"))

    def check(self, params):
        check_stacked_masses(params)

    def configure(self, spec, params):
        mx, my = params["m_x"], params["m_y"]
        set_mass(spec, "x_carriage", mx - my)
        set_mass(spec, "y_carriage", my - params["m_workpiece"])
        set_mass(spec, "workpiece", params["m_workpiece"])
        kx, ky = params["K_x"] * 1e-3, params["K_y"] * 1e-3
        spec.joint("x_table").damping = [params["a_x"] * mx, 0.0, 0.0]
        spec.joint("y_table").damping = [params["a_y"] * my, 0.0, 0.0]
        spec.actuator("x_drive").gainprm[0] = kx * mx
        spec.actuator("y_drive").gainprm[0] = ky * my
        spec.tendon("x_input").wrap_joint("y_table", params["H_wy_ux"] * 1e-3 * my / (kx * mx))
        spec.tendon("y_input").wrap_joint("x_table", params["H_wx_uy"] * 1e-3 * mx / (ky * my))

    def plant(self, params, model):
        dx = [1.0, params["a_x"], 0.0]
        dy = [1.0, params["a_y"], 0.0]
        return (
            (SisoTf((params["K_x"] * 1e-3,), dx), SisoTf((params["H_wx_uy"] * 1e-3,), dx)),
            (SisoTf((params["H_wy_ux"] * 1e-3,), dy), SisoTf((params["K_y"] * 1e-3,), dy)),
        )
