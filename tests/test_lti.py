"""The run path's own realization and discretization against python-control and scipy."""

import control
import numpy as np
import pytest

from controllers.lti import (
    SisoTf,
    delay_ticks,
    discretize,
    series,
    state_space,
    step_from_rest,
    summed_inputs,
    tf_to_ss,
)


def _frequency_response(A, B, C, D, z):
    """C (z I - A)^-1 B + D at one point (continuous: z = s)."""
    return C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B) + D


RANDOM_TFS = [
    SisoTf(np.random.default_rng(seed).normal(size=k), np.poly(-np.random.default_rng(seed).uniform(1, 50, n)))
    for seed, (k, n) in enumerate([(1, 1), (2, 2), (3, 3), (4, 4), (3, 5)])
]


@pytest.mark.parametrize("tf", RANDOM_TFS)
def test_realization_has_the_transfer_function(tf):
    A, B, C, D = tf_to_ss(tf)
    for s in (0.5j, 3.0 + 7j, 200j):
        assert _frequency_response(A, B, C, D, s)[0, 0] == pytest.approx(tf(s), rel=1e-10)


@pytest.mark.parametrize("tf", RANDOM_TFS)
def test_tustin_is_the_bilinear_substitution(tf):
    """Tustin: H(z) = H(s) at s = (2/dt) (z - 1)/(z + 1), exactly."""
    dt = 2e-3
    ours = discretize(*tf_to_ss(tf), dt=dt, method="tustin")
    for f in (0.1, 7.0, 120.0):
        z = np.exp(2j * np.pi * f * dt)
        assert _frequency_response(*ours, z)[0, 0] == pytest.approx(tf(2 / dt * (z - 1) / (z + 1)), rel=1e-10)


@pytest.mark.parametrize("tf", RANDOM_TFS)
def test_zoh_matches_python_control(tf):
    """Zero-order hold: the same discrete model as ``control.c2d`` of python-control's own
    state-space realization (slycot), by frequency response."""
    dt = 2e-3
    ours = discretize(*tf_to_ss(tf), dt=dt, method="zoh")
    theirs = control.c2d(control.ss(tf.to_control()), dt, "zoh")
    for f in (0.1, 7.0, 120.0):
        z = np.exp(2j * np.pi * f * dt)
        assert _frequency_response(*ours, z)[0, 0] == pytest.approx(complex(theirs(z)), rel=1e-10)


def test_static_gain_and_improper_models():
    A, _B, _C, D = discretize(*tf_to_ss(SisoTf([3.0], [2.0])), dt=1e-3)
    assert A.shape == (0, 0)
    assert D[0, 0] == 1.5
    with pytest.raises(ValueError, match="improper"):
        tf_to_ss(SisoTf([1.0, 0.0], [1.0]))
    with pytest.raises(ValueError, match="denominator is zero"):
        SisoTf([1.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="flat"):
        SisoTf([[1.0]], [1.0])
    with pytest.raises(ValueError, match="method"):
        discretize(*tf_to_ss(SisoTf([1.0], [1.0, 1.0])), dt=1e-3, method="euler")


def test_tustin_pole_at_two_over_dt_is_an_error():
    with pytest.raises(ValueError, match="2/dt"):
        discretize(*tf_to_ss(SisoTf([1.0], [1.0, -2.0 / 1e-3])), dt=1e-3)


def test_series_delay_and_summed_inputs_are_products_and_sums():
    dt = 1e-3
    g1 = discretize(*tf_to_ss(RANDOM_TFS[2]), dt=dt)
    g2 = discretize(*tf_to_ss(RANDOM_TFS[1]), dt=dt)
    both = summed_inputs(g1, series(delay_ticks(3), g2))
    for f in (0.5, 40.0):
        z = np.exp(2j * np.pi * f * dt)
        h1, h2 = _frequency_response(*g1, z)[0, 0], _frequency_response(*g2, z)[0, 0]
        assert _frequency_response(*both, z)[0] == pytest.approx([h1, h2 * z**-3], rel=1e-10)
    assert delay_ticks(0)[3][0, 0] == 1.0


def test_state_space_takes_python_control_models():
    A, _B, _C, _D, dt = state_space(control.c2d(control.tf([1.0], [1.0, 2.0]), 0.01))
    assert dt == 0.01
    assert A.shape == (1, 1)
    assert state_space(SisoTf([1.0], [1.0, 2.0]))[4] is None


def test_degree_limit_and_short_messages():
    with pytest.raises(ValueError, match=r"\[1, 1, 1, 1, 1, 1, \.\.\. 96 more\]: degree 101 above the limit of 100"):
        SisoTf([1.0], np.ones(102))
    assert SisoTf([1.0], np.ones(101)).relative_degree == 100


@pytest.mark.parametrize("n", [2, 7, 6001])
@pytest.mark.parametrize("tf", RANDOM_TFS)
def test_step_from_rest_is_python_controls_step_response(tf, n):
    """The doubling's samples equal python-control's sample-by-sample simulation (stable
    models, a proper one with a direct term among them), any sample count."""
    t = np.linspace(0.0, 0.2, n)
    dt = 0.2 / (n - 1)
    reference = np.asarray(control.step_response(tf.to_control(), t).outputs, float).reshape(-1)
    ours = step_from_rest(tf, dt=dt, n=n)
    assert ours.shape == (n,)
    np.testing.assert_allclose(ours, reference, rtol=1e-10, atol=1e-12 * np.abs(reference).max())


def test_step_from_rest_takes_continuous_siso_models_only():
    # one sample: the response at t = 0, the direct term (python-control needs two samples)
    assert step_from_rest(SisoTf([2.0, 1.0], [1.0, 3.0]), dt=0.1, n=1).tolist() == [2.0]
    with pytest.raises(ValueError, match="continuous model with one input and one output"):
        step_from_rest(control.tf([1.0], [1.0, 1.0], 0.1), dt=0.1, n=5)
