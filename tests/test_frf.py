"""The motor's encoder in the loop (FRF measurement, semi-closed loops and their tuning) and the FRF's peaks."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from twin.commissioning.frf import FrfSettings, measure, peaks
from twin.errors import SimulationDiverged, TwinInputError

MID = str(Path(__file__).resolve().parent.parent / "examples" / "machines" / "mid_size_xy.toml")
LINE_HZ = 1e4 / 16384  # the measurement's line spacing: 0.1 ms samples, 16 384-sample segments


def _resonance_on_a_rigid_body(f_hz, f0_hz, zeta):
    """|G| (dB) of a rigid body (-40 dB/decade) with a lightly damped mode at f0."""
    s = 2j * math.pi * f_hz
    w = 2 * math.pi * f0_hz
    mode = (2 * zeta * w * s + w**2) / (s**2 + 2 * zeta * w * s + w**2)  # a resonance and no zero
    return 20 * np.log10(np.abs(mode / s**2))


@pytest.mark.parametrize(("f0_hz", "zeta"), [(5.3, 0.02), (8.72, 0.05), (40.0, 0.02), (59.35, 0.25), (175.0, 0.1)])
def test_a_peak_is_refined_within_half_a_line_of_the_modes_maximum(f0_hz, zeta):
    """The refinement's parabola is fitted above the rigid body's slope, where the mode is the
    extreme, and stays within half a line: the resonance within half a line of the maximum of
    |G| f^2 found on a grid 100 times finer.  On the raw magnitude (falling 2 dB a line at 5 Hz)
    the vertex of a damped mode at 59 Hz landed 21 lines away, at 46 Hz."""
    f = LINE_HZ * np.arange(2, 1600)
    resonances, antiresonances = peaks(f, _resonance_on_a_rigid_body(f, f0_hz, zeta), coherence=np.ones_like(f))
    fine = np.linspace(0.5 * f0_hz, 1.5 * f0_hz, 100 * round(f0_hz / LINE_HZ))
    expected = fine[np.argmax(_resonance_on_a_rigid_body(fine, f0_hz, zeta) + 40 * np.log10(fine))]
    assert resonances == [pytest.approx(expected, abs=0.5 * LINE_HZ)]
    assert antiresonances == []


def test_a_slow_bend_is_no_resonance_and_a_mode_beside_it_is():
    """A broad 6 dB hump over a decade around 15 Hz (what Coulomb friction leaves at low
    frequency: the twin's mid_size_xy X read a resonance at 15.3 Hz there) is not prominent
    within a factor 1.5 of its frequency; the 175 Hz mode beside it is found."""
    f = LINE_HZ * np.arange(2, 1600)
    hump = 6.0 * np.exp(-(np.log10(f / 15.0) ** 2) / (2 * 0.4**2))
    resonances, _ = peaks(f, _resonance_on_a_rigid_body(f, 175.0, 0.02) + hump, coherence=np.ones_like(f))
    assert resonances == [pytest.approx(175.0, abs=LINE_HZ)]


def test_the_heavy_axis_is_measured_with_the_loop_on_the_motor_encoder():
    """A 200 kg table with a 1.99e-3 kg m^2 motor (the issue's case): the default velocity loop
    on the table's scale is unstable (non-collocated) and the error says what to try; on the
    motor's encoder (the default) it measures both modes within 1 % of the model's, and a table
    sensor reports no anti-resonance (its transfer function has no zeros)."""
    machine = str(Path(__file__).resolve().parent.parent / "examples" / "machines" / "mid_size_xy.toml")
    heavy = {"x_table_mass_kg": 200.0, "x_motor_inertia_kg_m2": 1.99e-3}
    with pytest.raises(SimulationDiverged, match="try --feedback motor"):
        measure(machine, FrfSettings(feedback="table", duration_s=4.0), heavy)
    r = measure(machine, FrfSettings(duration_s=8.0), heavy)
    assert len(r.resonances_hz) == len(r.model_resonances_hz) == 2
    np.testing.assert_allclose(r.resonances_hz, r.model_resonances_hz, rtol=0.01)
    assert r.antiresonances_hz == []
    assert not r.collocated  # the table's dips are no anti-resonances: the JSON says so
    assert r.to_json()["antiresonances_note"]


def test_a_semi_closed_loop_reads_the_motor_encoder_in_table_travel():
    """`sensors.feedback = "motor"`: the encoder the position loop reads is motor angle x lead /
    2 pi (ideal encoders: exactly), not the table, which lags it through the nut's and the
    screw's compliance while the axis accelerates (29 um on a 1 mm step, the drive at its
    4.6 kN); with the default, dual feedback, the position loop reads the table's scale; with
    the machine's 20-bit motor encoder, the motor's reading is on its grid of lead / 2^20."""
    from twin.machines import build
    from twin.scenario import run_scenario, scenario_from_dict

    machine = str(Path(__file__).resolve().parent.parent / "examples" / "machines" / "mid_size_xy.toml")
    bm = build(machine)
    gains = {"kp_pos": 60.0, "kp_vel": 300.0, "ti_vel_s": 0.01}

    def step(sensors):
        return run_scenario(
            scenario_from_dict(
                {
                    "machine": machine,
                    "duration_s": 0.1,
                    "control_period_s": 1e-4,
                    "controllers": {a: {"type": "servo_cascade", "params": gains} for a in "xy"},
                    "reference": {"type": "step", "amplitude_m": 1e-3},
                    "sensors": sensors,
                }
            )
        ).run

    ideal = {"encoder_resolution_m": 0.0, "motor_encoder_resolution_m": 0.0}
    run = step({"feedback": "motor", **ideal})
    motor = run.qpos[:, bm.joint_qpos_index("x_motor")] * bm.motor_travel_m_per_rad["x"]
    np.testing.assert_allclose(run.meas_m[:, 0], motor, rtol=0, atol=1e-15)
    lag = np.abs(run.meas_m[:, 0] - run.table_position_m()[:, 0]).max()
    assert 1e-6 < lag < 1e-4
    dual = step(ideal)
    np.testing.assert_allclose(dual.meas_m, dual.table_position_m(), rtol=0, atol=1e-15)
    counts = step({"feedback": "motor"}).meas_m[:, 0] / (0.010 / 2**20)
    np.testing.assert_allclose(counts, np.rint(counts), rtol=0, atol=1e-6)


def test_a_semi_closed_loop_is_tuned_on_the_motor_and_holds_the_table(tmp_path):
    """`twin tune --feedback motor` on the heavy axis designs both loops on the motor's transfer
    function (collocated: a velocity loop of 173 Hz against 30 Hz on the scale) with the
    margins met, and bounds the table's response peak to 3 dB: on the twin the table
    overshoots a 1 mm step by under 10 % (45 % without the bound); the scenario it writes
    closes the loops on the motors.  The machine's default, dual feedback, keeps the motor's
    velocity loop and closes position on the scale: the table settles faster than with both
    loops on the scale, without overshoot."""
    from twin.commissioning.tuning import GAIN_MARGIN_DB, PHASE_MARGIN_DEG, scenario_text, tune, verify

    machine = str(Path(__file__).resolve().parent.parent / "examples" / "machines" / "mid_size_xy.toml")
    heavy = {"x_table_mass_kg": 200.0, "x_motor_inertia_kg_m2": 1.99e-3}
    motor, table, dual = (
        tune(machine, heavy, feedback="motor"),
        tune(machine, heavy, feedback="table"),
        tune(machine, heavy),
    )
    assert dual["feedback"] == "dual"
    x = motor["axes"]["x"]
    assert x["phase_margin_deg"] >= PHASE_MARGIN_DEG
    assert x["gain_margin_db"] >= GAIN_MARGIN_DB
    assert x["velocity_loop"]["crossover_hz"] > 3 * table["axes"]["x"]["velocity_loop"]["crossover_hz"]
    assert dual["axes"]["x"]["velocity_loop"]["crossover_hz"] == x["velocity_loop"]["crossover_hz"]
    assert '[sensors]\nfeedback = "motor"' in scenario_text(motor, machine)
    checked = verify(motor, machine, tmp_path)
    assert checked["x"]["step_overshoot_pct"] < 10.0
    on_scale, both = verify(table, machine, tmp_path), verify(dual, machine, tmp_path)
    assert both["x"]["step_overshoot_pct"] < 1.0
    assert both["x"]["step_settling_s"] < 0.8 * on_scale["x"]["step_settling_s"]


@pytest.mark.slow  # six realizations at the default 16 s (tests/test_frf_oracle.py: shorter ones)
def test_a_multisine_with_friction_gives_its_best_linear_approximation_without_phantoms():
    """mid_size_xy X (Coulomb friction 15 N), the table sensor, the default 16 s multisine: one
    periodic multisine made friction's distortion repeat and look coherent (48 resonances
    reported, 36 Hz to 875 Hz); over six realizations of random phases the distortion lowers
    the coherence and widens the BLA's scatter, and only the model's two modes are found (the
    first within 1 % at the low crest factor's RMS, 4 % at random phases' 2.1 times less:
    friction damps it).  The distortion is measured where the model says it is large: within
    30 dB of the BLA between 300 and 600 Hz."""
    r = measure(MID, FrfSettings(excitation="multisine"))
    assert r.levels is not None and r.levels.realizations == 6
    assert len(r.resonances_hz) == len(r.model_resonances_hz) == 2
    np.testing.assert_allclose(r.resonances_hz, r.model_resonances_hz, rtol=0.01)
    f, mag = np.array(r.frequency_hz), np.array(r.magnitude_db)
    distortion = np.array([-np.inf if v is None else v for v in r.to_json()["distortion_db"]])
    band = (f > 300) & (f < 600)
    assert np.median(mag[band] - distortion[band]) < 30


def test_a_multisine_on_a_linear_machine_equals_its_transfer_function():
    """Without Coulomb friction the machine is linear: the BLA equals the transfer function's
    ZOH response (python-control) within 0.3 dB on every line to 500 Hz (1.2 dB to 1 kHz, where
    MuJoCo's explicit springs at a 50 us step stiffen the top mode by 0.6 %), with coherence
    over 0.99, and the nonlinear distortion and the noise lie 60 dB or more below it."""
    linear = {"x_friction_coulomb_N": 0.0, "y_friction_coulomb_N": 0.0}
    r = measure(MID, FrfSettings(excitation="multisine", duration_s=10.0), linear)
    assert r.levels is not None and r.levels.realizations == 4
    f, mag, model = r.frequency_hz, r.magnitude_db, r.model_magnitude_db
    assert np.abs(mag - model)[f <= 500].max() < 0.3
    assert np.abs(mag - model).max() < 1.2
    assert min(r.coherence) > 0.99
    for level in ("distortion_db", "noise_db"):
        values = np.array([-np.inf if v is None else v for v in r.to_json()[level]])
        assert (mag - values).min() > 60
    assert len(r.resonances_hz) == 2


def test_a_multisine_too_short_for_its_realizations_is_refused():
    with pytest.raises(TwinInputError, match=r"4 realizations of 3 periods: at least 9\.9 s"):
        measure(MID, FrfSettings(excitation="multisine", duration_s=8.0))


def test_the_multisine_estimator_recovers_a_known_filter_and_its_distortion():
    """An independent oracle for the estimator (no twin): the excitation through a known
    discrete filter and an integrator (scipy's lfilter: the output drifts, as an open loop's
    position does), read back at every excited line as scipy's freqz within 1e-9 dB, with no
    distortion; a cubic inside (odd, as friction is) shows as distortion with the coherence
    below 1, and the BLA within 1 dB of the filter in the median (the cubic's linear part)."""
    from twin.commissioning.frf import excitation_signal, multisine_frf

    dt, n = 1e-4, 4 * 3 * 8192
    d = excitation_signal("multisine", n, dt, amplitude=1.0, f_max_hz=800.0, seed=7)
    b, a = signal.butter(2, 300.0, fs=1.0 / dt)
    w = signal.lfilter(b, a, d)
    r = multisine_frf(d, d, np.cumsum(w), dt=dt, f_max_hz=800.0)
    _, h = signal.freqz(b, np.convolve(a, [1.0, -1.0]), worN=r["frequency_hz"], fs=1.0 / dt)
    level = 20 * np.log10(np.abs(h))
    assert r["realizations"] == 4
    np.testing.assert_allclose(20 * np.log10(np.abs(r["frf"] / h)), 0.0, atol=1e-9)
    assert np.all(np.isneginf(r["distortion_db"]) | (r["distortion_db"] < level - 150))
    r = multisine_frf(d, d, np.cumsum(w + 0.3 * w**3 / np.abs(w).max() ** 2), dt=dt, f_max_hz=800.0)
    assert np.median(r["distortion_db"] - level) > -60
    assert min(r["coherence"]) < 0.99
    assert np.median(np.abs(20 * np.log10(np.abs(r["frf"] / h)))) < 1.0


def test_the_multisine_period_keeps_its_lines_with_a_low_crest_factor():
    """The swapped period's DFT (numpy's, independent of the swapping) has unit amplitude on
    every excited line and nothing elsewhere, and its crest factor (peak / RMS) is under 1.8
    where the same random phases give over 3."""
    from twin.commissioning.frf import MULTISINE_PERIOD, low_crest_period

    lines = np.arange(1, 820)
    phasors = np.exp(2j * np.pi * np.random.default_rng(5).random(len(lines)))
    period = low_crest_period(phasors, lines)
    spectrum = np.fft.rfft(period) * 2 / MULTISINE_PERIOD
    np.testing.assert_allclose(np.abs(spectrum[lines]), 2.0 / MULTISINE_PERIOD, rtol=1e-9)
    others = np.delete(np.abs(spectrum), lines)
    assert others.max() < 1e-12
    random_phases = np.fft.irfft(np.r_[0, phasors, np.zeros(MULTISINE_PERIOD // 2 - len(lines))], MULTISINE_PERIOD)

    def crest(x):
        return np.abs(x).max() / np.sqrt(np.mean(x**2))

    assert crest(random_phases) > 3.0
    assert crest(period) < 1.8


def test_a_mode_is_unreliable_where_a_line_near_it_is_incoherent():
    """The lowest coherence within 5 % of the mode decides (a dip 6 % away does not), and the
    incoherent lines are listed as bands, runs merged across gaps of up to three lines."""
    from twin.commissioning.frf import incoherent_bands, mode_quality

    freqs = np.arange(1.0, 201.0)
    coherence = np.ones_like(freqs)
    coherence[[93, 149, 151, 155, 160]] = 0.5  # 94 Hz; 150, 152, 156 Hz (one band); 161 Hz
    sound = mode_quality("resonance", 100.0, freqs=freqs, coherence=coherence, distortion_db=None)
    assert sound.unreliable is None and sound.coherence == 1.0
    doubtful = mode_quality("antiresonance", 98.0, freqs=freqs, coherence=coherence, distortion_db=np.full(200, -20.0))
    assert doubtful.coherence == 0.5 and doubtful.distortion_db == -20.0
    assert doubtful.unreliable is not None and doubtful.unreliable.startswith("coherence 0.500 < 0.95 within 5 % of it")
    assert incoherent_bands(freqs, coherence) == [[94.0, 94.0], [150.0, 156.0], [161.0, 161.0]]


def test_the_cli_marks_an_unreliable_mode_with_its_reason():
    """`twin frf` prints a mode with low coherence near it as unreliable, with the coherence,
    and the incoherent bands (mid_size_xy X, its friction, the motor's sensor, a 0.45 V
    multisine: the first resonance, 2-3 % low, and the anti-resonances)."""
    from cli_process import twin

    r = twin("frf", MID, "--sensor", "motor", "--excitation", "multisine", "--amplitude", "0.45", "--duration", "9.9")
    assert r.returncode == 0, r.stderr
    listed = next(line for line in r.stdout.splitlines() if line.strip().startswith("resonances (Hz):"))
    first = float(listed.split(":")[1].split(",")[0].split()[0])
    assert 165 < first < 175.02 * 0.99 and "(unreliable)" in listed.split(",")[0]
    reason = next(
        line for line in r.stdout.splitlines() if line.strip().startswith(f"unreliable resonance {first:.1f} Hz")
    )
    coherence = float(reason.split("coherence ")[1].split()[0])
    assert coherence < 0.95
    assert "coherence < 0.95 (a mode there is unreliable or missing) at " in r.stdout
