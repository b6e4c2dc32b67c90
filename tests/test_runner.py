"""Closed-loop runner: agreement with the TF closed loop, drive, sensors, divergence."""

import control
import numpy as np
import pytest

from controllers import DiscreteLTI, make_controller, seed000
from controllers.open_loop import OpenLoop
from twin.drive import Drive, Encoder
from twin.errors import SimulationDiverged, TwinInputError
from twin.machines import build
from twin.references import Step
from twin.runner import simulate


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
    with pytest.raises(TwinInputError, match="drive.delay_s"):
        Drive(1, 5, 1e-4, delay_s=1.25e-4)


def test_encoder_quantization_and_seeded_noise():
    enc = Encoder(np.array([1e-6]), np.array([0.0]), np.array([1.0]))
    assert enc.measure(np.array([1.2345678e-3]))[0] == pytest.approx(1.235e-3)
    a = Encoder(np.array([0.0]), np.array([1e-6]), np.array([1.0]), seed=7)
    b = Encoder(np.array([0.0]), np.array([1e-6]), np.array([1.0]), seed=7)
    xa = [a.measure(np.zeros(1))[0] for _ in range(5)]
    xb = [b.measure(np.zeros(1))[0] for _ in range(5)]
    assert xa == xb and np.std(xa) > 0


def test_divergence_is_reported_with_time():
    dt = 1e-3
    bm = build("cncmt")
    unstable = DiscreteLTI(control.tf([-500.0], [1.0]), dt, name="positive feedback")
    with pytest.raises(SimulationDiverged) as err:
        simulate(bm, [unstable], Step(0.01), 50.0, dt)
    assert 0.0 < err.value.sim_time_s < 50.0


def test_control_period_must_be_multiple_of_timestep():
    bm = build("cncmt")
    with pytest.raises(TwinInputError, match="control_period_s"):
        simulate(bm, [make_controller("seed000_imc", 2.5e-4)], Step(1.0), 1.0, 2.5e-4 + 1e-5)
