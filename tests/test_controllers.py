"""Block kinds on the signal bus against python-control and closed forms (no MuJoCo)."""

import control
import numpy as np
import pytest

from controllers import CONTROLLERS, BlockProgram, error_feedback, make_controller, open_loop
from controllers.blocks import (
    Controller,
    Linear,
    SignalError,
    Static,
    Sum,
    cascade,
    inverse_model_observer,
    lure,
    preview_ticks_needed,
    standard_signals,
    with_correction,
)
from controllers.design.pid import pid_tf
from controllers.lti import SisoTf
from controllers.papers import yadav2020
from controllers.registry import Context, make_observers


def _controller(blocks, dt=1e-3):
    return Controller(blocks, dt, "test")


def _drive(program, inputs: dict, n: int, outputs):
    """Run ``n`` ticks, setting bus signals from ``inputs[name][k]``; return the outputs' series."""
    program.reset()
    out = []
    for k in range(n):
        program.bus[program.index("tick")] = k
        for name, series in inputs.items():
            program.bus[program.index(name)] = series[k]
        program.run()
        out.append([program.bus[program.index(o)] for o in outputs])
    return np.array(out)


@pytest.mark.parametrize("method", ["tustin", "zoh"])
def test_linear_block_matches_python_control(method):
    """Eq. (28) discretized by our realization and formulas, against python-control's own
    realization (slycot) and ``c2d`` (scipy): equal up to rounding."""
    dt, n = 1e-3, 2000
    ctrl = error_feedback(yadav2020.HINF, dt, method=method)
    e = np.sin(np.arange(n) * dt * 7.0)
    u = _drive(BlockProgram([ctrl], standard_signals("x")), {"error.x": e}, n, ["u.x"])[:, 0]
    ref = control.forced_response(
        control.c2d(control.ss(yadav2020.HINF.to_control()), dt, method), T=np.arange(n) * dt, U=e
    ).outputs
    assert np.abs(u - ref).max() <= 1e-12 * np.abs(ref).max()


def test_mimo_linear_block_steady_state():
    c = control.tf([[[2.0], [1.0]], [[0.0], [3.0]]], [[[1.0, 1.0], [1.0]], [[1.0], [1.0, 2.0]]])
    ctrl = error_feedback(c, 1e-3, axes=("x", "y"))
    u = _drive(
        BlockProgram([ctrl], standard_signals("xy")),
        {"error.x": np.ones(20000), "error.y": np.ones(20000)},
        20000,
        ["u.x", "u.y"],
    )[-1]
    assert u == pytest.approx([2.0 + 1.0, 0.0 + 1.5], rel=1e-6)  # C(0) @ [1, 1]


def test_feedforward_adds_velocity_and_acceleration():
    ctrl = make_controller("tf", 1e-3, {"num": [0.0], "den": [1.0]}, velocity_ff=2.0, acceleration_ff=0.5)
    u = _drive(BlockProgram([ctrl], standard_signals("x")), {"ref_vel.x": [3.0], "ref_acc.x": [4.0]}, 1, ["u.x"])
    assert u[0, 0] == 2.0 * 3.0 + 0.5 * 4.0


def test_static_nonlinearities():
    v = np.array([-2.0, -0.5, 0.0, 0.3, 1.5])
    for name, settings, expected in [
        ("saturation", (1.0,), np.clip(v, -1.0, 1.0)),
        ("dead_zone", (0.5,), np.where(np.abs(v) <= 0.5, 0.0, v - 0.5 * np.sign(v))),
        ("cosh_gain", (6.0, 0.3), np.cosh(6.0 * np.clip(v, -0.3, 0.3)) * v),
    ]:
        prog = BlockProgram([_controller([Static(name, settings, ("error.x",), ("u.x",))])], standard_signals("x"))
        out = _drive(prog, {"error.x": v}, len(v), ["u.x"])[:, 0]
        np.testing.assert_allclose(out, expected, rtol=1e-15, atol=0)
    with pytest.raises(ValueError, match="cosh_gain takes k, e_max"):
        Static("cosh_gain", (6.0,), ("error.x",), ("u.x",))


def test_npid_is_the_pid_of_the_shaped_error():
    """Anang 2017 eqs. (6)-(8): u = PID(cosh(KO e) e), e clipped at e_max inside cosh (mm read)."""
    dt, n = 1e-4, 3000
    e = 0.5e-3 * np.sin(np.arange(n) * dt * 40.0)  # +-0.5 mm: the clip at 0.3 mm is active
    npid = make_controller("anang2017_npid", dt)
    u = _drive(BlockProgram([npid], standard_signals("x")), {"error.x": e}, n, ["u.x"])[:, 0]
    shaped = np.cosh(6e3 * np.clip(e, -0.3e-3, 0.3e-3)) * e
    from controllers.papers import anang2017

    ref = control.forced_response(
        control.c2d(control.ss(anang2017.pid(1e-4).to_control()), dt, "tustin"), T=np.arange(n) * dt, U=shaped
    ).outputs
    assert np.abs(u - ref).max() <= 1e-9 * np.abs(ref).max()
    # the gain at the clip is the paper's Ke = 3.1075 at KO = 6, e_max = 0.3
    assert (shaped / np.where(e == 0, 1, e)).max() == pytest.approx(3.1075, abs=1e-4)


def test_cascade_is_the_two_loop_law():
    """v_ref = kp_pos e + ff ref_vel, u = kp_vel (v_ref - vel) + ki_vel sum(T (.))  (Tustin)."""
    dt, n = 1e-3, 50
    rng = np.random.default_rng(1)
    e, rv, vel = rng.normal(size=(3, n))
    ctrl = make_controller("cascade", dt, {"kp_pos": 40.0, "kp_vel": 2.0, "ki_vel": 30.0, "velocity_ref_ff": 1.0})
    u = _drive(BlockProgram([ctrl], standard_signals("x")), {"error.x": e, "ref_vel.x": rv, "vel.x": vel}, n, ["u.x"])
    v_err = 40.0 * e + rv - vel
    pi = control.c2d(control.ss(pid_tf(2.0, 30.0).to_control()), dt, "tustin")
    ref = control.forced_response(pi, T=np.arange(n) * dt, U=v_err).outputs
    np.testing.assert_allclose(u[:, 0], ref, rtol=1e-12, atol=1e-12)


def test_inverse_model_observer_recovers_an_input_disturbance():
    """Plant P_n = 78.02/(s^2 + 163 s + 193.3) m/V (Anang 2017 eq. 1) under u + d: d_hat -> d."""
    dt, n = 1e-4, 20000
    plant = SisoTf([78.02], [1.0, 163.0, 193.3])
    obs = inverse_model_observer(plant, cutoff_hz=50.0, order=2, dt=dt)
    u = 0.2 * np.sin(np.arange(n) * dt * 2 * np.pi * 1.0)
    d = np.where(np.arange(n) * dt > 0.5, 0.05, 0.0)
    y = control.forced_response(control.c2d(plant.to_control(), dt, "zoh"), T=np.arange(n) * dt, U=u + d).outputs
    u_prev = np.concatenate([[0.0], u[:-1]])
    prog = BlockProgram([_controller([obs], dt)], standard_signals("x"))
    d_hat = _drive(prog, {"pos.x": y, "u_prev.x": u_prev}, n, ["dob:d_hat.x"])[:, 0]
    settled = np.arange(n) * dt > 1.0
    assert np.abs(d_hat[settled] - d[settled]).max() < 0.01 * 0.05 + 0.01 * 0.2


def test_observer_add_on_subtracts_the_estimate():
    dt = 1e-3
    base = make_controller("pid", dt, {"kp": 1.0})
    obs = make_observers(
        "inverse_model", {"cutoff_hz": 20.0, "order": 2}, Context(dt, ("x",), plants={"x": SisoTf([1.0], [1.0, 1.0])})
    )
    ctrl = with_correction(base, obs)
    prog = BlockProgram([ctrl], standard_signals("x"))
    out = _drive(prog, {"error.x": [0.3] * 5, "pos.x": [0.1] * 5}, 5, ["u.x", "observer.x:d_hat.x"])
    np.testing.assert_allclose(out[:, 0], 0.3 - out[:, 1], rtol=0, atol=1e-15)
    assert np.abs(out[:, 1]).max() > 0


def test_preview_signals_and_sum():
    """A D-only linear block on preview.x.3 plays r[k+3]; a sum adds two parts."""
    assert preview_ticks_needed(["preview.x.3", "ref.x"]) == 3
    for bad in ("preview.x.0", "preview.x.100000000", "preview.x"):  # the last two would exhaust memory or
        with pytest.raises(ValueError, match="preview"):  # name nothing
            preview_ticks_needed([bad])
    ff = _controller([Linear(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[2.0]], ["preview.x.3"], ["u.x"])])
    names = standard_signals("x", 3)
    assert names[-3:] == ["preview.x.1", "preview.x.2", "preview.x.3"]
    out = _drive(BlockProgram([ff], names), {"preview.x.3": [1.0, 5.0]}, 2, ["u.x"])
    assert out[:, 0].tolist() == [2.0, 10.0]
    total = make_controller(
        "sum", 1e-3, parts=[make_controller("pid", 1e-3, {"kp": 2.0}), make_controller("pid", 1e-3, {"kp": 3.0})]
    )
    assert _drive(BlockProgram([total], standard_signals("x")), {"error.x": [1.0]}, 1, ["u.x"])[0, 0] == 5.0


def test_missing_signal_names_block_and_signal():
    ctrl = make_controller("linear", 1e-3, {"inputs": ["vel.z"], "D": [[1.0]]})
    with pytest.raises(SignalError) as err:
        BlockProgram([ctrl], standard_signals("xy"))
    assert err.value.signal == "vel.z"
    assert "linear" in err.value.block
    with pytest.raises(SignalError, match="already written"):
        BlockProgram([_controller([Sum((1.0,), ("error.x",), "pos.x")])], standard_signals("x"))


@pytest.mark.parametrize(
    "kp, ki, kd, order",
    [(2.0, 3.0, 0.5, 2), (2.0, 0.0, 0.5, 1), (2.0, 3.0, 0.0, 1), (2.0, 0.0, 0.0, 0), (0.0, 3.0, 0.0, 1)],
)
def test_pid_tf(kp, ki, kd, order):
    """Every gain pattern against the sum of its terms; no state for a zero gain's factor."""
    c = pid_tf(kp, ki, kd, 0.01)
    for w in (0.3, 10.0, 3e3):
        s = 1j * w
        assert c(s) == pytest.approx(kp + ki / s + kd * s / (0.01 * s + 1), rel=1e-12)
    assert len(c.den) - 1 == order
    with pytest.raises(ValueError, match="tf_s"):
        pid_tf(1.0, 0.0, 1.0, 0.0)


def test_published_yadav2020_controllers():
    assert yadav2020.ROBUST_PI(1j) == pytest.approx(38.33 + 45.65 / 1j)
    assert yadav2020.HINF_REDUCED(0) == pytest.approx(20.97 / 5.5)
    assert make_controller("yadav2020_hinf", 1e-4).blocks[0].n_state == 4


def test_registry_rejects_unknown_parameters_and_builds_every_kind():
    with pytest.raises(ValueError, match="gain"):
        make_controller("pid", 1e-3, {"gain": 1.0})
    params = {
        "tf": {"num": [1.0], "den": [1.0]},
        "lure": {"num": [1.0], "den": [1.0], "nonlinearity": "dead_zone", "width": 1e-6},
        "linear": {"D": [[1.0]]},
        "sum": {},
        "servo_cascade": {"kp_pos": 100.0, "kp_vel": 5.0, "ti_vel_s": 0.01, "notch_hz": 150.0, "lowpass_hz": 400.0},
    }
    for name in CONTROLLERS:
        parts = [make_controller("pid", 1e-3, {"kp": 1.0}, axes=("x", "y"))] if name == "sum" else ()
        googol = SisoTf([78.02], [1.0, 163.0, 193.3])  # Anang 2017 eq. (1) in m/V, for model-based kinds
        dt = 5e-4 if name.startswith("choi1999") else 1e-3  # Choi 1999's are designed for 2 kHz
        ctrl = make_controller(
            name,
            dt,
            params.get(name, {}),
            axes=("x", "y"),
            parts=parts,
            plants={"x": googol, "y": googol},
            delay_s=1.2e-3,
        )
        assert sorted(ctrl.drives) == ["x", "y"], name
        preview = preview_ticks_needed(s for b in ctrl.blocks for s in b.inputs)
        BlockProgram([ctrl], standard_signals("xy", preview))  # every signal it reads exists


def test_open_loop_block_plays_sequence():
    out = _drive(BlockProgram([open_loop(np.array([[1.0], [2.0]]), 1e-3)], standard_signals("x")), {}, 3, ["u.x"])
    assert out[:, 0].tolist() == [1.0, 2.0, 0.0]


def test_lure_block_is_nonlinearity_then_linear():
    ctrl = lure(control.tf([3.0], [1.0]), "saturation", settings=(0.5,), dt=1e-3)
    out = _drive(BlockProgram([ctrl], standard_signals("x")), {"error.x": [0.2, 2.0, -2.0]}, 3, ["u.x"])
    np.testing.assert_allclose(out[:, 0], [0.6, 1.5, -1.5], rtol=1e-15)
    assert cascade(control.tf(1, 1), control.tf(1, 1), 1e-3, axis="y").drives == ["y"]


@pytest.mark.parametrize(
    "params, match",
    [
        ({"cutoff_hz": 500.0}, "Nyquist frequency 500 Hz"),  # dt = 1 ms
        ({"cutoff_hz": 1e-7}, "at least 1e-6 Hz"),
        ({"order": 1}, "relative degree 2"),
        ({"order": 11}, "to 10"),
        ({"order": 2.5}, "whole number"),
        ({"delay_s": 0.1001}, "100 control periods"),
        ({"delay_s": -1e-3}, "from 0"),
    ],
)
def test_observer_limits(params, match):
    """Limits that keep the observer's realization small: each named in its error."""
    plant = SisoTf([78.02], [1.0, 163.0, 193.3])
    settings = {"cutoff_hz": 20.0, "order": 2, "delay_s": 0.0, **params}
    with pytest.raises(ValueError, match=match):
        inverse_model_observer(
            plant, cutoff_hz=settings["cutoff_hz"], order=settings["order"], dt=1e-3, delay_s=settings["delay_s"]
        )
    # the largest delay allowed builds: a shift register of 99 states after the 2 of Q
    assert inverse_model_observer(plant, cutoff_hz=20.0, order=2, dt=1e-3, delay_s=0.1).n_state == 2 + 2 + 99
