"""The user's own machine: machine files, compliance, FRF measurement, calibration, tuning."""

import math
from pathlib import Path

import control
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from cli_process import twin as _twin

from twin.commissioning.calibration import calibrate, replay
from twin.commissioning.frf import FrfSettings, excitation_signal, measure, peaks
from twin.commissioning.tuning import tune
from twin.errors import TwinInputError
from twin.fidelity import time_response_nrmse
from twin.machines import build, get_machine

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "machines"
MID = str(EXAMPLES / "mid_size_xy.toml")
LINEAR = str(EXAMPLES / "linear_motor_xy.toml")
RIGID = {"x_k_axial_N_per_m": math.inf, "y_k_axial_N_per_m": math.inf}
TORSION_RIGID = {
    f"{a}_{key}": math.inf for a in "xy" for key in ("k_torsion_N_m_per_rad", "k_screw_torsion_N_m_per_rad")
}
RIGID |= TORSION_RIGID
NO_COULOMB = {"x_friction_coulomb_N": 0.0, "y_friction_coulomb_N": 0.0}


def test_linear_motor_file_equals_the_bundled_machine():
    from twin.api import run

    bundled, from_file = build("linear_motor_xy"), build(LINEAR)
    assert bundled.plant == from_file.plant
    np.testing.assert_array_equal(bundled.model.body_subtreemass, from_file.model.body_subtreemass)
    settings = {"duration_s": 0.3}
    a = run("choi1999_pid_cutting", **settings).summary
    b = run(
        "choi1999_pid_cutting",
        machine=LINEAR,
        overrides={"x_friction_coulomb_N": 2.94, "y_friction_coulomb_N": 1.90},
        **settings,
    ).summary
    assert {k: v for k, v in a.items() if k != "machine"} == {k: v for k, v in b.items() if k != "machine"}


def test_generated_model_masses_and_rigid_transfer_function():
    """The MJCF's masses are the file's (X carries Y's table, motor, screw and nut and the
    workpiece) and the rigid transfer function is the closed form K n / p / (M s^2 + c s)."""
    machine = get_machine(MID)
    bm = build(MID, RIGID)
    p = machine.resolve(RIGID)
    screw_y = 7850 * math.pi * 0.032**2 * 0.7 / 4
    carried = p["y_table_mass_kg"] + p["y_motor_mass_kg"] + p["y_nut_mass_kg"] + screw_y + p["workpiece_mass_kg"]
    x_table = bm.model.body("x_table").id
    assert bm.model.body_subtreemass[x_table] == pytest.approx(p["x_table_mass_kg"] + p["x_nut_mass_kg"] + carried)
    lead = 0.010 / (2 * math.pi)
    j_screw = math.pi * 7850 * 0.032**4 * 1.0 / 32
    mass = (p["x_motor_inertia_kg_m2"] + j_screw + p["x_coupling_inertia_kg_m2"]) / lead**2
    mass += p["x_table_mass_kg"] + p["x_nut_mass_kg"] + carried
    gain = 0.49 * 1.5 / lead
    g = bm.plant[0][0]
    assert len(g.den) == 3
    assert g.num[-1] / g.den[0] == pytest.approx(gain / mass, rel=1e-12)
    assert g.den[1] / g.den[0] == pytest.approx(150.0 / mass, rel=1e-12)
    assert bm.model.ntendon == 0
    assert bm.model.neq == 4  # rigid: today's gear equalities only


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        RIGID,
        {"x_k_axial_N_per_m": math.inf, "y_k_torsion_N_m_per_rad": math.inf},
        {"x_k_torsion_N_m_per_rad": math.inf},
    ],
    ids=["compliant", "rigid", "mixed", "screw torsion alone"],
)
def test_mujoco_mass_matrix_equals_the_transfer_functions_masses(overrides):
    """One mass budget: MuJoCo's own joint-space inertia (mj_fullM at the start) in table travel,
    motor n^2/p^2, screw 1/p^2, table 1 (the table's slide carries all that rides on it), is the
    chain's masses for every axis, with the rigid links merged as the chain merges them."""
    _assert_one_mass_budget(MID, overrides)


@pytest.mark.parametrize("name", ["mid_size_xy", "compact_xy", "heavy_xy"])
def test_every_example_machine_has_one_mass_budget(name):
    """The same for every example ball-screw machine file (the catalogue machines compute their
    stiffnesses from the shaft)."""
    _assert_one_mass_budget(str(EXAMPLES / f"{name}.toml"), {})


def _assert_one_mass_budget(path: str, overrides: dict) -> None:
    import mujoco

    machine = get_machine(path)
    bm = build(path, overrides, timestep_s=2e-5)  # a rigid coupling leaves the screw's 1 kHz mode
    p = machine.resolve(overrides)
    data = mujoco.MjData(bm.model)
    mujoco.mj_forward(bm.model, data)
    full = np.zeros((bm.model.nv, bm.model.nv))
    mujoco.mj_fullM(bm.model, data, full)
    for a in ("x", "y"):
        lead = p[f"{a}_screw_lead_m"] / (2 * math.pi)
        n = p[f"{a}_gear_ratio"]

        def diagonal(joint):
            dof = bm.model.joint(joint).dofadr[0]
            return full[dof, dof]

        masses = [diagonal(f"{a}_motor") * n**2 / lead**2, diagonal(f"{a}_screw") / lead**2, diagonal(f"{a}_table")]
        if math.isinf(machine.axial_N_per_m(p, a)):
            masses[1:] = [masses[1] + masses[2]]
        if math.isinf(machine.torsion_N_m_per_rad(p, a)):
            masses[:2] = [masses[0] + masses[1]]
        np.testing.assert_allclose(machine.chain(p, a).masses_kg, masses, rtol=1e-12)


def test_the_screws_torsion_is_in_series_with_the_coupling():
    """k = 1 / (1/k_coupling + 1/k_screw) in the chain (in table travel, / p^2) and on the MJCF's
    tendon; the screw's alone where the coupling is rigid; rigid only where both are."""
    machine = get_machine(MID)
    for overrides, expected in (
        ({}, 1 / (1 / 5000.0 + 1 / 8.3e3)),
        ({"x_k_torsion_N_m_per_rad": math.inf}, 8.3e3),
        ({"x_k_screw_torsion_N_m_per_rad": math.inf}, 5000.0),
    ):
        p = machine.resolve(overrides)
        lead = p["x_screw_lead_m"] / (2 * math.pi)
        assert machine.chain(p, "x").springs_N_per_m[0] == pytest.approx(expected / lead**2, rel=1e-12)
        model = build(MID, overrides, timestep_s=2e-5).model
        assert model.tendon_stiffness[model.tendon("x_gear_spring").id] == pytest.approx(expected, rel=1e-12)
    assert len(machine.chain(machine.resolve(TORSION_RIGID), "x").masses_kg) == 2


def test_a_physics_step_too_coarse_for_the_fastest_mode_is_refused_with_the_step_that_would_do():
    """The fastest mode is the largest |pole| of the chains (719 Hz, Y's torsion); 2 pi f h at
    most 0.3 gives a step of at most 6.6e-5 s: 5e-5 builds, 1e-4 is refused naming the step."""
    machine = get_machine(MID)
    p = machine.resolve({})
    poles = [np.abs(np.roots(machine.chain(p, a).transfer_function().den)).max() for a in "xy"]
    fastest = max(poles) / (2 * math.pi)
    assert machine.fastest_mode_hz(p) == pytest.approx(fastest, rel=1e-12)
    assert 2 * math.pi * fastest * 5e-5 < 0.3 < 2 * math.pi * fastest * 1e-4
    build(MID, timestep_s=5e-5)
    with pytest.raises(TwinInputError) as refused:
        build(MID, timestep_s=1e-4)
    assert refused.value.field == "timestep_s"
    assert f"{0.3 / (2 * math.pi * fastest):.2g} s" in str(refused.value)


@pytest.mark.parametrize("machine", ["googol_xy", MID])
def test_twin_mjcf_writes_the_model_the_twin_simulates(machine, tmp_path):
    """`twin mjcf` writes the MJCF with the values in (here a heavier workpiece): MuJoCo reads it
    back with the twin's bodies, masses and stiffnesses (to the 6 digits MuJoCo writes XML with),
    joints, tendons and step."""
    import mujoco
    from typer.testing import CliRunner

    from twin.cli import app

    symbol = "workpiece_mass_kg" if machine == MID else "m_workpiece"
    out = tmp_path / "model.xml"
    result = CliRunner().invoke(app, ["mjcf", machine, "--out", str(out), "--set", f"{symbol}=31.5"])
    assert result.exit_code == 0, result.output
    ours = build(machine, {symbol: 31.5}).model
    theirs = mujoco.MjModel.from_xml_path(str(out))
    assert theirs.body("workpiece").mass[0] == pytest.approx(31.5)
    np.testing.assert_allclose(theirs.body_subtreemass, ours.body_subtreemass, rtol=5e-6)
    assert (theirs.njnt, theirs.ntendon, theirs.neq, theirs.nu) == (ours.njnt, ours.ntendon, ours.neq, ours.nu)
    np.testing.assert_allclose(theirs.tendon_stiffness, ours.tendon_stiffness, rtol=5e-6)
    assert theirs.opt.timestep == ours.opt.timestep


def test_compliant_modes_at_the_closed_forms():
    """Axial compliance alone: a two-mass system, resonance sqrt(k (1/m + 1/M)), anti-resonance
    (motor side) sqrt(k/m): the model's poles and zeros there, the twin's time response equal to
    the 4th-order model's, and the measured peaks where the model's FRF has them, within 2 % of
    the (undamped) closed forms (the 4 % damping moves the motor-side peaks up by 1-2 %; the
    measured peak sits 0.9 % above the model FRF's, the 0.6 Hz resolution and the sampled loop)."""
    overrides = {**TORSION_RIGID, **NO_COULOMB}
    machine = get_machine(MID)
    p = machine.resolve(overrides)
    chain = machine.chain(p, "x")
    m_table, m_rotor = chain.masses_kg[1], chain.masses_kg[0]
    k = p["x_k_axial_N_per_m"]
    resonance = math.sqrt(k * (1 / m_table + 1 / m_rotor)) / (2 * math.pi)
    anti = math.sqrt(k / m_table) / (2 * math.pi)
    bm = build(MID, overrides)
    g_motor = bm.motor_plant[0]
    poles = [abs(r) / (2 * math.pi) for r in np.roots(bm.plant[0][0].den) if r.imag > 0]
    zeros = [abs(r) / (2 * math.pi) for r in np.roots(g_motor.num) if r.imag > 0]
    assert poles == [pytest.approx(resonance, rel=1e-3)]  # |pole| = w_n (lightly damped)
    assert zeros == [pytest.approx(anti, rel=1e-3)]
    assert time_response_nrmse(bm, bm.plant_lti(), duration_s=0.3) < 0.005
    r = measure(MID, FrfSettings(sensor="motor", duration_s=8.0), overrides)
    f, model = np.array(r.frequency_hz), np.array(r.model_magnitude_db)
    model_peak, model_dip = peaks(f, model, coherence=np.ones_like(f))
    assert r.resonances_hz == [pytest.approx(model_peak[0], rel=0.015)] == [pytest.approx(resonance, rel=0.02)]
    assert r.antiresonances_hz == [pytest.approx(model_dip[0], rel=0.015)] == [pytest.approx(anti, rel=0.02)]


@pytest.mark.parametrize("machine", ["cncmt", "googol_xy", "coupled_servo_xy", "linear_motor_xy"])
def test_frf_of_a_rigid_machine_equals_its_transfer_function(machine):
    """The papers' machines (no friction by default): the measured FRF within 0.6 dB of the
    transfer function on every coherent line, 1.2 Hz - 1 kHz (the largest departures are the
    lowest lines, where the 20 Hz loop leaves the least response), and no peaks."""
    r = measure(machine, FrfSettings(), {})
    assert r.coherent_share > 0.95
    assert r.max_model_error_db < 0.6
    assert r.resonances_hz == []
    assert r.antiresonances_hz == []
    assert set(r.parameters) == set(get_machine(machine).parameters)


@pytest.mark.parametrize("kind", ["prbs", "chirp", "multisine"])
def test_excitations_reach_their_amplitude_and_band(kind):
    u = excitation_signal(kind, 20000, 1e-4, amplitude=2.0, f_max_hz=500.0, seed=1)
    assert np.abs(u).max() == pytest.approx(2.0, rel=1e-6)
    spectrum = np.abs(np.fft.rfft(u)) ** 2
    f = np.fft.rfftfreq(len(u), 1e-4)
    assert spectrum[(f > 5) & (f < 400)].sum() > 0.5 * spectrum.sum()


def test_calibration_recovers_hidden_parameters(tmp_path):
    hidden = {"x_table_mass_kg": 100.0, "x_friction_viscous_N_s_per_m": 180.0, "x_friction_coulomb_N": 18.0}
    dt, n = 1e-4, 6000
    u = np.zeros((n, 2))
    u[:, 0] = excitation_signal("prbs", n, dt, amplitude=2.0, f_max_hz=50.0, seed=3)
    y = replay(build(MID, hidden), dt, u, np.zeros(2))[:, 0]
    y = y + np.random.default_rng(0).normal(0.0, 2e-7, n)  # sensor noise, 0.2 um
    path = tmp_path / "trace.parquet"
    pq.write_table(pa.table({"time_s": np.arange(n) * dt, "u_x_V": u[:, 0], "pos_x_m": y}), path)
    r = calibrate(MID, path, list(hidden))
    for name, value in hidden.items():
        assert r.fitted[name] == pytest.approx(value, rel=0.01)
        assert 0 < r.statistical_errors[name] < 0.01 * value
        # the model's own error (the step halved) is in the standard error: the viscous
        # friction's, beside Coulomb friction's soft constraint, is 2 % of it
        assert r.standard_errors[name] >= r.statistical_errors[name]
    assert r.fit_index_pct.before < 95 < r.fit_index_pct.after
    assert r.fit_index_pct.twin == pytest.approx(r.fit_index_pct.after, abs=1e-6)
    out = tmp_path / "calibrated.toml"
    text = _twin("calibrate", MID, "--trace", str(path), "--fit", ",".join(hidden), "--out", str(out))
    assert text.returncode == 0, text.stderr
    assert get_machine(str(out)).parameters["x_table_mass_kg"].value == pytest.approx(100.0, rel=0.01)


def test_calibration_names_a_combination_it_cannot_identify(tmp_path):
    """X alone moves: its table and Y's table enter only as their sum."""
    dt, n = 1e-4, 3000
    u = excitation_signal("prbs", n, dt, amplitude=2.0, f_max_hz=50.0, seed=3)
    y = replay(build(MID), dt, np.c_[u, np.zeros(n)], np.zeros(2))[:, 0]
    y = y + np.random.default_rng(1).normal(0.0, 2e-7, n)
    path = tmp_path / "trace.csv"
    path.write_text(
        "time_s,u_x_V,pos_x_m\n"
        + "\n".join(f"{i * dt!r},{float(a)!r},{float(b)!r}" for i, (a, b) in enumerate(zip(u, y)))
    )
    r = calibrate(MID, path, ["x_table_mass_kg", "y_table_mass_kg"])
    assert r.unidentifiable == {
        "x_table_mass_kg": "the data determine only its combination with y_table_mass_kg",
        "y_table_mass_kg": "the data determine only its combination with x_table_mass_kg",
    }
    assert r.fitted == {}
    assert r.parameters["x_table_mass_kg"] == 90.0  # both held at nominal


def test_calibration_holds_a_combination_together_and_fits_the_rest_again(tmp_path):
    """X's table 23 % heavy, and the fit asked for X's and Y's table masses and X's viscous
    friction on an X trace: both masses are held at nominal together (not one of them left at
    the value fitted with the other) and the friction is fitted again without them, so the fit
    index rises from the nominal's."""
    dt, n = 1e-4, 3000
    u = excitation_signal("prbs", n, dt, amplitude=2.0, f_max_hz=50.0, seed=3)
    y = replay(build(MID, {"x_table_mass_kg": 110.7}), dt, np.c_[u, np.zeros(n)], np.zeros(2))[:, 0]
    y = y + np.random.default_rng(1).normal(0.0, 2e-7, n)
    path = tmp_path / "trace.parquet"
    pq.write_table(pa.table({"time_s": np.arange(n) * dt, "u_x_V": u, "pos_x_m": y}), path)
    r = calibrate(MID, path, ["x_table_mass_kg", "y_table_mass_kg", "x_friction_viscous_N_s_per_m"])
    assert set(r.unidentifiable) == {"x_table_mass_kg", "y_table_mass_kg"}
    assert list(r.fitted) == ["x_friction_viscous_N_s_per_m"]
    assert r.parameters["x_table_mass_kg"] == 90.0
    assert r.parameters["y_table_mass_kg"] == 45.0
    assert r.solver.converged
    assert r.fit_index_pct.after > r.fit_index_pct.before


def test_calibration_recovers_a_compliant_hidden_variant(tmp_path):
    """The issue's hidden variant: table +23 %, axial stiffness -31 %, viscous friction 210 N s/m
    (Coulomb 15 N as the file), 0.2 um noise, a 500 Hz PRBS. From the nominal alone the solve
    converged at +62 % stiffness with a 0.2 % standard error (a local minimum: the response is
    not convex in a stiffness); with the stiffness's starts it recovers all three within 0.5 %
    and the fit index of the truth itself."""
    hidden = {"x_table_mass_kg": 110.7, "x_k_axial_N_per_m": 1.0005e8, "x_friction_viscous_N_s_per_m": 210.0}
    dt, n = 1e-4, 6000
    u = np.zeros((n, 2))
    u[:, 0] = excitation_signal("prbs", n, dt, amplitude=2.0, f_max_hz=500.0, seed=3)
    y = replay(build(MID, hidden), dt, u, np.zeros(2))[:, 0] + np.random.default_rng(0).normal(0.0, 2e-7, n)
    path = tmp_path / "trace.parquet"
    pq.write_table(pa.table({"time_s": np.arange(n) * dt, "u_x_V": u[:, 0], "pos_x_m": y}), path)
    r = calibrate(MID, path, list(hidden))
    assert r.solver.converged
    assert r.unidentifiable == {}
    for name, value in hidden.items():
        assert r.fitted[name] == pytest.approx(value, rel=0.005)
    truth = replay(build(MID, hidden), dt, u, np.zeros(2))[:, :1]
    from twin.metrics import fit_index

    assert r.fit_index_pct.after == pytest.approx(float(fit_index(y[:, None], truth)[0]), abs=0.01)


def test_calibration_fits_the_velocity_where_the_positions_cost_is_rugged(tmp_path):
    """The catalogue's hidden variant (X's table +20 %, axial stiffness -30 %, viscous friction
    +20 %) from `twin excite --simulate` (0.6 s, open loop, 500 Hz PRBS): fitting the position
    alone stopped at -7.9 % mass, +3.4 % stiffness, -4.0 % friction with standard errors of
    0.03 % (the open loop's position cost has several minima between the nominal and the truth:
    one sticking shifts the rest of the record); through the velocity first, all three within
    1e-6, the residual at the trace's noise and nothing left unexcited."""
    from twin.commissioning.calibration import excitation_trace, write_table

    hidden = {"x_table_mass_kg": 108.0, "x_k_axial_N_per_m": 1.015e8, "x_friction_viscous_N_s_per_m": 180.0}
    path = tmp_path / "hidden.parquet"
    write_table(excitation_trace(MID, overrides=hidden, simulate_twin=True), path)
    r = calibrate(MID, path, list(hidden))
    for name, value in hidden.items():
        assert r.fitted[name] == pytest.approx(value, rel=1e-6)
    assert r.solver.against_noise is not None and r.solver.against_noise.at_noise_floor
    assert r.not_excited == {}
    assert r.excited_band_hz == pytest.approx(0.908 * 1e4 / 8, abs=20)  # the PRBS's main lobe, 2 lines


def test_a_fit_above_the_traces_noise_says_so(tmp_path):
    """The viscous friction 40 % high and only the table's mass fitted: the fit converges, its
    residual is far above the trace's 0.2 um noise, and the result says so."""
    dt, n = 1e-4, 3000
    u = np.zeros((n, 2))
    u[:, 0] = excitation_signal("prbs", n, dt, amplitude=2.0, f_max_hz=50.0, seed=3)
    y = replay(build(MID, {"x_friction_viscous_N_s_per_m": 210.0}), dt, u, np.zeros(2))[:, 0]
    y = y + np.random.default_rng(2).normal(0.0, 2e-7, n)
    path = tmp_path / "trace.parquet"
    pq.write_table(pa.table({"time_s": np.arange(n) * dt, "u_x_V": u[:, 0], "pos_x_m": y}), path)
    r = calibrate(MID, path, ["x_table_mass_kg"])
    noise = r.solver.against_noise
    assert noise is not None and noise.noise_floor_m == pytest.approx(2e-7, rel=0.1)
    assert noise.residual_rms_m > 1.2 * noise.noise_floor_m
    assert not noise.at_noise_floor
    assert "a parameter not fitted" in noise.note


def test_the_noise_floor_of_a_trace():
    """White noise on a smooth motion read back within 5 %; an encoder's quantization alone
    (a slow ramp on a 1 um grid) is its resolution / sqrt(12)."""
    from twin.commissioning.calibration import noise_floor

    t = np.arange(20000) * 1e-4
    smooth = 1e-3 * np.sin(2 * np.pi * 3 * t)
    noisy = smooth + np.random.default_rng(0).normal(0.0, 5e-7, t.size)
    assert noise_floor(noisy[:, None], np.zeros(1)) == pytest.approx(5e-7, rel=0.05)
    ramp = np.round(1e-3 * t / 1e-6) * 1e-6
    assert noise_floor(ramp[:, None], np.array([1e-6])) == pytest.approx(1e-6 / math.sqrt(12), rel=1e-12)


def test_a_stiffness_beyond_the_inputs_band_is_named_with_the_excitation_that_would(tmp_path):
    """A 50 Hz PRBS excites to its main lobe's end (0.908 of its 125 Hz bit rate): X's axial
    mode (175 Hz) needs 1.5 x that, so the axial stiffness is named, with `twin excite` to
    270 Hz; the table's mass is not a stiffness and is not named."""
    from twin.commissioning.calibration import excitation_trace, write_table

    path = tmp_path / "slow.csv"
    write_table(excitation_trace(MID, f_max_hz=50.0, simulate_twin=True), path)
    r = calibrate(MID, path, ["x_table_mass_kg", "x_k_axial_N_per_m"])
    assert r.excited_band_hz == pytest.approx(0.908 * 1e4 / 80, abs=20)
    assert list(r.not_excited) == ["x_k_axial_N_per_m"]
    assert "its mode at 175 Hz" in r.not_excited["x_k_axial_N_per_m"]
    assert f"twin excite {MID} --f-max 270" in r.not_excited["x_k_axial_N_per_m"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--out", "trace.txt"], "--out = 'trace.txt': must be a .csv or .parquet file"),
        (["--out", "t.csv", "--f-max", "5"], "--f-max = 5.0: must be in [10, 4000] Hz"),
        (["--out", "t.csv", "--duration", "1e9"], "--duration = 1000000000.0: must be in [0.05, 60] s"),
        (["--out", "t.csv", "--axis", "z"], "--axis = 'z': machine axes are ['x', 'y']"),
        (["--out", "t.csv", "--seed", "-5"], "--seed = -5: must be in [0, 2**32)"),
    ],
)
def test_twin_excite_refuses_bad_options_in_one_line(tmp_path, monkeypatch, args, message):
    from typer.testing import CliRunner

    from twin.cli import app

    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["excite", MID, *args])
    assert result.exit_code == 2
    assert result.output == f"error: {message}\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "rows, message",
    [
        ("time_s,u_x_V,pos_x_m\n" + "".join(f"{i * 1e-4},0.1,{i * 1e-6}\n" for i in range(50)), "too short"),
        ("time_s,u_x,pos_x_m\n" + "".join(f"{i * 1e-4},0.1,{i * 1e-6}\n" for i in range(1000)), "u_x"),
        (
            "time_s,u_x_V,pos_x_m\n"
            + "".join(f"{i * 1e-4},0.1,{'nan' if i == 7 else i * 1e-6}\n" for i in range(1000)),
            "row 7",
        ),
        (
            "time_s,u_x_V,pos_x_m\n" + "".join(f"{(i if i != 9 else 3) * 1e-4},0.1,{i * 1e-6}\n" for i in range(1000)),
            "increase",
        ),
        ("time_s,u_x_V,pos_x_m\n" + "".join(f"{i * 1e-4},0.0,0.0\n" for i in range(1000)), "never moves"),
    ],
)
def test_bad_traces_give_one_error_line(tmp_path, rows, message):
    path = tmp_path / "trace.csv"
    path.write_text(rows)
    r = _twin("calibrate", MID, "--trace", str(path), "--fit", "x_table_mass_kg")
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1
    assert r.stderr.startswith("error: ")
    assert message in r.stderr


@pytest.mark.parametrize(
    "edit, field",
    [
        (("table_mass_kg = 90.0", "table_mass_kg = -90.0"), "axes.x.table_mass_kg"),
        (("amplifier_gain_A_per_V = 1.5\n", ""), "axes.y"),
        (('stacking = ["x", "y"]', 'stacking = ["x"]'), "axes"),
        (("screw_lead_m = 0.010", "screw_lead_m = [0.01"), "malformed TOML"),
    ],
)
def test_bad_machine_files_give_one_error_line(tmp_path, edit, field):
    path = tmp_path / "mill.toml"
    path.write_text(Path(MID).read_text().replace(*edit, 1))
    r = _twin("frf", str(path))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1
    assert field in r.stderr


@pytest.fixture(scope="module")
def tuned():
    return tune(MID)


@pytest.mark.parametrize("name", ["mid_size", "compact", "heavy", "sgm7j"])
def test_the_part_scenario_holds_the_tuned_gains(name, tuned):
    """examples/machines/<name>_part.toml carries `twin tune`'s gains for <name>_xy.toml,
    rounded to 4 digits."""
    import tomllib

    scenario = tomllib.loads((EXAMPLES / f"{name}_part.toml").read_text())
    assert scenario["machine"] == f"{name}_xy.toml"
    result = tuned if name == "mid_size" else tune(str(EXAMPLES / f"{name}_xy.toml"))
    for axis, design in result["axes"].items():
        written = scenario["controllers"][axis]["params"]
        for key, value in design["gains"].items():
            assert written.get(key, 0.0) == pytest.approx(value, rel=5e-4), (axis, key)


def _velocity_controller(gains: dict, dt: float):
    """The tuned PI and filter by Tustin, built with python-control alone."""
    from controllers.kinds.generic import velocity_filter

    f = velocity_filter(gains["notch_hz"], 20.0, 0.5, gains["lowpass_hz"])
    pi = control.tf([gains["kp_vel"] * gains["ti_vel_s"], gains["kp_vel"]], [gains["ti_vel_s"], 0.0])
    return control.c2d(pi * control.tf(list(f.num), list(f.den)), dt, "tustin")


def _velocity_loop(bm, i: int, gains: dict, dt: float):
    """Axis ``i``'s sampled velocity loop from the tuned gains on the motor's transfer function
    (dual feedback): ZOH plant and delay, the PI and filter by Tustin, the backward-difference
    velocity."""
    z = control.tf([1.0, 0.0], [1.0], dt)
    loop = _velocity_controller(gains, dt) * _sampled(bm.motor_plant[i], bm, dt) * (z - 1) / (dt * z)
    return control.minreal(loop, verbose=False)


def _sampled(plant, bm, dt: float):
    """``plant`` (a SisoTf) by zero-order hold with the drive's delay, in python-control."""
    gd = control.c2d(control.ss(control.tf(list(plant.num), list(plant.den))), dt, "zoh")
    return control.tf(gd) * control.tf([1.0], [1.0] + [0.0] * round(bm.delay_s / dt), dt)


def _margins(loop, dt: float, outer=None):
    """python-control's stability margins of a sampled loop, on a dense grid to Nyquist; with
    ``outer``, of ``outer / (1 + loop)`` (a position loop around it, from the two responses: the
    product's polynomials lose their roots near z = 1)."""
    w = 2 * math.pi * np.geomspace(0.1, 0.49999 / dt, 20_000)
    response = control.frequency_response(loop, w).complex.ravel()
    if outer is not None:
        response = control.frequency_response(outer, w).complex.ravel() / (1 + response)
    return control.stability_margins(control.frd(response, w))


def test_tuned_loops_meet_the_margins_checked_by_python_control(tuned):
    """The designer's margins over every crossing, recomputed by python-control's
    stability_margins on the loops built here from the returned gains (dual feedback: the
    velocity loop on the motor's transfer function, the position loop kp C_v G_table /
    (1 + C_v D G_motor)), and the velocity loop's gain margin checked by the closed loop's
    poles: stable at 0.8 and unstable at 1.25 times it."""
    r = tuned
    assert r["feedback"] == "dual"
    bm = build(MID)
    dt = r["control_period_s"]
    for i, design in enumerate(r["axes"].values()):
        g = design["gains"]
        velocity, position = design["velocity_loop"], design["position_loop"]
        assert design["phase_margin_deg"] >= 45
        assert design["gain_margin_db"] >= 6
        assert g["notch_hz"] > 0 or g["lowpass_hz"] > 0  # the axial resonance needs a filter
        loop = _velocity_loop(bm, i, g, dt)
        gm, pm, _, w_gm, _, _ = _margins(loop, dt)
        assert pm == pytest.approx(velocity["phase_margin_deg"], abs=0.05)
        assert 20 * math.log10(gm) == pytest.approx(velocity["gain_margin_db"], abs=0.01)
        assert w_gm / (2 * math.pi) == pytest.approx(velocity["gain_margin_hz"], rel=1e-3)
        # the position loop, on the table's scale around the velocity loop on the motor
        table = g["kp_pos"] * _velocity_controller(g, dt) * _sampled(bm.plant[i][i], bm, dt)
        gm, pm, _, w_gm, _, _ = _margins(loop, dt, outer=table)
        assert pm == pytest.approx(position["phase_margin_deg"], abs=0.05)
        assert 20 * math.log10(gm) == pytest.approx(position["gain_margin_db"], abs=0.01)
        critical = 10 ** (velocity["gain_margin_db"] / 20)
        for factor, stable in ((0.8, True), (1.25, False)):
            poles = control.poles(control.feedback(factor * critical * loop))
            # (a pole at z = 1 is the table's integrator the velocity's difference cancels)
            outside = (np.abs(poles) > 1.0 + 1e-9) & (np.abs(poles - 1.0) > 1e-4)
            assert (not outside.any()) is stable, (factor, np.abs(poles).max())


def test_the_twin_goes_unstable_past_the_tuned_gain_margins(tuned, tmp_path):
    """On the twin itself (MuJoCo, the servo cascade, a 10 mm circle at 2 m/min), one axis's
    velocity gain (its position loop all but open) or position gain times 0.8 or 1.25 of the
    reported gain margin: the first runs 0.5 s, the second diverges on that axis (its drive
    command runs away, ten times the other's at least)."""
    import copy

    from twin import api
    from twin.commissioning.tuning import scenario_text
    from twin.errors import SimulationDiverged

    for axis in ("x", "y"):
        for loop, gain in (("velocity_loop", "kp_vel"), ("position_loop", "kp_pos")):
            for factor in (0.8, 1.25):
                design = copy.deepcopy(tuned)
                gains = design["axes"][axis]["gains"]
                gains[gain] *= factor * 10 ** (design["axes"][axis][loop]["gain_margin_db"] / 20)
                if loop == "velocity_loop":
                    gains["kp_pos"] = 1e-3  # the velocity loop alone
                path = tmp_path / f"{axis}_{gain}_{factor}.toml"
                path.write_text(scenario_text(design, str(Path(MID).resolve()), "circle"))
                if factor < 1:
                    assert api.run(str(path), duration_s=0.5).status == "ok"
                else:
                    with pytest.raises(SimulationDiverged) as diverged:
                        api.run(str(path), duration_s=0.5)
                    # the axis that diverged is the one whose drive command ran away
                    command = np.abs(diverged.value.result.u_V).max(axis=0)
                    assert command[0 if axis == "x" else 1] > 10 * command[1 if axis == "x" else 0]


def test_a_sweep_and_a_scenario_take_a_machine_file(tmp_path):
    """A scenario names the machine file relative to itself; a sweep on a local Dask cluster
    varies the file's parameters, each row equal to a run with the same value."""
    import twin

    (tmp_path / "machines").mkdir()
    (tmp_path / "machines" / "mill.toml").write_text(Path(MID).read_text())
    scenario = tmp_path / "step.toml"
    scenario.write_text(
        'machine = "machines/mill.toml"\nduration_s = 0.05\ncontrol_period_s = 1e-4\n'
        '[controller]\ntype = "pid"\nparams = { kp = 2000.0, kd = 40.0, tf_s = 2e-4 }\n'
        '[reference]\ntype = "step"\namplitude_m = 1e-4\naxes = ["x"]\n'
    )
    sweep = twin.sweep(scenario, ["overrides.x_table_mass_kg=grid(60, 120, 2)"], workers=1, out=tmp_path / "sw")
    rows = sweep.table.to_pylist()
    assert [r["overrides.x_table_mass_kg"] for r in rows] == [60.0, 120.0]
    for row in rows:
        alone = twin.run(scenario, overrides={"x_table_mass_kg": row["overrides.x_table_mass_kg"]}).summary
        assert row["rmse_um_x"] == pytest.approx(alone["rmse_um"]["x"], abs=5e-4)  # the summary rounds to 1 nm
    assert rows[0]["rmse_um_x"] != rows[1]["rmse_um_x"]


def test_velocity_filter_notch_depth_and_low_pass():
    """The servo_cascade's filter: -20 dB at the notch centre, unity far from it; the low-pass
    at its corner |H| = 1/(2 x 0.7)."""
    from controllers.kinds.generic import velocity_filter

    notch = velocity_filter(200.0, 20.0, 0.5, 0.0)
    gain = lambda g, f: abs(np.polyval(g.num, 2j * np.pi * f) / np.polyval(g.den, 2j * np.pi * f))
    assert gain(notch, 200.0) == pytest.approx(0.1, rel=1e-12)
    assert gain(notch, 2.0) == pytest.approx(1.0, abs=1e-3)
    assert gain(notch, 20000.0) == pytest.approx(1.0, abs=1e-3)
    assert gain(velocity_filter(0.0, 20.0, 0.5, 300.0), 300.0) == pytest.approx(1 / 1.4, rel=1e-12)


def test_calibration_from_a_measured_frf(tmp_path):
    """An FRF (the model's, with hidden values and 1 % multiplicative noise) fitted through the
    transfer function recovers the hidden values within 1 %."""
    hidden = {"x_table_mass_kg": 40.0, "x_friction_viscous_N_s_per_m": 250.0}
    g = build(LINEAR, hidden).plant[0][0]
    f = np.geomspace(0.5, 200.0, 300)
    s = 2j * np.pi * f
    h = np.polyval(g.num, s) / np.polyval(g.den, s)
    h = h * (1 + 0.01 * np.random.default_rng(2).standard_normal(len(f)))
    path = tmp_path / "frf.csv"
    rows = [f"{a!r},{float(20 * np.log10(abs(b)))!r},{float(np.degrees(np.angle(b)))!r}" for a, b in zip(f.tolist(), h)]
    path.write_text("frequency_hz,magnitude_db,phase_deg\n" + "\n".join(rows) + "\n")
    r = calibrate(LINEAR, path, list(hidden))
    assert r.kind == "frf"
    for name, value in hidden.items():
        assert r.fitted[name] == pytest.approx(value, rel=0.01)
    assert r.fit_index_pct.after > r.fit_index_pct.before


def test_a_motor_sensor_frf_is_fitted_through_the_motors_transfer_function(tmp_path):
    """A motor-side FRF of mid_size_xy with X's table 23 % heavy and its nut 31 % soft (the
    model's with the drive's delay, 1 % noise): --sensor motor fits it through the motor's transfer function and
    recovers both within 1 %; through the table's (the old behaviour) the fit drifts to a 125 kg
    table on a near-rigid nut, its fit index 94.5 % against 98.6 %."""
    from twin.commissioning.frf import sensor_plant

    hidden = {"x_table_mass_kg": 110.7, "x_k_axial_N_per_m": 1.0005e8}
    g = sensor_plant(build(MID, hidden), 0, "motor")
    f = np.geomspace(2.0, 1000.0, 400)
    s = 2j * np.pi * f
    h = np.exp(-s * 2e-4) * np.polyval(g.num, s) / np.polyval(g.den, s)  # the file's 0.2 ms drive delay
    h = h * (1 + 0.01 * np.random.default_rng(3).standard_normal(len(f)))
    path = tmp_path / "frf.parquet"
    pq.write_table(
        pa.table({"frequency_hz": f, "magnitude_db": 20 * np.log10(np.abs(h)), "phase_deg": np.degrees(np.angle(h))}),
        path,
    )
    motor = calibrate(MID, path, list(hidden), sensor="motor")
    for name, value in hidden.items():
        assert motor.fitted[name] == pytest.approx(value, rel=0.01)
    table = calibrate(MID, path, list(hidden), sensor="table")
    assert table.fitted["x_table_mass_kg"] > 1.1 * hidden["x_table_mass_kg"]  # 125 kg
    assert table.fitted["x_k_axial_N_per_m"] > 10 * hidden["x_k_axial_N_per_m"]  # no mode where it looks
    assert table.fit_index_pct.after < motor.fit_index_pct.after - 3


@pytest.mark.parametrize(
    "args, message",
    [
        (["frf", MID, "--loop", "closed"], "--loop = 'closed'"),
        (["frf", MID, "--excitation", "noise"], "--excitation = 'noise'"),
        (["tune", MID, "--control-period", "3e-5"], "--control-period = 3e-05"),
        (["calibrate", MID, "--trace", "nowhere.csv", "--fit", "x_table_mass_kg"], "--trace = 'nowhere.csv'"),
    ],
)
def test_bad_options_give_one_error_line(args, message):
    r = _twin(*args)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1
    assert message in r.stderr


def _positional_machine(tmp_path, extra: str = "", name: str = "positional.toml") -> str:
    """The example with X's axial stiffness and screw torsion computed from the shaft (27 mm
    root, both ends fixed) and the nut's position: nut 700 N/um, bearings 750 N/um."""
    text = Path(MID).read_text().replace("k_screw_torsion_N_m_per_rad = 8.3e3\n", "", 1)
    text = text.replace(
        "k_axial_N_per_m = 1.45e8",
        f"screw_root_diameter_m = 0.027\nk_nut_N_per_m = 7.0e8\nk_bearing_N_per_m = 7.5e8{extra}",
        1,
    )
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_the_axial_mode_moves_with_the_nut_as_mujoco_linearizes_it(tmp_path):
    """With `screw_root_diameter_m`, the axial stiffness is the nut, the bearings and the shaft
    E A L / (a (L - a)) in series (THK's formula, written here), the screw's torsion G J / a;
    the axial mode of MuJoCo's own linearization of the generated model (mjd_transitionFD, no
    Coulomb friction) moves from 208 Hz with the nut at mid travel to 245 Hz at 0.1 m, as the
    transfer function's within 0.2 %, and its torsional mode within 1 % (the explicit springs'
    step shifts it)."""
    import mujoco

    from twin.commissioning.frf import model_modes

    path = _positional_machine(tmp_path)
    machine = get_machine(path)
    modes = {}
    for position in (0.1, 0.5):
        overrides = {"x_nut_position_m": position, "x_friction_coulomb_N": 0.0, "y_friction_coulomb_N": 0.0}
        bm = build(path, overrides)
        area, polar = math.pi * 0.027**2 / 4, math.pi * 0.027**4 / 32
        shaft = 2.06e11 * area * 1.0 / (position * (1.0 - position))
        assert machine.axial_N_per_m(bm.params, "x") == pytest.approx(1 / (1 / shaft + 1 / 7e8 + 1 / 7.5e8), rel=1e-12)
        torsion = 1 / (1 / 5000.0 + position / (7.93e10 * polar))
        assert machine.torsion_N_m_per_rad(bm.params, "x") == pytest.approx(torsion, rel=1e-12)
        model, data = bm.model, mujoco.MjData(bm.model)
        mujoco.mj_forward(model, data)
        n = 2 * model.nv + model.na
        transition = np.zeros((n, n))
        mujoco.mjd_transitionFD(model, data, 1e-6, True, transition, None, None, None)
        rates = np.log(np.linalg.eigvals(transition).astype(complex)) / model.opt.timestep
        linearized = np.abs(rates.imag[rates.imag > 1.0]) / (2 * math.pi)
        axial, torsional = model_modes(bm, 0, "table")[0]
        assert np.abs(linearized / axial - 1).min() < 2e-3
        assert np.abs(linearized / torsional - 1).min() < 1e-2
        modes[position] = axial
    assert modes[0.5] == pytest.approx(207.7, abs=0.5)
    assert modes[0.1] == pytest.approx(244.5, abs=0.5)


def test_frf_position_measures_the_mode_where_the_nut_is(tmp_path):
    """`twin frf --position 0.1` on that machine finds the axial mode at 0.1 m (within 1 % of
    the model's 244.5 Hz) and says the stiffness there; on a machine whose stiffness does not
    depend on the position, and past the screw's end, one error line, exit 2; a file giving
    both the stiffness and the root diameter is refused naming both."""
    path = _positional_machine(tmp_path)
    r = _twin("frf", path, "--position", "0.1", "--duration", "8", "--json")
    assert r.returncode == 0, r.stderr
    import json

    result = json.loads(r.stdout)
    assert result["parameters"]["x_nut_position_m"] == 0.1
    measured = np.array(result["resonances_hz"])
    assert np.abs(measured / 244.5 - 1).min() < 0.01
    for args, message in (
        ([MID, "--position", "0.2"], "--position = 0.2: needs screw_root_diameter_m"),
        ([path, "--position", "1.5"], "x_nut_position_m = 1.5: nut_position_m = 1.5 must be within the screw's 1.0 m"),
        (
            [_positional_machine(tmp_path, "\nk_axial_N_per_m = 1e8", "both.toml")],
            "give k_axial_N_per_m or screw_root_diameter_m",
        ),
    ):
        r = _twin("frf", *args)
        assert r.returncode == 2
        assert r.stdout == ""
        assert r.stderr.count("\n") == 1, r.stderr
        assert message in r.stderr, r.stderr


@pytest.mark.slow  # 16 s of simulation per axis, 15-20 s a machine (tests/test_frf_oracle.py: 3.3 s runs)
@pytest.mark.parametrize("name", ["compact_xy", "heavy_xy"])
def test_a_catalogue_machine_is_measured_with_default_settings(name):
    """`twin frf` with its defaults (velocity loop on the motor's encoder, PRBS to 1 kHz) on each
    axis of the catalogue machines finds the transfer function's two modes, each within 1 %,
    and nothing else (heavy X: 128.9 and 432.1 Hz; compact Y: 373.4 and 784.6 Hz)."""
    from twin import api

    for axis in ("x", "y"):
        r = api.frf(str(EXAMPLES / f"{name}.toml"), axis=axis).summary
        assert len(r["model_resonances_hz"]) == 2
        assert len(r["resonances_hz"]) == 2
        np.testing.assert_allclose(r["resonances_hz"], r["model_resonances_hz"], rtol=0.01)
