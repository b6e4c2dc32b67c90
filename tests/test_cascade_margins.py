"""``twin tune``'s whole-cascade margins against an independent model (issue 48): each catalogue
axis's drive train as a state-space chain of masses built from the machine's masses, springs and
dampers (not from its transfer function), sampled by zero-order hold with the drive's delay in
whole periods, the sensors' backward-difference velocity, the PI and filter by Tustin, all in
python-control state space; each gain scaled until the closed cascade's largest pole leaves
the unit circle (bisection)."""

import math
from pathlib import Path

import control
import numpy as np
import pytest

from controllers.kinds.generic import velocity_filter
from twin.commissioning.tuning import tune
from twin.machines import build, get_machine

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "machines"


def _chain_ss(chain):
    """The chain (masses m, springs k, dampers c in table travel, the drive's force on the
    first mass) as continuous state space, outputs the first and the last mass's position."""
    n = len(chain.masses_kg)
    stiffness, damping = np.zeros((n, n)), np.zeros((n, n))
    for i, (k, c) in enumerate(zip(chain.springs_N_per_m, chain.dampers_N_s_per_m)):
        for matrix, value in ((stiffness, k), (damping, c)):
            matrix[i : i + 2, i : i + 2] += value * np.array([[1.0, -1.0], [-1.0, 1.0]])
    damping[-1, -1] += chain.table_damping_N_s_per_m
    inverse = np.diag(1.0 / np.array(chain.masses_kg))
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-inverse @ stiffness, -inverse @ damping]])
    b = np.zeros((2 * n, 1))
    b[n, 0] = chain.force_per_volt_N_per_V / chain.masses_kg[0]
    c = np.zeros((2, 2 * n))
    c[0, 0], c[1, n - 1] = 1.0, 1.0  # motor side, table
    return control.ss(a, b, c, np.zeros((2, 1)))


def _largest_pole(plant, gains: dict, dt: float, sensors: tuple[int, int], scale: dict) -> float:
    """The closed cascade's largest pole magnitude with each gain times ``scale[gain]``."""
    f = velocity_filter(gains["notch_hz"], 20.0, 0.5, gains["lowpass_hz"])
    filt = control.c2d(control.tf(list(f.num), list(f.den)), dt, "tustin")
    integral = control.c2d(control.tf([1.0], [gains["ti_vel_s"], 0.0]), dt, "tustin")
    kv = gains["kp_vel"] * scale.get("kp_vel", 1.0)
    controller = control.ss(kv * filt * (1 + scale.get("ki_vel", 1.0) * integral))
    kp = gains["kp_pos"] * scale.get("kp_pos", 1.0)
    velocity, position = sensors
    sensed = control.ss(control.tf([[[1.0, -1.0], [kp]]], [[[dt, 0.0], [1.0]]], dt))  # [D, kp]
    loop = (
        controller
        * sensed
        * control.ss(plant.A, plant.B, plant.C[[velocity, position]], plant.D[[velocity, position]], dt)
    )
    return float(np.abs(control.poles(control.feedback(loop))).max())


def _boundary_db(plant, gains, dt, sensors, gain: str) -> float:
    """The gain increase (dB) at which the closed cascade goes unstable, by bisection."""
    low, high = 1.0, 100.0
    assert _largest_pole(plant, gains, dt, sensors, {}) < 1.0
    for _ in range(16):  # the 40 dB bracket to 0.0006 dB
        middle = math.sqrt(low * high)
        if _largest_pole(plant, gains, dt, sensors, {gain: middle}) < 1.0:
            low = middle
        else:
            high = middle
    return 20 * math.log10(low)


@pytest.mark.parametrize("feedback", ["dual", "motor", "table"])
@pytest.mark.parametrize("name", ["heavy_xy", "mid_size_xy", "compact_xy", "sgm7j_xy"])
def test_cascade_margins_equal_an_independent_state_space_model(name, feedback):
    """Every axis and gain of every catalogue machine, the three feedbacks: the reported
    increase to instability within 0.05 dB of the bisected boundary."""
    path = str(EXAMPLES / f"{name}.toml")
    result = tune(path, feedback=feedback)
    machine, dt = get_machine(path), result["control_period_s"]
    params, bm = machine.resolve(), build(path)
    delay = round(bm.delay_s / dt)
    sensors = {"dual": (0, 1), "motor": (0, 0), "table": (1, 1)}[feedback]
    for a, design in result["axes"].items():
        sampled = control.c2d(_chain_ss(machine.chain(params, a)), dt, "zoh")
        plant = control.ss(sampled * control.ss(control.tf([1.0], [1.0] + [0.0] * delay, dt))) if delay else sampled
        for gain in ("kp_pos", "kp_vel", "ki_vel"):
            reported = design["cascade_margins"][gain]["gain_margin_db"]
            assert reported == pytest.approx(_boundary_db(plant, design["gains"], dt, sensors, gain), abs=0.05), (
                a,
                gain,
            )
