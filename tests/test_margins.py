"""Margins over every crossing (controllers.design.loop_analysis.crossing_margins) against
python-control's stability_margins and against the crossings found by root finding on the
exact sampled loop, on random two-mass axes under a sampled PI velocity loop with and without
a notch at the mode."""

import json
import math
import warnings

import control
import numpy as np
import pytest
from scipy.optimize import brentq

from controllers.design.loop_analysis import crossing_margins, loop_margins
from controllers.kinds.generic import velocity_filter

DT = 1e-4
FREQS = np.geomspace(0.1, 0.49999 / DT, 20_000)


def random_loop(rng, notch: bool):
    """Drive (V) to table position of two masses joined by a damped spring, ZOH with 0-2
    periods of delay, under kv (1 + 1/(Ti s)) by Tustin (notched at the mode or not) with the
    backward-difference velocity: gains and masses drawn so that some loops are unstable.
    The loop's factors, each a python-control system (their product, one system of high
    order, is ill-conditioned near z = 1, where its phase would jitter about -180 deg)."""
    m1, m2 = rng.uniform(5, 200, 2)
    k = (2 * math.pi * rng.uniform(80, 900)) ** 2 * m1 * m2 / (m1 + m2)
    c = rng.uniform(0.005, 0.05) * 2 * math.sqrt(k * m1 * m2 / (m1 + m2))
    gain = rng.uniform(50, 500)
    plant = control.tf([gain * c, gain * k], np.polymul([1, 0, 0], [m1 * m2, c * (m1 + m2), k * (m1 + m2)]))
    delay = control.tf([1.0], [1.0] + [0.0] * int(rng.integers(0, 3)), DT)
    mode_hz = math.sqrt(k * (m1 + m2) / (m1 * m2)) / (2 * math.pi)
    f = velocity_filter(mode_hz if notch else 0.0, 20.0, 0.5, 0.0)
    ti = rng.uniform(2e-3, 2e-2)
    kv = rng.uniform(0.3, 3.0) * (m1 + m2) / gain * 2 * math.pi * 50
    pi = control.tf([kv * ti, kv], [ti, 0.0])
    c_z = control.c2d(pi * control.tf(list(f.num), list(f.den)), DT, "tustin")
    z = control.tf([1.0, 0.0], [1.0], DT)
    return [c_z, control.c2d(plant, DT, "zoh"), delay, (z - 1) / (DT * z)]


def response(factors, freqs_hz) -> np.ndarray:
    """The loop's frequency response: its factors' product."""
    out = np.ones(len(np.atleast_1d(freqs_hz)), complex)
    for factor in factors:
        out *= control.frequency_response(factor, 2 * math.pi * np.atleast_1d(freqs_hz)).complex.ravel()
    return out


def _root(fun, lo, hi):
    return brentq(fun, lo, hi, xtol=1e-12)


# python-control's margins of a 20 000-point FRD take about 1.3 s: ten loops by default, ten
# more in the slow suite
@pytest.mark.parametrize("seed", [*range(10), *(pytest.param(s, marks=pytest.mark.slow) for s in range(10, 20))])
def test_margins_equal_python_control_and_the_exact_crossings(seed):
    loop = random_loop(np.random.default_rng(seed), notch=seed % 2 == 1)
    on_grid = response(loop, FREQS)
    ours = crossing_margins(FREQS, on_grid)
    # python-control on the same response (its FRD search: splines and brentq over every crossing)
    gm, pm, _, w_gm, w_pm, _ = control.stability_margins(control.frd(on_grid, 2 * math.pi * FREQS))
    assert ours.gm_db == pytest.approx(20 * math.log10(gm), abs=0.01)
    assert ours.pm_deg == pytest.approx(pm, abs=0.05)
    assert ours.f_gm_hz == pytest.approx(w_gm / (2 * math.pi), rel=1e-3)
    assert ours.f_pm_hz == pytest.approx(w_pm / (2 * math.pi), rel=1e-3)

    # the exact loop (no grid) at the crossings bracketed near ours
    def at(f_hz):
        return complex(response(loop, f_hz)[0])

    f_gm = _root(lambda f: at(f).imag, ours.f_gm_hz * 0.995, min(ours.f_gm_hz * 1.005, 0.5 / DT))
    assert at(f_gm).real < 0
    assert ours.gm_db == pytest.approx(-20 * math.log10(abs(at(f_gm))), abs=0.01)
    f_pm = _root(lambda f: abs(at(f)) - 1.0, ours.f_pm_hz * 0.995, ours.f_pm_hz * 1.005)
    assert ours.pm_deg == pytest.approx(math.degrees(np.angle(at(f_pm))) % 360.0 - 180.0, abs=0.05)


def test_every_crossing_counts_not_the_first():
    """An integrator with 1 ms of delay and a lightly damped mode at 1.2 kHz: the phase first
    passes -180 deg at 250 Hz (19.6 dB, what the first crossing gives, as the papers' loop
    analysis reads it), then -540 deg at the mode, 1.6 dB from instability: that one is the
    margin, equal to the exact loop's there."""

    def loop(f_hz):
        s = 2j * math.pi * np.asarray(f_hz)
        w_r = 2 * math.pi * 1200.0
        return 157.0 * np.exp(-s * 1e-3) / s * w_r**2 / (s**2 + 2 * 0.005 * w_r * s + w_r**2)

    freqs = np.geomspace(1.0, 3000.0, 20_000)
    ours = crossing_margins(freqs, loop(freqs))
    first = loop_margins(lambda w: loop(w / (2 * math.pi)), w_min=2 * math.pi, w_max=2 * math.pi * 3000.0)
    assert first.gm_db == pytest.approx(19.6, abs=0.1)
    assert first.w_gm / (2 * math.pi) == pytest.approx(250.0, rel=0.01)
    f_mode = _root(lambda f: complex(loop(f)).imag, 0.99 * ours.f_gm_hz, 1.01 * ours.f_gm_hz)
    assert ours.gm_db == pytest.approx(-20 * math.log10(abs(complex(loop(f_mode)))), abs=0.01)
    assert 1.0 < ours.gm_db < 2.0
    assert ours.f_gm_hz == pytest.approx(1186.0, rel=1e-3)


def test_an_infinite_margin_is_null_with_a_reason():
    # |L| = 0.5 at every frequency, phase 0: no crossing of either kind
    m = crossing_margins(FREQS, np.full(len(FREQS), 0.5 + 0j)).as_dict()
    assert m["phase_margin_deg"] is None
    assert m["gain_margin_db"] is None
    assert "infinite" in m["phase_margin_note"]
    assert "infinite" in m["gain_margin_note"]
    json.dumps(m, allow_nan=False)  # strict JSON
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a zero on the grid (a ZOH's at Nyquist) warns nothing
        crossing_margins(FREQS, np.append(np.full(len(FREQS) - 1, 2.0 + 0j), 0.0))
