"""Googol Tech XY ball-screw table (``googol_xy``), Anang 2017 and Maharof 2021.

Source: Anang et al. eq. (1): G(s) = 78020/(s^2 + 163 s + 193.3)
with a 0.0012 s delay, identified from measured FRFs on the X axis; Maharof 2021 uses the
same table.  Units: input in V, position in mm (the UTeM papers' convention; assumed, the
extraction states none), i.e. 78.02 m/(V s^2) in SI.

The model is identified, not physical, so the mechanism (rotor, screw, 5 mm lead, table and
workpiece masses) is assumed and the identified coefficients are realized by the drive:
actuator gain g = b0 p M and affine bias (amplifier velocity and position feedback)
-a1 p^2 M theta_m' - a0 p^2 M theta_m, where M is the axis's equivalent translating mass
(table subtree + rotor and screw inertia reflected through the lead).  Each axis's
input-to-table dynamics then equal G exactly, whatever the assumed masses; both axes use G
(the paper identified X only).
"""

from __future__ import annotations

import math

from controllers.lti import SisoTf
from twin.errors import TwinInputError
from twin.machines.base import (
    Axis,
    Coupling,
    Machine,
    MotionLimits,
    Parameter,
    coulomb_friction_parameters,
    diagonal_plant,
    register_machine,
    set_axial_inertia,
    set_gear,
    set_mass,
)

SOURCE = "Anang et al. (2017) eq. (1)"


@register_machine
class GoogolXY(Machine):
    name = "googol_xy"
    xml = "googol_xy/googol_xy.xml"
    summary = "Googol XY ball-screw table, each axis G = 78020/(s^2+163s+193.3) mm/V, 1.2 ms delay"
    parameters = {
        "b0": Parameter(78020.0, "mm/(V s^2)", f"numerator of G, {SOURCE}"),
        "a1": Parameter(163.0, "1/s", f"s-coefficient of G's denominator, {SOURCE}"),
        "a0": Parameter(193.3, "1/s^2", f"constant of G's denominator, {SOURCE}"),
        "Td": Parameter(0.0012, "s", f"transport delay, {SOURCE}", positive=False),
        "lead_mm": Parameter(5.0, "mm/rev", "ball-screw lead (assumed)"),
        "Jm": Parameter(1.2e-4, "kg m^2", "motor rotor inertia (assumed, 400 W class servo)"),
        "Js": Parameter(1e-4, "kg m^2", "ball-screw inertia (assumed, 16 mm x 0.6 m)"),
        "m_workpiece": Parameter(2.0, "kg", "workpiece mass (assumed)"),
        **coulomb_friction_parameters(("x", "y")),
    }
    #: ours: a small ball-screw table (5 mm lead): 15 m/min, 2.5 m/s^2, 100 m/s^3 (the sources give none)
    motion_limits = {a: MotionLimits(0.25, 2.5, 100.0, "ours: a small ball-screw table") for a in ("x", "y")}
    axes = (
        Axis("x", "x_drive", "x_table", "x_motor", "x_screw"),
        Axis("y", "y_drive", "y_table", "y_motor", "y_screw"),
    )

    def check(self, params):
        if params["Td"] < 0:
            raise TwinInputError("overrides.Td", params["Td"], "delay must be >= 0")

    @staticmethod
    def lead_m_per_rad(params) -> float:
        """Table travel per screw radian (m/rad)."""
        return params["lead_mm"] * 1e-3 / (2.0 * math.pi)

    @classmethod
    def equivalent_mass_kg(cls, params, model, axis: str) -> float:
        """Mass an axis's drive moves (kg): the table's subtree plus the rotor and screw
        inertias over the lead squared.  1 V accelerates it by b0 (m/s^2), so a force F on the
        table acts as F / (M b0) V at the drive's input."""
        mass = float(model.body_subtreemass[model.body(f"{axis}_table").id])
        return mass + (params["Jm"] + params["Js"]) / cls.lead_m_per_rad(params) ** 2

    @classmethod
    def volts_per_newton(cls, params, model, axis: str) -> float:
        """Drive input (V) equivalent to a force of 1 N on the table: 1 / (M b0), b0 in m/(V s^2)."""
        return 1.0 / (cls.equivalent_mass_kg(params, model, axis) * params["b0"] * 1e-3)

    def configure(self, spec, params):
        p = self.lead_m_per_rad(params)
        set_mass(spec, "workpiece", params["m_workpiece"])
        for k, a in enumerate(("x", "y")):
            set_axial_inertia(spec, f"{a}_motor_rotor", k, params["Jm"])
            set_axial_inertia(spec, f"{a}_screw", k, params["Js"])
            set_gear(spec, f"{a}_coupling", 1.0)
            set_gear(spec, f"{a}_nut", 1.0 / p)
        model = spec.compile()  # masses carried by each axis, to size the drive
        for a in ("x", "y"):
            M = self.equivalent_mass_kg(params, model, a)
            act = spec.actuator(f"{a}_drive")
            act.gainprm[0] = params["b0"] * 1e-3 * p * M
            act.biasprm[1] = -params["a0"] * p**2 * M
            act.biasprm[2] = -params["a1"] * p**2 * M

    def plant(self, params, model):
        g = SisoTf((params["b0"] * 1e-3,), (1.0, params["a1"], params["a0"]))
        return diagonal_plant([g, g])

    def delay(self, params):
        return params["Td"]

    def couplings(self, params):
        p = self.lead_m_per_rad(params)
        pairs = []
        for a in ("x", "y"):
            pairs += [Coupling(a, f"{a}_motor", f"{a}_screw", 1.0), Coupling(a, f"{a}_screw", f"{a}_table", 1.0 / p)]
        return pairs, {"x": p, "y": p}
