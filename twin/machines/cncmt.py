"""Yadav 2020 lead-screw axis (``cncmt``) and two stacked axes (``cncmt_xy``).

Source: Yadav, Pathak, Gaur (2020): eq. (1), Table 1, Appendix A.

Equation (1) written as the twin realizes it, with screw angle theta_s (rad), motor angle
theta_m = n theta_s and table position x = p theta_s:

    (p^2 m + n^2 Im) theta_s'' = n K1 K2 (u - H2 theta_s')

so G(s) = X/U = K1 K2 n p / ((p^2 m + n^2 Im) s^2 + K1 K2 n H2 s).  With Table 1's nominal values
and p = 0.05 this is 4.85/(s(s + 9.7)), eq. (2).  p = 0.05 is what eq. (2) needs: Table 1 lists
a 5 mm pitch, i.e. 7.96e-4 m/rad, which would give a different G; the twin follows eq. (2) and
treats p as the lead in m per screw radian.  The tachogenerator (H2) therefore measures the
screw speed; on the motor shaft it would enter as n^2 H2.
"""

from __future__ import annotations

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

SOURCE = "Yadav et al. (2020)"


def leadscrew_parameters(
    suffix: str = "", mass_kg: float = 50.0, mass_note: str = "mass of table + workpiece"
) -> dict[str, Parameter]:
    """Table 1 parameters of one lead-screw axis, symbols optionally suffixed (``_x``)."""
    s = suffix
    return {
        f"K1{s}": Parameter(2.0, "V/V", f"power amplifier gain, {SOURCE} Table 1", (1.0, 3.0)),
        f"K2{s}": Parameter(4.0, "N m/V", f"servomotor gain, {SOURCE} Table 1", (3.0, 5.0)),
        f"m{s}": Parameter(mass_kg, "kg", f"{mass_note}, {SOURCE} Table 1 (m)", (0.6 * mass_kg, 1.4 * mass_kg)),
        f"Im{s}": Parameter(
            0.01, "kg m^2", f"equivalent inertia at the motor (rotor + screw/n^2), {SOURCE} Table 1", (0.008, 0.012)
        ),
        f"p{s}": Parameter(
            0.05, "m/rad", f"lead (table travel per screw radian) as eq. (2) needs; Table 1 says 5 mm pitch, {SOURCE}"
        ),
        f"n{s}": Parameter(2.0, "-", f"gear ratio motor:screw, {SOURCE} Table 1"),
        f"H1{s}": Parameter(1.0, "-", f"encoder gain (measured = H1 x), {SOURCE} Table 1"),
        f"H2{s}": Parameter(0.1, "V s/rad", f"tachogenerator gain on screw speed, {SOURCE} Table 1"),
    }


def leadscrew_tf(*, K1, K2, m, Im, p, n, H2) -> SisoTf:
    """Eq. (1): table position (m) per control input (V)."""
    J = p**2 * m + n**2 * Im
    return SisoTf((K1 * K2 * n * p,), (J, K1 * K2 * n * H2, 0.0))


class _LeadScrewMachine(Machine):
    """Shared configure/plant for one or two Yadav 2020 axes."""

    suffixes: tuple[str, ...] = ("",)
    #: ours: Yadav 2020 gives no limits; 6 m/min, 1 m/s^2, 20 m/s^3 for its 50 kg lead-screw table
    motion_limits = {a: MotionLimits(0.1, 1.0, 20.0, "ours: a 50 kg lead-screw table") for a in ("x", "y")}
    common = {
        "Js": Parameter(
            8e-4, "kg m^2", "lead-screw inertia (32 mm x 1 m steel screw; assumed, part of Im: rotor gets Im - Js/n^2)"
        ),
        "m_workpiece": Parameter(10.0, "kg", "workpiece mass, part of m (assumed split)"),
        "Td": Parameter(
            0.0,
            "s",
            f"transport delay of eq. (2) (0.1 s in the paper's simulations;"
            f" off by default: {SOURCE} analyses without it)",
            positive=False,
        ),
    }

    def _axis_values(self, params, s):
        return {k: params[f"{k}{s}"] for k in ("K1", "K2", "m", "Im", "p", "n", "H2")}

    def check(self, params):
        if params["Td"] < 0:
            raise TwinInputError("overrides.Td", params["Td"], "delay must be >= 0")
        for s in self.suffixes:
            v = self._axis_values(params, s)
            if v["Im"] - params["Js"] / v["n"] ** 2 <= 0:
                raise TwinInputError(
                    f"overrides.Im{s}", v["Im"], f"must exceed Js/n^2 = {params['Js'] / v['n'] ** 2:g} kg m^2"
                )
        table_mass = params[f"m{self.suffixes[-1]}"]
        if table_mass <= params["m_workpiece"]:
            raise TwinInputError(
                f"overrides.m{self.suffixes[-1]}", table_mass, f"must exceed m_workpiece = {params['m_workpiece']:g} kg"
            )

    def configure(self, spec, params):
        top = self.suffixes[-1]
        for axis, s in zip(self.axes, self.suffixes):
            v = self._axis_values(params, s)
            a = axis.name
            k = 0 if a == "x" else 1
            set_axial_inertia(spec, f"{a}_motor_rotor", k, v["Im"] - params["Js"] / v["n"] ** 2)
            set_axial_inertia(spec, f"{a}_screw", k, params["Js"])
            set_gear(spec, f"{a}_gearbox", v["n"])
            set_gear(spec, f"{a}_nut", 1.0 / v["p"])
            act = spec.actuator(f"{a}_drive")
            gain = v["K1"] * v["K2"]
            act.gainprm[0] = gain
            act.biasprm[2] = -gain * v["H2"] / v["n"]
            table_mass = v["m"] - (params["m_workpiece"] if s == top else 0.0)
            set_mass(spec, f"{a}_table", table_mass)
        set_mass(spec, "workpiece", params["m_workpiece"])

    def plant(self, params, model):
        channels = []
        for axis, s in zip(self.axes, self.suffixes):
            v = self._axis_values(params, s)
            # translating mass of this axis: its own table plus everything riding on it
            v["m"] = float(model.body_subtreemass[model.body(f"{axis.name}_table").id])
            channels.append(leadscrew_tf(**v))
        return diagonal_plant(channels)

    def delay(self, params):
        return params["Td"]

    def couplings(self, params):
        pairs, leads = [], {}
        for axis, s in zip(self.axes, self.suffixes):
            a = axis.name
            pairs += [
                Coupling(a, f"{a}_motor", f"{a}_screw", params[f"n{s}"]),
                Coupling(a, f"{a}_screw", f"{a}_table", 1.0 / params[f"p{s}"]),
            ]
            leads[a] = params[f"p{s}"]
        return pairs, leads

    def sensor_gains(self, params):
        return tuple(params[f"H1{s}"] for s in self.suffixes)


@register_machine
class CNCMT(_LeadScrewMachine):
    name = "cncmt"
    xml = "cncmt/cncmt.xml"
    summary = "Yadav 2020 lead-screw axis: motor, gearbox n=2, lead screw, table + workpiece (50 kg)"
    suffixes = ("",)
    parameters = {**leadscrew_parameters(""), **_LeadScrewMachine.common, **coulomb_friction_parameters(("x",))}
    axes = (Axis("x", "x_drive", "x_table", "x_motor", "x_screw"),)


@register_machine
class CNCMTXY(_LeadScrewMachine):
    name = "cncmt_xy"
    xml = "cncmt_xy/cncmt_xy.xml"
    summary = "two Yadav 2020 axes, the Y drive train and table riding on the X table"
    suffixes = ("_x", "_y")
    parameters = {
        **leadscrew_parameters("_x", 50.0, "mass of the X table alone (the Y axis adds its own mass on top)"),
        **leadscrew_parameters("_y", 50.0, "mass of Y table + workpiece"),
        **_LeadScrewMachine.common,
        **coulomb_friction_parameters(("x", "y")),
    }
    axes = (
        Axis("x", "x_drive", "x_table", "x_motor", "x_screw"),
        Axis("y", "y_drive", "y_table", "y_motor", "y_screw"),
    )
