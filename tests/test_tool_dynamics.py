"""The tool's structure: modes and a measured FRF (twin.machining.tool_dynamics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.errors import TwinInputError
from twin.machining.tool_dynamics import ToolDynamicsSpec
from twin.scenario.files import bundled_scenarios, load_scenario, read_scenario_data

MODE_X = {"direction": "x", "frequency_hz": 922.0, "damping_ratio": 0.011, "modal_mass_kg": 0.03993}


def test_a_mode_receptance_static_and_at_resonance():
    """Static 1/k, at resonance 1/(2 i zeta k), k = m omega_n^2 (Altintas ch. 3.2)."""
    dyn = ToolDynamicsSpec.model_validate({"modes": [MODE_X]})
    k = 0.03993 * (2 * math.pi * 922.0) ** 2
    g = dyn.receptance(np.array([0.0, 922.0]))
    assert g[0, 0, 0] == pytest.approx(1 / k, rel=1e-12)
    assert g[1, 0, 0] == pytest.approx(1 / (2j * 0.011 * k), rel=1e-12)
    assert np.all(g[:, 1, 1] == 0) and np.all(g[:, 0, 1] == 0)


def test_modes_along_one_direction_add():
    """Two modes in Y: their receptances add; the mode given by its stiffness has m = k/omega^2."""
    one = {"direction": "y", "frequency_hz": 800.0, "damping_ratio": 0.02, "stiffness_N_per_m": 2e6}
    two = {"direction": "y", "frequency_hz": 2500.0, "damping_ratio": 0.03, "stiffness_N_per_m": 5e6}
    dyn = ToolDynamicsSpec.model_validate({"modes": [one, two]})
    f = 1200.0
    expected = sum(
        1
        / (
            m["stiffness_N_per_m"]
            * (1 - (f / m["frequency_hz"]) ** 2 + 2j * m["damping_ratio"] * f / m["frequency_hz"])
        )
        for m in (one, two)
    )
    assert dyn.receptance(f)[1, 1] == pytest.approx(expected, rel=1e-12)
    assert dyn.modes[0].mass == pytest.approx(2e6 / (2 * math.pi * 800.0) ** 2, rel=1e-12)


def test_feed_frame_rotation_of_an_x_mode():
    """A feed at 90 deg: the machine's X is the feed frame's -y, so an X mode is its yy term."""
    dyn = ToolDynamicsSpec.model_validate({"modes": [MODE_X]})
    g = dyn.receptance(922.0, feed_angle_rad=math.pi / 2)
    assert g[1, 1] == pytest.approx(dyn.receptance(922.0)[0, 0], rel=1e-12)
    assert abs(g[0, 0]) < 1e-12 * abs(g[1, 1])


@pytest.mark.parametrize(
    ("mode", "message"),
    [
        ({"direction": "x", "frequency_hz": 922.0, "damping_ratio": 0.011}, "neither given"),
        ({**MODE_X, "stiffness_N_per_m": 1e6}, "both given"),
        ({**MODE_X, "damping_ratio": 1.5}, "less than 1"),
        ({**MODE_X, "direction": "z"}, "'x' or 'y'"),
    ],
)
def test_bad_modes_name_the_field(mode, message):
    with pytest.raises(ValueError, match=message):
        ToolDynamicsSpec.model_validate({"modes": [mode]})


def _tap_csv(path, rows, header="frequency_hz,xx_real,xx_imag,yy_real,yy_imag"):
    path.write_text(header + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return path


def test_a_measured_frf_interpolates_and_is_relative_to_the_scenario(tmp_path):
    """A tool's frf_file beside the scenario file: read, interpolated linearly, bounded."""
    _tap_csv(tmp_path / "tap.csv", [[100, 1e-7, -1e-7, 2e-7, 0], [300, 3e-7, -3e-7, 2e-7, -2e-7]])
    program = read_scenario_data("gcode_test_piece")["reference"]["file"]  # made absolute
    source = bundled_scenarios()["gcode_test_piece"].read_text()
    source = source.replace('file = "programs/test_piece.ngc"', f'file = "{program}"')
    text = tmp_path / "x.toml"
    text.write_text(source + '\n[tools.dynamics]              # of the last [[tools]]\nfrf_file = "tap.csv"\n')
    scenario = load_scenario(text)
    dyn = scenario.tools[0].dynamics
    g = dyn.receptance(np.array([200.0]))
    assert g[0, 0, 0] == pytest.approx(2e-7 - 2e-7j)
    assert g[0, 1, 1] == pytest.approx(2e-7 - 1e-7j)
    assert dyn.frequency_range_hz() == (100.0, 300.0)
    with pytest.raises(TwinInputError, match="400 Hz is outside"):
        dyn.receptance(400.0)


@pytest.mark.parametrize(
    ("header", "rows", "message"),
    [
        ("frequency_hz,xx_real,xx_imag,yy_real", [[1, 0, 0, 0]], "yy_imag missing"),
        ("frequency_hz,xx_real,xx_imag,yy_real,yy_imag,zz", [[1, 0, 0, 0, 0, 0]], "unknown column"),
        ("frequency_hz,xx_real,xx_imag,yy_real,yy_imag", [[2, 0, 0, 0, 0], [1, 0, 0, 0, 0]], "increasing"),
        ("frequency_hz,xx_real,xx_imag,yy_real,yy_imag", [[1, 0, 0, 0, 0], [2, 0, "a", 0, 0]], "line 3"),
        ("frequency_hz,xx_real,xx_imag,yy_real,yy_imag", [[1, 0, 0, 0, 0]], "at least 2"),
    ],
)
def test_bad_frf_files_name_the_file_and_reason(tmp_path, header, rows, message):
    path = _tap_csv(tmp_path / "tap.csv", rows, header)
    with pytest.raises(ValueError, match=message):
        ToolDynamicsSpec.model_validate({"frf_file": str(path)})


def test_modes_or_a_file_not_both_nor_neither(tmp_path):
    with pytest.raises(ValueError, match="one of the two"):
        ToolDynamicsSpec.model_validate({})
    with pytest.raises(ValueError, match="one of the two"):
        ToolDynamicsSpec.model_validate({"modes": [MODE_X], "frf_file": str(tmp_path / "x.csv")})


def test_isotropy():
    """X and Y alike (any order of the modes) is isotropic; one mode less is not."""
    y = {**MODE_X, "direction": "y"}
    other = {**MODE_X, "frequency_hz": 1500.0}
    assert ToolDynamicsSpec.model_validate({"modes": [MODE_X, other, {**other, "direction": "y"}, y]}).is_isotropic()
    assert not ToolDynamicsSpec.model_validate({"modes": [MODE_X, other, y]}).is_isotropic()
