"""Per-line results of a G-code run: every line that moved gets its time span, contour and
tracking errors and cutting force, consistent with the run's own totals."""

import itertools
import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from twin import api
from twin.cli import app

PROGRAM = Path(__file__).resolve().parent.parent / "twin" / "scenarios" / "programs" / "test_piece.ngc"


@pytest.fixture(scope="module")
def part_run():
    return api.run("gcode_test_piece", duration_s=6.0)


def test_every_line_that_moved_has_its_row_and_the_rows_add_up(part_run):
    summary = part_run.summary
    rows = summary["lines"]
    source = PROGRAM.read_text().splitlines()
    assert [r["line"] for r in rows] == sorted(r["line"] for r in rows)  # program order
    for row in rows:
        assert row["text"] == source[row["line"] - 1].strip()
    for before, after in itertools.pairwise(rows):
        assert after["t_start_s"] == pytest.approx(before["t_end_s"])  # the spans tile the run
    assert rows[0]["t_start_s"] == 0.0
    assert rows[-1]["t_end_s"] == pytest.approx(6.0, abs=1e-9)
    assert max(r["max_contour_error_um"] for r in rows) == summary["max_contour_error_um"]
    for axis in ("x", "y"):
        assert max(r["max_tracking_error_um"][axis] for r in rows) == summary["max_tracking_error_um"][axis]
    planned = api.program(PROGRAM, machine="linear_motor_xy").planned  # `twin gcode`'s plan of the file
    assert summary["cycle_time_s"] == pytest.approx(planned.cycle_time_s, abs=1e-9)  # the whole program's
    assert "lines" not in api.run("step_cncmt_hinf", duration_s=0.2).summary


def test_twin_run_prints_the_worst_lines_and_writes_the_table(tmp_path, part_run):
    table = tmp_path / "lines.parquet"
    out = CliRunner().invoke(app, ["run", "gcode_test_piece", "--set", "duration_s=6.0", "--lines", str(table)])
    assert out.exit_code == 0, out.output
    text = out.output.splitlines()
    at = text.index("  worst lines (max contour error, um):")
    worst = sorted(part_run.summary["lines"], key=lambda r: r["max_contour_error_um"], reverse=True)[:5]
    for printed, row in zip(text[at + 1 : at + 6], worst):
        assert printed.split()[0] == str(row["line"])
        assert printed.endswith(row["text"])
    read = pq.read_table(table).to_pylist()
    assert len(read) == len(part_run.summary["lines"])
    assert read[0]["max_tracking_error_um_x"] == part_run.summary["lines"][0]["max_tracking_error_um"]["x"]
    short = CliRunner().invoke(app, ["run", "gcode_test_piece", "--set", "duration_s=0.5", "--json"])
    as_json = json.loads(short.output)
    assert as_json["lines"][0]["line"] == 11
    bad = CliRunner().invoke(app, ["run", "step_cncmt_hinf", "--lines", str(tmp_path / "x.parquet")])
    assert bad.exit_code == 2
    assert "needs a G-code reference" in bad.output
