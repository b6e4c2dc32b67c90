"""Control blocks against python-control (no MuJoCo)."""

import control
import numpy as np
import pytest

from controllers import DiscreteLTI, make_controller, seed000
from controllers.open_loop import OpenLoop
from controllers.design.pid import pid_tf


def _run_block(block, e):
    out = []
    for ek in e:
        ref = np.zeros((block.n_axes, 3))
        ref[:, 0] = ek
        out.append(block.step(ref, np.zeros((block.n_axes, 2))))
    return np.array(out)


@pytest.mark.parametrize("method", ["tustin", "zoh"])
def test_discrete_lti_matches_c2d(method):
    dt = 1e-3
    block = DiscreteLTI(seed000.HINF, dt, method)
    n = 2000
    e = np.sin(np.arange(n) * dt * 7.0)
    u = _run_block(block, e)[:, 0]
    ref = control.forced_response(control.c2d(seed000.HINF, dt, method), T=np.arange(n) * dt, U=e).outputs
    # independent realization (TF vs our state space): rounding of the ill-conditioned eq. (28)
    assert np.abs(u - ref).max() <= 1e-5 * np.abs(ref).max()


def test_mimo_block():
    c = control.tf([[[2.0], [1.0]], [[0.0], [3.0]]], [[[1.0, 1.0], [1.0]], [[1.0], [1.0, 2.0]]])
    block = DiscreteLTI(c, 1e-3)
    assert block.n_axes == 2
    u = _run_block(block, np.ones(20000))[-1]
    # steady state of a unit error on both inputs: C(0) @ [1, 1]
    assert u == pytest.approx([2.0 + 1.0, 0.0 + 1.5], rel=1e-6)


def test_feedforward_adds_velocity_and_acceleration():
    block = DiscreteLTI(control.tf([0.0], [1.0]), 1e-3, velocity_ff=2.0, acceleration_ff=0.5)
    u = block.step(np.array([[0.0, 3.0, 4.0]]), np.zeros((1, 2)))
    assert u[0] == pytest.approx(2.0 * 3.0 + 0.5 * 4.0)


def test_pid_tf():
    c = pid_tf(2.0, 3.0, 0.5, 0.01)
    w = 10.0
    expected = 2.0 + 3.0 / (1j * w) + 0.5 * 1j * w / (0.01 * 1j * w + 1)
    assert c(1j * w) == pytest.approx(expected)
    with pytest.raises(ValueError, match="tf_s"):
        pid_tf(1.0, 0.0, 1.0, 0.0)


def test_published_seed000_controllers():
    assert seed000.ROBUST_PI(1j) == pytest.approx(38.33 + 45.65 / 1j)
    assert seed000.HINF_REDUCED(0) == pytest.approx(20.97 / 5.5)
    assert make_controller("seed000_hinf", 1e-4).x.size == 4


def test_registry_rejects_unknown_parameters():
    with pytest.raises(ValueError, match="gain"):
        make_controller("pid", 1e-3, {"gain": 1.0})


def test_open_loop_block_plays_sequence():
    block = OpenLoop(np.array([[1.0], [2.0]]), 1e-3)
    out = _run_block(block, [0, 0, 0])[:, 0]
    assert out.tolist() == [1.0, 2.0, 0.0]
