"""Crashes and misuse caught per line: each warning on a program written to make it, with the
value the geometry gives (a rapid 1 mm into the block, a tip 2 mm below its bottom, material
3 mm above 5 mm flutes, a plunge at 90 deg, 0.03 mm a tooth), none on a clean program, and
``twin run --strict`` ending with exit code 4."""

import json

import numpy as np
import pytest
from cli_process import twin as _twin

from twin.gcode.planned import Limits
from twin.gcode.planner import PlannerSettings, plan
from twin.gcode.reader import Reader
from twin.machining.engagement import StockSpec, ToolSpec
from twin.machining.program_cut import program_milling

LIMITS = Limits((0.5, 0.5, 0.2), (5.0, 5.0, 2.0), (100.0, 100.0, 200.0))
BLOCK = StockSpec(corners_mm=((0, -10), (40, 10)), top_mm=0, bottom_mm=-20)


FLAT = ToolSpec(diameter_mm=6.0, n_flutes=2)


def _warnings(lines, tool=FLAT, spindle="M3 S10000"):
    program = ["G21 G90 G0 X-10 Y0 Z5", spindle, *lines, "G0 Z5", "M5"]
    planned = plan(Reader(program).moves(), LIMITS, PlannerSettings())
    cut = program_milling(planned, BLOCK, tool, [], 0)
    return {(w.line - 2, w.kind): w for w in cut.warnings}, cut.warnings_total


def test_a_clean_program_warns_of_nothing():
    """A plunge outside the block, a slot 3 mm deep at F600 (0.03 mm a tooth) within every limit."""
    tool = ToolSpec(diameter_mm=6.0, n_flutes=2, flute_length_mm=10, max_ramp_deg=0, feed_per_tooth_mm=(0.01, 0.1))
    found, total = _warnings(["G1 Z-3 F300", "G1 X30 F600"], tool)
    assert found == {}
    assert total == 0


@pytest.mark.parametrize(
    "lines, tool, spindle, line, kind, value",
    [
        (["G0 Z-1", "G0 X30"], {}, "M3 S10000", 2, "rapid_through_material", 1.0),
        (["G1 Z-2 F300", "G1 X30 F600"], {}, "M5", 2, "spindle_off_in_material", 2.0),
        (["G1 Z-22 F300", "G1 X30 F600"], {}, "M3 S10000", 2, "below_stock_bottom", 2.0),
        (["G1 Z-8 F300", "G1 X30 F600"], {"flute_length_mm": 5.0}, "M3 S10000", 2, "deeper_than_flutes", 3.0),
        (["G0 X10", "G1 Z-2 F300"], {"max_ramp_deg": 10.0}, "M3 S10000", 2, "plunge_too_steep", 90.0),
        (["G1 Z-2 F300", "G1 X30 F600"], {"feed_per_tooth_mm": (0.05, 0.1)}, "M3 S10000", 2, "feed_per_tooth", 0.03),
    ],
)
def test_each_crash_or_misuse_is_a_warning_on_its_line_with_its_value(lines, tool, spindle, line, kind, value):
    found, total = _warnings(lines, ToolSpec(diameter_mm=6.0, n_flutes=2, **tool), spindle)
    assert (line, kind) in found, found
    assert found[(line, kind)].value == pytest.approx(value, rel=1e-3)
    assert found[(line, kind)].text == lines[line - 1]
    assert total == len(found)


@pytest.mark.parametrize(("shank_mm", "over_mm"), [(None, None), (4.0, None), (10.0, 2.0)])
def test_a_shank_wider_than_the_cutter_rubs_on_the_walls_of_its_own_slot(shank_mm, over_mm):
    """A 6 mm cutter with 2 mm flutes takes a slot down to 4 mm in two passes: its flutes
    reach above the material it left (none rubs) unless its shank is wider than the slot: a
    10 mm shank meets the walls standing 4 - 2 = 2 mm above the flutes on the second pass."""
    tool = ToolSpec(diameter_mm=6.0, n_flutes=2, flute_length_mm=2.0, shank_diameter_mm=shank_mm)
    found, _ = _warnings(["G1 Z-2 F300", "G1 X30 F600", "G1 Z-4 F300", "G1 X-10 F600"], tool)
    rubs = {line: w.value for (line, kind), w in found.items() if kind == "deeper_than_flutes"}
    if over_mm is None:
        assert rubs == {}
    else:
        assert set(rubs) == {3, 4}  # the plunge at X30 already meets the wall of the slot's end
        assert rubs[4] == pytest.approx(over_mm, abs=1e-6)


def test_a_ramp_within_the_tools_angle_is_not_a_plunge():
    """A 5.7 deg ramp (2 mm down over 20 mm) with a tool that ramps at up to 10 deg."""
    found, _ = _warnings(
        ["G0 X10", "G1 Z0 F300", "G1 X30 Z-2 F600"], ToolSpec(diameter_mm=6.0, n_flutes=2, max_ramp_deg=10)
    )
    assert not any(kind == "plunge_too_steep" for _, kind in found)


def test_strict_turns_warnings_into_exit_code_4(tmp_path):
    """The bundled test piece with 5 mm flutes on T1 (it cuts 10 mm deep at most): the JSON
    lists each line's warning, the run still reports; --strict adds one error line, exit 4."""
    twin = ["run", "gcode_test_piece", "--set", "tools.0.flute_length_mm=1"]
    plain = _twin(*twin, "--json", "--set", "duration_s=0.5")
    assert plain.returncode == 0, plain.stderr
    warnings = json.loads(plain.stdout)["machining_warnings"]
    assert warnings
    assert {w["kind"] for w in warnings} == {"deeper_than_flutes"}
    assert np.all([w["value"] > 0 for w in warnings])
    strict = _twin(*twin, "--strict", "--set", "duration_s=0.5")
    assert strict.returncode == 4
    assert strict.stderr.count("\n") == 1
    assert strict.stderr.startswith("error: ")
    assert "--strict" in strict.stderr
    assert "machining warnings" in strict.stdout


def test_a_tools_material_and_the_users_own_coefficients_reach_the_force_model():
    """The kernel's tool row is the material's coefficients with the user's over them."""
    from twin.machining.materials import MATERIALS

    tool = ToolSpec(diameter_mm=6.0, n_flutes=3, material="aluminium_6082_t6", coefficients={"K_tc": 500.0})
    expected = MATERIALS["aluminium_6082_t6"].value.coefficients.as_array()
    expected[0] = 500.0
    assert tool.cutting_coefficients().as_array() == pytest.approx(expected)
    planned = plan(
        Reader(["G21 G90 G0 X-10 Y0 Z5", "M3 S10000", "G1 Z-2 F300", "G1 X30 F600"]).moves(), LIMITS, PlannerSettings()
    )
    milling = program_milling(planned, BLOCK, tool, [], 0).milling
    from twin.machines import build

    _, params, _ = milling.kernel_arrays(build("linear_motor_xy"))
    assert np.isin(np.append(expected, 3.0), params).all()


def test_twin_list_shows_every_material_with_its_source():
    from twin.machining.materials import MATERIALS

    listed = _twin("list")
    assert listed.returncode == 0
    for name, entry in MATERIALS.items():
        material = entry.value
        line = next(row for row in listed.stdout.splitlines() if row.strip().startswith(name + " "))
        assert material.source in line
        assert material.alloy in line


def test_the_docs_materials_table_is_the_library():
    """The machining page's table is generated from the library: each row holds its entry's
    coefficients and Kienzle exponent."""
    from pathlib import Path

    from twin.kinds_doc import materials_table
    from twin.machining.materials import MATERIALS

    page = (Path(__file__).resolve().parent.parent / "docs" / "pages" / "machining.md").read_text()
    assert "<!-- table: materials -->" in page
    rows = {line.split("`")[1]: line for line in materials_table().splitlines() if line.startswith("| `")}
    assert set(rows) == set(MATERIALS)
    for name, entry in MATERIALS.items():
        material = entry.value
        cells = [c.strip() for c in rows[name].split("|")[6:13]]
        assert [float(c) for c in cells] == pytest.approx(material.coefficients.as_array().tolist(), rel=1e-5), name
