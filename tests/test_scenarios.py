"""Every bundled scenario validates, runs compiled, and both loops agree on it; every block kind
works from a scenario file; the Choi 1999 air cut keeps its accuracy."""

import math
import warnings

import numpy as np
import pytest

from twin.errors import TwinInputError
from twin.metrics import tracking_summary
from twin.outcome import finish
from twin.scenario import assemble, bundled_scenarios, load_scenario, run_scenario, scenario_from_dict
from twin.settings import parse_settings

SERIES = ("qpos", "qvel", "meas_m", "u_V", "u_applied_V", "actuator_force", "workpiece_force_N", "vibration_probe")


@pytest.mark.parametrize("name", sorted(bundled_scenarios()))
def test_bundled_scenario_runs_compiled_and_equals_the_python_loop(name):
    """The Python loop is the reference: over the first 0.2 s of every bundled scenario both
    loops give the same series, bit for bit (the compiled loop accumulates the simulation time
    the milling force reads as MuJoCo does; the full-length runs are bit-identical too)."""
    inputs = assemble(load_scenario(name, {"duration_s": 0.2}))
    fast, slow = (inputs.simulate(compiled=c) for c in (True, False))
    assert fast.info["loop"] == "compiled"
    assert slow.info["loop"] == "python"
    for key in SERIES:
        assert np.array_equal(getattr(fast, key), getattr(slow, key)), key
    summary = tracking_summary(finish(fast, inputs.program))
    assert all(math.isfinite(v) for v in summary["max_tracking_error_um"].values())
    # a milling force where the table moves (the chip is the tool's motion relative to the part:
    # gcode_choi1999_circle only plunges along Z in its first 0.2 s)
    milling = any(d.type in ("end_milling", "average_force") for d in load_scenario(name).disturbances)
    if milling and np.abs(fast.ref[:, :, 1]).max() > 1e-3:
        assert max(summary["max_cutting_force_N"].values()) > 1.0


def test_choi1999_air_cut_contour_error_is_micrometres():
    """Choi 1999 reports max tracking errors of 6/7 um (its MIMO controller + ZPETC) on this
    circle; the twin's PID + model feedforward with catalogue friction stays under 10 um contour error."""
    outcome = run_scenario(load_scenario("choi1999_air_cut_circle"))
    assert tracking_summary(outcome)["max_contour_error_um"] < 10.0


BASE = {
    "machine": "googol_xy",
    "duration_s": 0.3,
    "timestep_s": 1e-4,
    "control_period_s": 1e-4,
    "reference": {"type": "sines", "amplitudes_m": [0.002], "frequencies_hz": [1.0], "axes": ["x"]},
}


def _run(controller: dict, **extra):
    return run_scenario(scenario_from_dict({**BASE, "controller": controller, **extra})).run


def test_every_block_kind_from_a_scenario_file_tracks():
    """Each kind on googol_xy, compiled: a 2 mm, 1 Hz sine tracked to within 10 % of its size."""
    kinds = {
        "pid": {"type": "anang2017_pid"},
        "npid": {"type": "anang2017_npid", "params": {"ko_per_mm": 6.0, "e_max_mm": 0.3}},
        "lure": {"type": "lure", "params": {"num": [899.8], "den": [1.0], "nonlinearity": "saturation", "limit": 0.01}},
        "cascade": {"type": "cascade", "params": {"kp_pos": 200.0, "kp_vel": 7.0, "ki_vel": 400.0}},
        "cascade+observer": {
            "type": "cascade",
            "params": {"kp_pos": 200.0, "kp_vel": 7.0, "ki_vel": 400.0},
            "observer": {"type": "inverse_model", "params": {"cutoff_hz": 20.0, "order": 2}},
        },
        "linear (MIMO, continuous)": {
            "type": "linear",
            "params": {
                "domain": "continuous",
                "inputs": ["error.x", "error.y"],
                "outputs": ["u.x", "u.y"],
                "A": [[0.0]],
                "B": [[1.0, 0.0]],
                "C": [[0.6077], [0.0]],
                "D": [[899.8, 0.0], [0.0, 899.8]],
            },
        },
        "sum": {
            "type": "sum",
            "parts": [{"type": "pid", "params": {"kp": 500.0}}, {"type": "pid", "params": {"kp": 399.8, "ki": 0.6077}}],
        },
    }
    for name, spec in kinds.items():
        res = _run(spec)
        assert res.info["loop"] == "compiled", name
        assert res.error_max_m[0] < 0.1 * 0.002, (name, res.error_max_m)


def test_tachometer_and_decimated_recording_from_a_scenario():
    res = _run(
        {"type": "cascade", "params": {"kp_pos": 200.0, "kp_vel": 7.0, "ki_vel": 400.0}},
        sensors={"velocity": "tachometer"},
        record_every_ticks=10,
    )
    assert len(res.t_s) == 300
    assert res.error_max_m[0] < 0.1 * 0.002


@pytest.mark.parametrize(
    "controller, field, words",
    [
        (
            {"type": "linear", "params": {"inputs": ["vel.z"], "D": [[1.0]]}},
            "controller block linear/linear.x",
            "vel.z",
        ),
        (
            {"type": "cascade", "params": {"kp_pos": 1.0, "gain": 2.0}},
            "controller.params.gain",
            "not a parameter of cascade (its parameters: kp_pos, ki_pos, kp_vel, ki_vel, velocity_ref_ff)",
        ),
        ({"type": "pid", "params": {"kp": "30"}}, "controller.params.kp", "valid number"),
        ({"type": "tf", "params": {"num": [1.0]}}, "controller.params.den", "tf needs it"),
        ({"type": "choi1999_mimo", "params": {"zpetc": 1}}, "controller.params.zpetc", "valid boolean"),
        (
            {"type": "pid", "observer": {"type": "harmonic", "params": {"bandwidth_hz": -1.0}}},
            "controller.observer.params.bandwidth_hz",
            "greater than 0",
        ),
        ({"type": "pid", "observer": {"type": "kalman"}}, "controller.observer.type", "kalman"),
        (
            {"type": "pid", "observer": {"type": "inverse_model", "params": {"order": 1}}},
            "controller.observer.params",
            "relative degree 2",
        ),
        (
            {"type": "lure", "params": {"num": [1.0], "den": [1.0], "nonlinearity": "cosh_gain", "k": 6.0}},
            "controller.params",
            "'e_max' is needed",
        ),
        ({"type": "sum"}, "controller.parts", "give parts"),
        ({"type": "linear", "params": {"D": [[1.0, 2.0]]}}, "controller.params", "D has shape"),
    ],
)
def test_bad_controllers_name_the_field(controller, field, words):
    with pytest.raises(TwinInputError) as err:
        _run(controller)
    assert err.value.field == field, str(err.value)
    assert words in str(err.value), str(err.value)


def test_inverse_model_observer_removes_a_step_input_disturbance_on_the_twin():
    """Cascade with a P velocity loop (no integral action) on googol_xy under a 0.05 V input
    step: without the observer the table settles 35.65 um off; with it, the offset goes to
    zero and the peak drops."""
    spec = {
        **BASE,
        "duration_s": 1.0,
        "reference": {"type": "step", "amplitude_m": 0.0},
        "disturbances": [{"type": "voltage_step", "amplitude_V": 0.05, "start_s": 0.2, "axes": ["x"]}],
    }
    cascade = {"type": "cascade", "params": {"kp_pos": 200.0, "kp_vel": 7.0}}
    plain = run_scenario(scenario_from_dict({**spec, "controller": cascade})).run
    observed = run_scenario(
        scenario_from_dict(
            {
                **spec,
                "controller": {
                    **cascade,
                    "observer": {"type": "inverse_model", "params": {"cutoff_hz": 20.0, "order": 2}},
                },
            }
        )
    ).run
    # independent: at rest u = kp_vel kp_pos e and y = G(0) (u + d), G(0) = 78.02/193.3 m/V (eq. 1)
    g0 = 78.02 / 193.3
    offset = g0 * 0.05 / (1 + g0 * 7.0 * 200.0)
    assert plain.error_m()[-1, 0] == pytest.approx(-offset, rel=1e-3)
    assert abs(observed.error_m()[-1, 0]) < 1e-3 * offset
    assert observed.error_max_m[0] < 0.8 * plain.error_max_m[0]


@pytest.mark.parametrize(
    "setting, field, words",
    [
        ("disturbances.0.n_flutes=2147483648", "disturbances.0.n_flutes", "less than or equal to 100"),
        ("disturbances.0.spindle_rpm=0.5", "disturbances.0.spindle_rpm", "greater than or equal to 1"),
        ("timestep_s=1e308", "timestep_s", "less than or equal to 0.01"),
    ],
)
def test_counts_and_rates_the_loops_run_over_are_bounded(setting, field, words):
    """Each count a force model loops over, and the timestep, has a bound named in its error."""
    with pytest.raises(TwinInputError) as err:
        load_scenario("choi1999_cutting_circle", parse_settings([setting]))
    assert err.value.field == field
    assert words in err.value.reason


@pytest.mark.parametrize(
    "setting, field, value, words",
    [
        ("sensors.noise_std_m=-1", "sensors.noise_std_m", -1, "greater than or equal to 0"),
        ("sensors.noise_std_m=[0, 2e-3]", "sensors.noise_std_m.1", 2e-3, "less than or equal to 0.001"),
        ("sensors.encoder_resolution_m='x'", "sensors.encoder_resolution_m", "x", "valid number"),
    ],
)
def test_a_number_or_list_setting_names_the_field_the_user_wrote(setting, field, value, words):
    """A union of a number and a list is refused under the user's path (no pydantic member such as
    ``constrained-float``), for the member the value is: a list for its item."""
    with pytest.raises(TwinInputError) as err:
        load_scenario("square_sabau_pid", parse_settings([setting]))
    assert (err.value.field, err.value.value) == (field, value)
    assert words in err.value.reason


def test_harmonic_and_sine_counts_are_bounded():
    many = "[" + ", ".join(["0.001"] * 101) + "]"
    with pytest.raises(TwinInputError) as err:
        load_scenario("maharof2021_cascade", parse_settings([f"disturbances.0.amplitudes_V={many}"]))
    assert err.value.field == "disturbances.0.amplitudes_V"
    assert "at most 100" in err.value.reason
    with pytest.raises(TwinInputError) as err:
        load_scenario("maharof2021_cascade", parse_settings([f"reference.amplitudes_m={many}"]))
    assert err.value.field == "reference.amplitudes_m"
    assert "at most 100" in err.value.reason


def test_a_design_that_fails_numerically_is_one_error_and_no_warning():
    """Maharof 2021's cascade designed for a physics step of 5e-324 s (beyond the schema's bound, so
    set past validation) overflows inside numpy; the build reports it as the controller's error
    instead of printing numpy's RuntimeWarnings first."""
    scn = load_scenario("maharof2021_cascade")
    scn = scn.model_copy(update={"timestep_s": 5e-324, "control_period_s": 5e-324})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(TwinInputError) as err:
            assemble(scn)
    assert not caught, [str(w.message) for w in caught]
    assert err.value.field == "controller.params"
    assert "failed numerically" in err.value.reason or "no loop with finite margins" in err.value.reason
    assert "nan" not in err.value.reason
