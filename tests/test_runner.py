"""Closed-loop runner: agreement with the TF closed loop, drive, sensors, divergence."""

import control
import numpy as np
import pytest

from controllers import error_feedback, make_controller, open_loop
from controllers.blocks import Controller, Sum
from controllers.papers import yadav2020
from twin.errors import SimulationDiverged, TwinInputError
from twin.machines import build
from twin.machining.cutting import AverageForce
from twin.references import Circle, Step
from twin.sim.drive import Drive, Encoder, actuator_input
from twin.sim.loop import DriveState
from twin.sim.runner import simulate


def test_closed_loop_step_matches_transfer_functions():
    """cncmt + robust PI at 1 kHz: twin step response equals the sampled-data TF loop."""
    dt = 1e-3
    bm = build("cncmt")
    res = simulate(bm, make_controller("yadav2020_robust_pi", dt), Step(1.0), duration_s=6.0, control_period_s=dt)
    g = control.c2d(bm.plant[0][0].to_control(), dt, "zoh")
    c = control.c2d(yadav2020.ROBUST_PI.to_control(), dt, "tustin")
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
    res = simulate(bm, open_loop(u, dt), Step(0.0), duration_s=0.2, control_period_s=dt, drive=drive)
    assert res.u_applied_V.max() == pytest.approx(10.0)
    x = res.table_position_m()[:, 0]
    assert np.all(x[:11] == 0.0)
    assert x[12] > 0.0  # 10 steps of delay, then motion
    plain = simulate(bm, open_loop(np.full((2000, 1), 10.0), dt), Step(0.0), duration_s=0.2, control_period_s=dt)
    assert np.allclose(x[10:], plain.table_position_m()[:-10, 0], rtol=0, atol=1e-12)


def test_delay_splits_inside_a_tick():
    """1.2 ms delay at a 0.5 ms control period (googol): 2 ticks + 2 physics steps."""
    drive = Drive(1, 5, 1e-4, delay_s=1.2e-3)
    assert (drive.delay_steps, drive.delay_ticks) == (12, 2)
    line = drive.delay_line()
    for k in range(4):
        line[k % len(line), 0] = 10.0 + k  # the command of tick k
    state = DriveState(
        u_idx=np.array([0]),
        act_idx=np.array([1]),  # the axis drives actuator 1
        limit=np.inf,
        substeps=5,
        delay_steps=drive.delay_steps,
        delay_line=line,
        u=np.zeros(1),
        ua=np.zeros(1),
        u_sat=np.zeros(1),
    )
    seen = []
    for k, s in [(0, 1), (2, 1), (2, 2), (3, 1), (3, 2)]:
        ctrl = np.full(2, -1.0)
        actuator_input(k, s, state.substeps, state.delay_steps, state.delay_line, state.act_idx, ctrl)
        assert ctrl[0] == -1.0
        seen.append(ctrl[1])
    # step s of tick k sees the command of tick (5k + s - 12) // 5, none before step 12
    assert seen == [0.0, 0.0, 10.0, 10.0, 11.0]
    with pytest.raises(TwinInputError, match=r"drive\.delay_s"):
        Drive(1, 5, 1e-4, delay_s=1.25e-4)


def test_encoder_quantization_and_seeded_noise():
    bm = build("cncmt")
    enc = Encoder(np.array([1e-6]), np.array([0.0]), np.array([1.0]))
    res = simulate(
        bm, open_loop(np.full((100, 1), 1.0), 1e-3), Step(0.0), duration_s=0.1, control_period_s=1e-3, encoder=enc
    )
    x = res.table_position_m()[:, 0]
    np.testing.assert_allclose(res.meas_m[:, 0], np.rint(x / 1e-6) * 1e-6, rtol=0, atol=1e-18)
    a = Encoder(np.array([0.0]), np.array([1e-6]), np.array([1.0]), seed=7).noise_source()
    b = Encoder(np.array([0.0]), np.array([1e-6]), np.array([1.0]), seed=7).noise_source()
    chunks = np.vstack([a(123), a(377)])
    assert np.array_equal(chunks, b(500))
    assert np.std(chunks) == pytest.approx(1e-6, rel=0.15)


class _Harmonic:
    """Input disturbance of 0.5 V at 3 Hz on every axis."""

    def input_V(self, t):
        return 0.5 * np.sin(2 * np.pi * 3.0 * t)[:, None] * np.ones(2)


def test_compiled_and_python_loops_give_identical_series():
    """googol_xy: delay split inside a tick, quantization, noise, saturation, feedforward."""
    bm = build("googol_xy")
    dt, period = bm.model.opt.timestep, 5e-4
    runs = []
    for compiled in (True, False):
        ctrl = make_controller("anang2017_pid", period, velocity_ff=0.5, axes=("x", "y"))
        drive = Drive(2, round(period / dt), dt, bm.delay_s, saturation_V=0.1)
        enc = Encoder(np.full(2, 1e-6), np.full(2, 2e-7), np.array(bm.sensor_gains), seed=3)
        runs.append(
            simulate(
                bm,
                ctrl,
                Circle(0.01, 6000.0),
                duration_s=0.3,
                control_period_s=period,
                drive=drive,
                encoder=enc,
                disturbances=[_Harmonic()],
                compiled=compiled,
            )
        )
    fast, slow = runs
    assert (fast.info["loop"], slow.info["loop"]) == ("compiled", "python")
    assert fast.u_applied_V.max() == pytest.approx(0.1)  # saturation was active
    for name in ("qpos", "qvel", "meas_m", "u_V", "u_applied_V", "actuator_force", "error_max_m", "error_rms_m"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name


class _PythonGain:
    """A Python block: u = gain * error (V)."""

    inputs, outputs, name = ("error.x",), ("u.x",), "python_gain"

    def __init__(self, gain):
        self.gain = gain

    def reset(self):
        pass

    def step(self, values):
        return self.gain * values


def test_python_block_runs_in_the_python_loop_only():
    bm = build("cncmt")
    py = simulate(bm, Controller([_PythonGain(30.0)], 1e-3), Step(0.01), duration_s=0.5, control_period_s=1e-3)
    compiled = simulate(
        bm, make_controller("pid", 1e-3, {"kp": 30.0}), Step(0.01), duration_s=0.5, control_period_s=1e-3
    )
    assert py.info["loop"] == "python"
    assert compiled.info["loop"] == "compiled"
    np.testing.assert_allclose(py.qpos, compiled.qpos, rtol=0, atol=1e-15)
    with pytest.raises(TwinInputError, match="compiled"):
        simulate(
            bm, Controller([_PythonGain(30.0)], 1e-3), Step(0.01), duration_s=0.5, control_period_s=1e-3, compiled=True
        )


def test_record_every_keeps_metrics_of_every_tick():
    bm = build("cncmt_xy")
    runs = [
        simulate(
            bm,
            make_controller("yadav2020_robust_pi", 1e-3, axes=("x", "y")),
            Circle(5.0, 600.0),
            duration_s=1.0,
            control_period_s=1e-3,
            record_every=every,
        )
        for every in (1, 7, 0)
    ]
    full, sparse, none = runs
    assert len(full.t_s) == 1000
    assert len(sparse.t_s) == 143
    assert len(none.t_s) == 0
    assert np.array_equal(sparse.qpos, full.qpos[::7])
    assert np.array_equal(sparse.t_s, full.t_s[::7])
    for r in (sparse, none):
        assert np.array_equal(r.error_max_m, full.error_max_m)
    np.testing.assert_allclose(full.error_max_m, np.abs(full.error_m()).max(axis=0), rtol=0, atol=0)
    np.testing.assert_allclose(full.error_rms_m, np.sqrt(np.mean(full.error_m() ** 2, axis=0)), rtol=1e-12)


def test_velocity_measurement_backward_difference_and_tachometer():
    """A cascade reads vel.x: the default is the encoder's backward difference."""
    bm = build("googol_xy")
    period = 1e-3
    seen = {}
    for mode in ("backward_difference", "tachometer"):
        probe = Controller(
            [Sum((1.0,), ("vel.x",), "u.x", "probe_x"), Sum((0.0,), ("vel.y",), "u.y", "probe_y")], period
        )  # u.x = measured velocity (V per m/s): a weak positive feedback
        enc = Encoder(np.zeros(2), np.zeros(2), np.array(bm.sensor_gains), velocity=mode)
        res = simulate(
            bm,
            probe,
            Step(0.0, n_axes=2),
            duration_s=0.2,
            control_period_s=period,
            encoder=enc,
            disturbances=[_Harmonic()],
        )
        seen[mode] = res
    bd, tach = seen["backward_difference"], seen["tachometer"]
    x = bd.meas_m[:, 0]
    np.testing.assert_allclose(bd.u_V[1:, 0], np.diff(x) / period, rtol=1e-12, atol=1e-18)
    v = tach.qvel[:, bm.joint_dof_index("x_table")]
    np.testing.assert_allclose(tach.u_V[:, 0], v, rtol=1e-12, atol=1e-18)


def test_u_prev_is_the_last_saturated_input():
    bm = build("cncmt")
    echo = Controller([Sum((1.0, 1.0), ("u_prev.x", "tick"), "u.x", "echo")], 1e-3)  # u[k] = ua[k-1] + k
    drive = Drive(1, 10, 1e-4, saturation_V=5.0)
    res = simulate(bm, echo, Step(0.0), duration_s=0.01, control_period_s=1e-3, drive=drive)
    expected = [0.0]
    for k in range(1, 10):
        expected.append(min(expected[-1] + k, 5.0))
    assert res.u_applied_V[:, 0].tolist() == expected


@pytest.mark.parametrize("compiled", [True, False])
def test_divergence_is_reported_with_time(compiled):
    dt = 1e-3
    bm = build("cncmt")
    unstable = error_feedback(control.tf([-500.0], [1.0]), dt, name="positive feedback")
    with pytest.raises(SimulationDiverged) as err:
        simulate(bm, unstable, Step(0.01), duration_s=50.0, control_period_s=dt, compiled=compiled)
    assert 0.1 < err.value.sim_time_s < 0.3  # e^(t/tau) from 0.01 m to 10 m


@pytest.mark.parametrize("compiled", [True, False])
def test_huge_or_nan_control_is_divergence_not_a_zeroed_input(compiled):
    """MuJoCo would zero a control beyond 1e10 and go on; the twin stops and says when."""
    bm = build("cncmt")
    u = np.zeros((100, 1))
    u[40] = 1e12
    with pytest.raises(SimulationDiverged, match="drive input") as err:
        simulate(bm, open_loop(u, 1e-3), Step(0.0), duration_s=0.1, control_period_s=1e-3, compiled=compiled)
    assert err.value.sim_time_s == pytest.approx(0.040)
    u[40] = np.nan
    with pytest.raises(SimulationDiverged, match="drive input"):
        simulate(bm, open_loop(u, 1e-3), Step(0.0), duration_s=0.1, control_period_s=1e-3, compiled=compiled)


@pytest.mark.parametrize("compiled", [True, False])
def test_unstable_physics_reported_at_its_step_without_a_log_file(tmp_path, monkeypatch, compiled):
    """A force of +1e9 N s/m times the velocity (an absurd cutting gain) blows the accelerations
    up within a few physics steps, long before the table moves far: reported at the step, in
    MuJoCo's words, and MuJoCo writes no MUJOCO_LOG.TXT into the working folder."""
    monkeypatch.chdir(tmp_path)
    bm = build("linear_motor_xy")
    with pytest.raises(SimulationDiverged, match="QACC") as err:
        simulate(
            bm,
            open_loop(np.full((400, 2), 1.0), 1e-3, ["x", "y"]),
            Step(0.0, n_axes=2),
            duration_s=0.4,
            control_period_s=1e-3,
            disturbances=[AverageForce(1e9, 0.0)],
            compiled=compiled,
        )
    assert err.value.sim_time_s == pytest.approx(4e-4)  # inside the first tick (10 physics steps)
    assert list(tmp_path.iterdir()) == []


def test_control_period_must_be_multiple_of_timestep():
    bm = build("cncmt")
    with pytest.raises(TwinInputError, match="control_period_s"):
        simulate(
            bm, make_controller("yadav2020_imc", 2.5e-4), Step(1.0), duration_s=1.0, control_period_s=2.5e-4 + 1e-5
        )


def test_controllers_must_drive_every_axis_once_and_read_existing_signals():
    bm = build("googol_xy")
    with pytest.raises(TwinInputError, match="needs each of"):
        simulate(
            bm, make_controller("pid", 1e-3, {"kp": 1.0}), Step(0.0, n_axes=2), duration_s=0.01, control_period_s=1e-3
        )
    bad = make_controller("linear", 1e-3, {"inputs": ["vel.z"], "outputs": ["u.x", "u.y"], "D": [[1.0], [1.0]]})
    with pytest.raises(TwinInputError, match=r"vel\.z"):
        simulate(bm, bad, Step(0.0, n_axes=2), duration_s=0.01, control_period_s=1e-3)


def test_long_runs_are_recorded_decimated_by_default(monkeypatch):
    """Over MAX_RECORDED_TICKS ticks the runner keeps every Nth (memory bounded); metrics
    still cover every tick."""
    import twin.sim.runner as runner

    bm = build("cncmt")
    ctrl = make_controller("yadav2020_robust_pi", 1e-3)
    full = simulate(bm, ctrl, Step(0.01), duration_s=1.0, control_period_s=1e-3)
    monkeypatch.setattr(runner, "MAX_RECORDED_TICKS", 300)
    sparse = simulate(bm, ctrl, Step(0.01), duration_s=1.0, control_period_s=1e-3)
    assert sparse.info["record_every"] == 4
    assert len(sparse.t_s) == 250
    assert np.array_equal(sparse.qpos, full.qpos[::4])
    assert np.array_equal(sparse.error_max_m, full.error_max_m)


def test_divergence_carries_the_run_up_to_it():
    bm = build("cncmt")
    with pytest.raises(SimulationDiverged) as err:
        simulate(
            bm, error_feedback(control.tf([-500.0], [1.0]), 1e-3), Step(0.01), duration_s=50.0, control_period_s=1e-3
        )
    part = err.value.result
    done = part.info["completed_ticks"]
    assert done == round(err.value.sim_time_s / 1e-3)
    assert len(part.t_s) == done
    assert np.isfinite(part.qpos).all()
    assert abs(part.table_position_m()[-1, 0]) < 10.0
