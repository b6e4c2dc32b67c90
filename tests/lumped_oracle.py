"""An independent lumped model of a catalogue ball-screw axis, the oracle of the FRF's and the
calibration's tests: three masses in a row (motor side, screw side, table, in table travel)
written here from the machine file's resolved values with the catalogue formulas (THK's shaft
stiffness, a solid steel screw), its FRF and its time response discretized exactly (zero-order
hold, ``scipy.signal.cont2discrete``), not through the twin's transfer function or MuJoCo."""

import math
import tomllib
from pathlib import Path

import numpy as np
from scipy import linalg, signal

from twin.machines import build

MACHINES = Path(__file__).resolve().parent.parent / "examples" / "machines"
CATALOGUE = ("compact_xy", "mid_size_xy", "heavy_xy", "sgm7j_xy")
DT = 1e-4
LINES = np.arange(2, 1639) * 1e4 / 16384  # the measurement's lines to 1 kHz
RHO, E, G = 7850.0, 2.06e11, 7.93e10  # screw steel (THK): kg/m^3, Pa, Pa


def lumped_axis(p: dict, axis: str, above: str | None, support: str) -> signal.StateSpace:
    """Drive input (V) to (motor in table travel, table) position (m) of a ball-screw ``axis``
    from resolved parameters ``p``, the axis ``above`` it (or None) and the workpiece carried."""

    def v(key):
        return p[f"{axis}_{key}"]

    lead = v("screw_lead_m") / (2 * math.pi)
    n = v("gear_ratio")
    length = v("screw_length_m")
    if f"{axis}_screw_root_diameter_m" in p:  # the shaft's stiffness up to the nut
        d_root, a = v("screw_root_diameter_m"), v("nut_position_m")
        k_shaft_torsion = G * math.pi * d_root**4 / 32 / a
        k_shaft = E * math.pi * d_root**2 / 4 / a  # held axially at the drive end
        if support == "fixed_fixed":  # and at the far end: the two lengths in parallel
            k_shaft *= length / (length - a)
        k_axial = 1 / (1 / k_shaft + 1 / v("k_nut_N_per_m") + 1 / v("k_bearing_N_per_m"))
    else:
        k_shaft_torsion, k_axial = v("k_screw_torsion_N_m_per_rad"), v("k_axial_N_per_m")
    k_torsion = 1 / (1 / v("k_torsion_N_m_per_rad") + 1 / k_shaft_torsion)
    carried = p["workpiece_mass_kg"]
    if above is not None:
        carried += (
            sum(p[f"{above}_{key}"] for key in ("table_mass_kg", "motor_mass_kg", "nut_mass_kg"))
            + RHO * math.pi * p[f"{above}_screw_diameter_m"] ** 2 / 4 * p[f"{above}_screw_length_m"]
        )
    j_screw = RHO * math.pi * v("screw_diameter_m") ** 4 * length / 32
    m = np.diag(
        [
            (v("motor_inertia_kg_m2") + v("gear_inertia_kg_m2") + v("coupling_inertia_kg_m2") / 2 / n**2)
            * n**2
            / lead**2,
            (j_screw + v("coupling_inertia_kg_m2") / 2) / lead**2 + v("nut_mass_kg"),
            v("table_mass_kg") + carried,
        ]
    )
    k1, k2 = k_torsion / lead**2, k_axial
    c1, c2, c3 = v("c_torsion_N_m_s_per_rad") / lead**2, v("c_axial_N_s_per_m"), v("friction_viscous_N_s_per_m")
    k = np.array([[k1, -k1, 0], [-k1, k1 + k2, -k2], [0, -k2, k2]])
    c = np.array([[c1, -c1, 0], [-c1, c1 + c2, -c2], [0, -c2, c2 + c3]])
    force = v("torque_constant_N_m_per_A") * v("amplifier_gain_A_per_V") * n / lead
    minv = np.linalg.inv(m)
    a_matrix = np.block([[np.zeros((3, 3)), np.eye(3)], [-minv @ k, -minv @ c]])
    b = np.r_[np.zeros(3), minv @ np.array([force, 0, 0])][:, None]
    outputs = np.zeros((2, 6))
    outputs[0, 0] = outputs[1, 2] = 1.0
    return signal.StateSpace(a_matrix, b, outputs, np.zeros((2, 1)))


def oracle(machine: str, axis: str, overrides: dict | None = None) -> tuple[signal.StateSpace, float]:
    """The lumped model of ``machine``'s ``axis`` (with ``overrides``) and its drive delay (s)."""
    path = MACHINES / f"{machine}.toml"
    support = tomllib.loads(path.read_text())["axes"][axis].get("screw_support", "fixed_fixed")
    bm = build(str(path), overrides)
    above = "y" if axis == "x" and "y_table_mass_kg" in bm.params else None  # Y rides on X
    return lumped_axis(bm.params, axis, above, support), bm.delay_s


def modes(sys: signal.StateSpace, sensor: str) -> tuple[list[float], list[float]]:
    """Natural frequencies (Hz) of the lightly damped poles and, for the motor, zeros (the
    eigenvalues of the chain with the motor held: its first mass removed)."""

    def hz(values):
        return sorted(abs(r) / (2 * math.pi) for r in values if r.imag > 0 and -r.real / abs(r) < 0.5)

    resonances = hz(linalg.eigvals(sys.A))
    if sensor == "table":
        return resonances, []
    held = np.delete(np.delete(sys.A, [0, 3], axis=0), [0, 3], axis=1)  # motor position and speed
    return resonances, hz(linalg.eigvals(held))


def zoh_frf(sys: signal.StateSpace, sensor: str, delay_s: float) -> np.ndarray:
    """The exact ZOH response (m/V) at DT on LINES, with the delay."""
    row = 0 if sensor == "motor" else 1
    one = signal.StateSpace(sys.A, sys.B, sys.C[row : row + 1], sys.D[row : row + 1])
    discrete = signal.cont2discrete((one.A, one.B, one.C, one.D), DT, method="zoh")
    z = np.exp(2j * math.pi * LINES * DT)
    a, b, c, _ = discrete[:4]
    response = np.array([(c @ np.linalg.solve(zi * np.eye(len(a)) - a, b))[0, 0] for zi in z])
    return response * np.exp(-2j * math.pi * LINES * delay_s)


def zoh_trace(sys: signal.StateSpace, u: np.ndarray, dt: float, delay_s: float, sensor: str = "table") -> np.ndarray:
    """The position (m) at the samples of the drive input ``u`` (V, held over each ``dt``,
    applied ``delay_s`` later: a whole number of samples) from rest: the exact ZOH response."""
    row = 0 if sensor == "motor" else 1
    a, b, c, d, _ = signal.cont2discrete((sys.A, sys.B, sys.C[row : row + 1], sys.D[row : row + 1]), dt, "zoh")
    delayed = np.r_[np.zeros(round(delay_s / dt)), u][: len(u)]
    _, y, _ = signal.dlsim((a, b, c, d, dt), delayed)
    return y[:, 0]
