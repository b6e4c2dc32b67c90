"""Closed-loop runner: agreement with the TF closed loop, drive, sensors, divergence."""

import control
import numpy as np
import pytest

from controllers import DiscreteLTI, make_controller, seed000
from controllers.open_loop import OpenLoop
from twin.sim.drive import Drive, Encoder
from twin.errors import SimulationDiverged, TwinInputError
from twin.machines import build
from twin.references import Circle, Step
from twin.sim.runner import simulate


def test_closed_loop_step_matches_transfer_functions():
    """cncmt + robust PI at 1 kHz: twin step response equals the sampled-data TF loop."""
    dt = 1e-3
    bm = build("cncmt")
    res = simulate(bm, [make_controller("seed000_robust_pi", dt)], Step(1.0), 6.0, dt)
    g = control.c2d(bm.plant[0, 0], dt, "zoh")
    c = control.c2d(seed000.ROBUST_PI, dt, "tustin")
    loop = control.feedback(g * c, 1)
    # the twin samples the state at the start of each tick: y[k] of the loop
    y_ref = control.step_response(loop, T=res.t_s).outputs
    y = res.table_position_m()[:, 0]
    assert np.abs(y - y_ref).max() <= 2e-3


def test_saturation_and_delay():
    dt = 1e-4
    bm = build("cncmt")
    u = np.full((2000, 1), 50.0)
    drive = Drive(1, 1, dt, delay_s=1e-3, saturation_V=10.0)
    res = simulate(bm, [OpenLoop(u, dt)], Step(0.0), 0.2, dt, drive=drive)
    assert res.u_applied_V.max() == pytest.approx(10.0)
    x = res.table_position_m()[:, 0]
    assert np.all(x[:11] == 0.0) and x[12] > 0.0  # 10 steps of delay, then motion
    plain = simulate(bm, [OpenLoop(np.full((2000, 1), 10.0), dt)], Step(0.0), 0.2, dt)
    assert np.allclose(x[10:], plain.table_position_m()[:-10, 0], rtol=0, atol=1e-12)


def test_delay_splits_inside_a_tick():
    """1.2 ms delay at a 0.5 ms control period (googol): 2 ticks + 2 physics steps."""
    drive = Drive(1, 5, 1e-4, delay_s=1.2e-3)
    assert (drive.delay_ticks, drive.split) == (2, 2)
    assert drive.segments(0) == [(2, -1), (3, -1)]
    assert drive.segments(3) == [(2, 0), (3, 1)]
    with pytest.raises(TwinInputError, match="drive.delay_s"):
        Drive(1, 5, 1e-4, delay_s=1.25e-4)


def test_encoder_quantization_and_seeded_noise():
    enc = Encoder(np.array([1e-6]), np.array([0.0]), np.array([1.0]))
    assert enc.measure(np.array([1.2345678e-3]), np.zeros(1))[0] == pytest.approx(1.235e-3)
    a = Encoder(np.array([0.0]), np.array([1e-6]), np.array([1.0]), seed=7).noise_m(500)
    b = Encoder(np.array([0.0]), np.array([1e-6]), np.array([1.0]), seed=7).noise_m(500)
    assert np.array_equal(a, b) and np.std(a) == pytest.approx(1e-6, rel=0.15)


class _Harmonic:
    """Input disturbance of 0.5 V at 3 Hz on every axis."""

    def input_V(self, t):
        return 0.5 * np.sin(2 * np.pi * 3.0 * t)[:, None] * np.ones(2)


def test_compiled_and_python_loops_give_identical_series():
    """googol_xy: delay split inside a tick, quantization, noise, saturation, feedforward."""
    bm = build("googol_xy")
    dt, period = bm.model.opt.timestep, 5e-4
    runs, blocks = [], []
    for compiled in (True, False):
        ctrls = [make_controller("seed002_pid", period, velocity_ff=0.5) for _ in range(2)]
        blocks.append(ctrls)
        drive = Drive(2, int(round(period / dt)), dt, bm.delay_s, saturation_V=0.1)
        enc = Encoder(np.full(2, 1e-6), np.full(2, 2e-7), np.array(bm.sensor_gains), seed=3)
        runs.append(simulate(bm, ctrls, Circle(0.01, 6000.0), 0.3, period, drive=drive, encoder=enc,
                             disturbances=[_Harmonic()], compiled=compiled))
    fast, slow = runs
    assert (fast.info["loop"], slow.info["loop"]) == ("compiled", "python")
    assert fast.u_applied_V.max() == pytest.approx(0.1)  # saturation was active
    for name in ("qpos", "qvel", "meas_m", "u_V", "u_applied_V", "actuator_force"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name
    for fast_block, slow_block in zip(*blocks):  # final controller state handed back
        assert np.abs(fast_block.x).max() > 0 and np.array_equal(fast_block.x, slow_block.x)


@pytest.mark.parametrize("compiled", [True, False])
def test_divergence_is_reported_with_time(compiled):
    dt = 1e-3
    bm = build("cncmt")
    unstable = DiscreteLTI(control.tf([-500.0], [1.0]), dt, name="positive feedback")
    with pytest.raises(SimulationDiverged) as err:
        simulate(bm, [unstable], Step(0.01), 50.0, dt, compiled=compiled)
    assert 0.0 < err.value.sim_time_s < 50.0


def test_control_period_must_be_multiple_of_timestep():
    bm = build("cncmt")
    with pytest.raises(TwinInputError, match="control_period_s"):
        simulate(bm, [make_controller("seed000_imc", 2.5e-4)], Step(1.0), 1.0, 2.5e-4 + 1e-5)
