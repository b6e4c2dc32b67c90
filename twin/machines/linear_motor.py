"""Linear-motor XY table (``linear_motor_xy``), Choi 1999.

Source: Choi, Hong, Kim, Kim (1999): eq. (1)
m_i v_i' + b_i v_i + F_coul,i sign(v_i) = k_i u_i, Table 1 (m_x 52.3 kg, m_y 17 kg,
b_x 193.5, b_y 36 N s/m with their uncertainty).  The Y carriage rides on the X carriage, so
m_x is the whole mass moved by X.  Input gains k_i are not in the paper: 98.2 N/V is the
Anorad LEB-S-8 peak force (982 N) at a +-10 V command (assumption).  Coulomb friction is not
quantified in the paper: 0 N by default, set per scenario.
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
    diagonal_plant,
    register_machine,
    set_mass,
)

SOURCE = "Choi et al. (1999)"


@register_machine
class LinearMotorXY(Machine):
    name = "linear_motor_xy"
    xml = "linear_motor_xy/linear_motor_xy.xml"
    summary = "Choi 1999 linear-motor XY table, m_x 52.3 kg, m_y 17 kg (Y on X), 1/2 um encoders"
    parameters = {
        "m_x": Parameter(
            52.3, "kg", f"mass moved by X (X + Y carriages + workpiece), {SOURCE} Table 1", (52.3 * 0.7, 52.3 * 1.3)
        ),
        "m_y": Parameter(
            17.0, "kg", f"mass moved by Y (Y carriage + workpiece), {SOURCE} Table 1", (17.0 * 0.6, 17.0 * 1.4)
        ),
        "b_x": Parameter(193.5, "N s/m", f"viscous damping X, {SOURCE} Table 1", (154.8, 232.2)),
        "b_y": Parameter(36.0, "N s/m", f"viscous damping Y, {SOURCE} Table 1", (28.8, 43.2)),
        "k_x": Parameter(98.2, "N/V", "input gain X: 982 N peak force at 10 V (assumed)"),
        "k_y": Parameter(98.2, "N/V", "input gain Y: 982 N peak force at 10 V (assumed)"),
        **coulomb_friction_parameters(("x", "y"), f"eq. (1); no value in {SOURCE}"),
        "m_workpiece": Parameter(2.0, "kg", "workpiece mass, part of m_y (assumed)"),
    }
    #: Choi 1999: the LEB-S-8's peak force 982 N over the moving masses (52.3 kg on X, 17 kg on Y);
    #: velocity and jerk ours (1 m/s, and the jerk that reaches the peak acceleration in 10 ms)
    motion_limits = {
        "x": MotionLimits(1.0, 982.0 / 52.3, 100 * 982.0 / 52.3, "Choi 1999: peak force 982 N / 52.3 kg; v, j ours"),
        "y": MotionLimits(1.0, 982.0 / 17.0, 100 * 982.0 / 17.0, "Choi 1999: peak force 982 N / 17 kg; v, j ours"),
    }
    axes = (Axis("x", "x_drive", "x_table"), Axis("y", "y_drive", "y_table"))

    def check(self, params):
        check_stacked_masses(params)

    def configure(self, spec, params):
        set_mass(spec, "x_carriage", params["m_x"] - params["m_y"])
        set_mass(spec, "y_carriage", params["m_y"] - params["m_workpiece"])
        set_mass(spec, "workpiece", params["m_workpiece"])
        for a in ("x", "y"):
            joint = spec.joint(f"{a}_table")
            joint.damping = [params[f"b_{a}"], 0.0, 0.0]
            spec.actuator(f"{a}_drive").gainprm[0] = params[f"k_{a}"]

    def plant(self, params, model):
        return diagonal_plant(
            [SisoTf((params[f"k_{a}"],), (params[f"m_{a}"], params[f"b_{a}"], 0.0)) for a in ("x", "y")]
        )
