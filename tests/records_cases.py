"""Runs whose JSON and text report are fixed in ``tests/fixtures/records/`` (written by
``tests/fixtures/records/regenerate.py`` from the code before the results were typed): per-line
rows, machining warnings, warnings against the machine, chatter warnings and each inspection
feature type (found, not found, outside the stock)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

from twin import api
from twin.exits import strict_json
from twin.machining.inspection import CircleFeature, LineFeature, WidthFeature

#: Where the fixtures are.
FIXTURES = Path(__file__).resolve().parent / "fixtures" / "records"

#: Per case: the bundled scenario, its settings and the features inspected.
CASES = {
    # 4 s of the 16 mm slot along Y25 (X -10 to about 12): chatter on line 13, a drive warning,
    # the slot's width and south wall, a circle where nothing is cut yet, a feature below the stock
    "deep_slot": (
        "gcode_deep_slot",
        {"duration_s": 4.0},
        [
            WidthFeature(type="width", name="slot", from_mm=(5, 15), to_mm=(5, 35), width_mm=10.0, z_mm=-8.0),
            LineFeature(type="line", name="south wall", from_mm=(2, 20), to_mm=(8, 20), z_mm=-8.0, tolerance_um=50.0),
            CircleFeature(type="circle", name="uncut", center_mm=(60, 25), diameter_mm=4.0, z_mm=-8.0),
            WidthFeature(type="width", name="below", from_mm=(5, 15), to_mm=(5, 35), width_mm=10.0, z_mm=-30.0),
            WidthFeature(type="width", name="in material", from_mm=(50, 5), to_mm=(50, 45), width_mm=10.0, z_mm=-8.0),
        ],
    ),
    # the Choi 1999 circle through its stock: the bore it opens, its width across, a line of it
    "bore": (
        "gcode_choi1999_circle_stock",
        {},
        [
            CircleFeature(type="circle", name="bore", center_mm=(-28, 0), diameter_mm=66.0, z_mm=-1.5, tolerance_um=10),
            WidthFeature(type="width", name="across", from_mm=(-50, 0), to_mm=(-6, 0), width_mm=66.0, z_mm=-1.5),
            LineFeature(type="line", name="flat", from_mm=(-30, 33), to_mm=(-26, 33), z_mm=-1.5, tolerance_um=1.0),
            LineFeature(type="line", name="one point", from_mm=(-28, 33), to_mm=(-28, 33), z_mm=-1.5),
        ],
    ),
    # half a second of the test piece with 1 mm flutes: a machining warning on each cutting line
    "test_piece_flutes": ("gcode_test_piece", {"duration_s": 0.5, "tools__0__flute_length_mm": 1.0}, []),
}


def run_case(name: str) -> api.Run:
    """The run of case ``name``."""
    scenario, settings, features = CASES[name]
    scn = api.load(scenario, **settings)
    return api.run(scn.model_copy(update={"inspect": features}) if features else scn)


def json_report(run: api.Run) -> str:
    """What ``twin run --json`` prints for ``run``."""
    return strict_json(run.summary, 2, default=float) + "\n"


def text_report(run: api.Run) -> str:
    """What ``twin run`` prints for ``run`` (its text summary)."""
    from twin.cli import _report

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        _report(run, rrd=None, as_json=False, plots=None)
    return out.getvalue()
