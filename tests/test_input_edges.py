"""Edges the fuzzer found (issue 49), each refused in one error line naming the field the user
wrote: an inspection name that would split the report's line, cutting coefficients and tool
diameters out of any physical range, an axis that is not the machine's for a time trace."""

import numpy as np
import pytest
from cli_process import twin as twin_cli

from twin.commissioning.calibration import calibrate
from twin.errors import TwinInputError
from twin.machining.cutting import MAX_CUTTING_N_PER_MM2, MAX_EDGE_N_PER_MM
from twin.machining.engagement import MIN_TOOL_MM
from twin.scenario import load_scenario
from twin.settings import parse_settings

SLOT = "gcode_slot_passes"


@pytest.mark.parametrize("name", ["slot\nwidth 10.000 mm", "tab\there", "bell\x07"])
def test_an_inspection_name_with_a_control_character_is_refused(name):
    with pytest.raises(TwinInputError) as err:
        load_scenario(SLOT, {"inspect.0.name": name})
    assert (err.value.field, err.value.value) == ("inspect.0.name", name)
    assert "one line of printable characters" in err.value.reason
    assert "\n" not in str(err.value)


def test_a_printable_name_is_kept():
    scn = load_scenario(SLOT, {"inspect.0.name": "Bohrung Ø10 – oben"})
    assert scn.inspect[0].name == "Bohrung Ø10 – oben"


@pytest.mark.parametrize(
    "setting, field, words",
    [
        ("coefficients.K_tc=-800", "tools.0.coefficients.K_tc", "greater than 0"),
        ("coefficients.K_tc=1e5", "tools.0.coefficients.K_tc", f"less than or equal to {MAX_CUTTING_N_PER_MM2:g}"),
        ("coefficients.K_te=-5", "tools.0.coefficients.K_te", "greater than or equal to 0"),
        ("coefficients.K_re=2e3", "tools.0.coefficients.K_re", f"less than or equal to {MAX_EDGE_N_PER_MM:g}"),
        ("coefficients.kc1_N_per_mm2=1e6", "tools.0.coefficients.kc1_N_per_mm2", "less than or equal"),
        ("shank_diameter_mm=1e-9", "tools.0.shank_diameter_mm", f"greater than or equal to {MIN_TOOL_MM:g}"),
        ("diameter_mm=1e-9", "tools.0.diameter_mm", f"greater than or equal to {MIN_TOOL_MM:g}"),
    ],
)
def test_coefficients_and_diameters_out_of_any_physical_range_are_refused(setting, field, words):
    with pytest.raises(TwinInputError) as err:
        load_scenario(SLOT, parse_settings([f"tools.0.{setting}"]))
    assert err.value.field == field
    assert words in err.value.reason


def test_a_negative_cutting_coefficient_is_one_cli_error_line():
    r = twin_cli("run", SLOT, "--set", "tools.0.coefficients.K_tc=-800")
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr.splitlines() == ["error: tools.0.coefficients.K_tc = -800: Input should be greater than 0"]


def test_calibrate_refuses_an_axis_the_machine_lacks_for_a_time_trace(tmp_path):
    t = np.arange(200) * 1e-3
    trace = tmp_path / "trace.csv"
    rows = "\n".join(f"{ti:.3f},{0.1 * np.sin(50 * ti):.6f},{1e-4 * ti:.9f}" for ti in t)
    trace.write_text("time_s,u_x_V,pos_x_m\n" + rows + "\n")
    with pytest.raises(TwinInputError) as err:
        calibrate("linear_motor_xy", trace, ["m_x"], axis="q")
    assert (err.value.field, err.value.value) == ("--axis", "q")
    assert err.value.reason == "machine axes are ['x', 'y']"
