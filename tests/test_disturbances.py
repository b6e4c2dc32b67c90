"""The papers' disturbance options as scenario entries: reproducible by seed, validated by field."""

import math

import numpy as np
import pytest

from twin.disturbances.drive_input import HarmonicInput
from twin.errors import TwinInputError
from twin.scenario import run_scenario, scenario_from_dict

CUT = dict(
    type="end_milling", spindle_rpm=1500.0, n_flutes=2, diameter_mm=10.0, axial_depth_mm=1.0, radial_depth_mm=10.0
)
OPTIONS = {
    "end_milling (Anang 2017's spindle speeds)": dict(disturbances=[CUT]),
    "average_force with tooth harmonic (Choi 1999)": dict(
        disturbances=[dict(type="average_force", harmonic_fraction=0.2, spindle_rpm=3500.0, n_flutes=2)]
    ),
    "harmonic_input 0.2/0.5/0.8 Hz (Maharof 2021)": dict(
        disturbances=[dict(type="harmonic_input", amplitudes_V=[0.01, 0.01, 0.01], frequencies_hz=[0.2, 0.5, 0.8])]
    ),
    "voltage_step + sensor noise (Yadav 2020)": dict(
        disturbances=[dict(type="voltage_step", amplitude_V=0.005, start_s=0.05)], sensors=dict(noise_std_m=2e-6)
    ),
}


def _scenario(seed, **extra):
    return scenario_from_dict(
        dict(
            machine="googol_xy",
            duration_s=0.25,
            timestep_s=1e-4,
            control_period_s=1e-4,
            seed=seed,
            controller=dict(type="anang2017_pid"),
            reference=dict(type="sines", amplitudes_m=[0.01], frequencies_hz=[0.4], axes=["x"]),
            **extra,
        )
    )


def _series(res):
    return np.concatenate([res.qpos.ravel(), res.u_V.ravel(), res.workpiece_force_N.ravel(), res.meas_m.ravel()])


@pytest.mark.parametrize("option", list(OPTIONS))
def test_disturbance_is_bit_identical_for_a_seed(option):
    a = _series(run_scenario(_scenario(7, **OPTIONS[option])).run)
    b = _series(run_scenario(_scenario(7, **OPTIONS[option])).run)
    assert np.array_equal(a, b)
    quiet = _series(run_scenario(_scenario(7)).run)
    assert not np.array_equal(a, quiet)  # the option does act
    # each option draws something from the seed (spindle or harmonic phases, noise)
    assert not np.array_equal(a, _series(run_scenario(_scenario(8, **OPTIONS[option])).run))


def test_harmonic_input_is_the_sum_of_sines():
    d = HarmonicInput((0.3, 0.2), (0.2, 0.5), (0.1, -0.4), n_axes=2, axes=(0,))
    t = np.linspace(0.0, 5.0, 501)
    expected = 0.3 * np.sin(2 * math.pi * 0.2 * t + 0.1) + 0.2 * np.sin(2 * math.pi * 0.5 * t - 0.4)
    np.testing.assert_allclose(d.input_V(t)[:, 0], expected, atol=1e-15)
    assert not d.input_V(t)[:, 1].any()


def test_disturbance_own_seed_overrides_scenario_seed():
    own = dict(disturbances=[{**CUT, "seed": 3}])
    assert np.array_equal(
        _series(run_scenario(_scenario(1, **own)).run), _series(run_scenario(_scenario(2, **own)).run)
    )


@pytest.mark.parametrize(
    "entry, field",
    [
        ({**CUT, "radial_depth_mm": 12.0}, "disturbances.0.radial_depth_mm"),
        ({**CUT, "n_flutes": 0}, "disturbances.0.n_flutes"),
        (dict(type="average_force", harmonic_fraction=0.3), "disturbances.0.harmonic_fraction"),
        (dict(type="harmonic_input", amplitudes_V=[0.1], frequencies_hz=[0.2], axes=["z"]), "disturbances.0.axes"),
        (dict(type="harmonic_input", amplitudes_V=[0.1, 0.2], frequencies_hz=[0.2]), "disturbances.0.frequencies_hz"),
        (dict(type="chatter"), "disturbances.0"),
    ],
)
def test_bad_disturbance_names_its_field(entry, field):
    with pytest.raises(TwinInputError) as err:
        run_scenario(_scenario(0, disturbances=[entry]))
    assert err.value.field == field


def test_the_disturbance_schema_is_the_registry():
    """[[disturbances]] entries are the registered kinds, each built by its own module's builder."""
    from twin.disturbances import DISTURBANCES
    from twin.scenario import Scenario

    schema = Scenario.model_json_schema()
    tags = set(schema["properties"]["disturbances"]["items"]["discriminator"]["mapping"])
    assert tags == set(DISTURBANCES) == {"end_milling", "average_force", "harmonic_input", "voltage_step"}
