"""The G-code reader against LinuxCNC's interpreter: the fixtures are ``rs274``'s canonical
calls for the test programs (tests/fixtures/gcode/regenerate.py), read back here and compared
move by move to 1e-4 mm (rs274 prints 4 decimals)."""

import math
import re
from pathlib import Path

import pytest

from twin.gcode.reader import GcodeError, Reader, Settings, read_program

FIXTURES = Path(__file__).parent / "fixtures" / "gcode"
INCH = 25.4
#: The settings rs274 ran with (regenerate.py's parameter file and tool table, in mm).
SETTINGS = Settings(
    work_offsets_mm={1: (0.5 * INCH, 0.25 * INCH, 0.0), 2: (INCH, -INCH, 0.5 * INCH), 3: (-2 * INCH, 0.0, 0.0)},
    tool_lengths_mm={1: 0.2 * INCH},
    g28_home_mm=(0.1 * INCH, 0.2 * INCH, 0.3 * INCH),
)
#: ARC_FEED's in-plane axes (first, second) and normal axis for each plane.
PLANE_AXES = {"xy": (0, 1, 2), "zx": (2, 0, 1), "yz": (1, 2, 0)}
_CALL = re.compile(r"(STRAIGHT_TRAVERSE|STRAIGHT_FEED|ARC_FEED|DWELL|USE_LENGTH_UNITS|SELECT_PLANE)\((.*)\)")


def canonical_moves(path: Path) -> list[dict]:
    """rs274's motion calls as dicts in mm: kind, end, and for arcs plane, center, turns."""
    scale, plane, out = 1.0, "xy", []
    for line in path.read_text().splitlines():
        m = _CALL.search(line)
        if not m:
            continue
        name, args = m.group(1), m.group(2)
        if name == "USE_LENGTH_UNITS":
            scale = INCH if "INCHES" in args else 1.0
            continue
        if name == "SELECT_PLANE":
            plane = {"CANON_PLANE_XY": "xy", "CANON_PLANE_XZ": "zx", "CANON_PLANE_YZ": "yz"}[args.strip()]
            continue
        values = [float(v) for v in args.split(",")]
        if name == "DWELL":
            out.append({"kind": "dwell", "dwell_s": values[0], "unit_mm": scale})
        elif name == "ARC_FEED":
            first, second, normal = PLANE_AXES[plane]
            end = [0.0, 0.0, 0.0]
            end[first], end[second], end[normal] = values[0] * scale, values[1] * scale, values[5] * scale
            out.append(
                {
                    "kind": "arc",
                    "end": end,
                    "plane": plane,
                    "center": [values[2] * scale, values[3] * scale],
                    "turns": int(values[4]),
                    "unit_mm": scale,
                }
            )
        else:
            kind = "rapid" if name == "STRAIGHT_TRAVERSE" else "feed"
            out.append({"kind": kind, "end": [v * scale for v in values[:3]], "unit_mm": scale})
    return out


@pytest.mark.parametrize("program", sorted(p.name for p in FIXTURES.glob("*.ngc")))
def test_moves_match_linuxcnc_rs274(program):
    ours = list(read_program(FIXTURES / program, SETTINGS))
    theirs = canonical_moves((FIXTURES / program).with_suffix(".canon"))
    assert len(theirs) > 3
    assert [m.kind for m in ours] == [m["kind"] for m in theirs]
    for mine, ref in zip(ours, theirs):
        if ref["kind"] == "dwell":
            assert mine.dwell_s == ref["dwell_s"]
            continue
        # rs274 prints 4 decimals of its unit: 1e-4 mm in G21, 1e-4 in (2.54e-3 mm) in G20
        tol = 1e-4 * ref["unit_mm"]
        assert mine.end_mm == pytest.approx(ref["end"], abs=tol), (mine.line, mine.end_mm)
        if ref["kind"] == "arc":
            assert (mine.plane, mine.turns) == (ref["plane"], ref["turns"]), mine.line
            assert mine.center_mm == pytest.approx(ref["center"], abs=tol), mine.line


def _read(text: str, settings: Settings | None = None):
    return list(Reader(text.splitlines(), settings, "part.ngc").moves())


@pytest.mark.parametrize(
    "program, line, words",
    [
        ("G21\nG41 X1 Y1 D1", 2, "cutter radius compensation (G41)"),
        ("G42 X1", 1, "cutter radius compensation (G42)"),
        ("G81 X1 Y1 Z-1 R1 F100", 1, "canned cycles (G81)"),
        ("G83 X1 Y1 Z-1 R1 Q1 F100", 1, "canned cycles (G83)"),
        ("#1 = 2", 1, "parameters (#)"),
        ("G1 X[1+2] F100", 1, "expressions ([ ])"),
        ("O100 sub", 1, "O-words"),
        ("G93 G1 X1 F2", 1, "inverse-time feed (G93)"),
        ("G5 X1 Y1 I1 J1 P1 Q1", 1, "splines (G5)"),
        ("G0 G1 X1", 1, "two motion words in one block"),
        ("G0 X0\nG1 X1", 2, "G1 with no feed set"),
        ("G0 X0\nG2 X1 Y0 I0.5", 2, "G2 with no feed set"),
        ("X1", 1, "no motion mode"),
        ("G0 X0 Y0\nG2 X1.2 Y0 I0.5 J0 F10", 2, "the end is not on the arc's circle"),
        ("G0 X0 Y0\nG2 X1 Y0 R0.4 F100", 2, "smaller than half the chord"),
        ("G0 X0 Y0\nG2 X0 Y0 R1 F100", 2, "cannot be a full circle"),
        ("G1 X1 F100 F200", 1, "two F words"),
        ("G1 X1 A2 F100", 1, "axis A is not one of"),
        ("G12 X1", 1, "G12 is not supported"),
        ("M98 P100", 1, "M98 is not supported"),
        ("G1 X1 (open comment F100", 1, "not closed"),
        ("G1 X1 Y$ F100", 1, "cannot read"),
        ("G0 X0\nG4", 2, "G4 needs a P word"),
        ("G0 X0\nG2 X0 Y0 I1 P1.5 F100", 2, "turns of an arc"),
        ("G43 H7", 1, "tool 7 is not in the tool table"),
    ],
)
def test_unsupported_and_bad_blocks_name_their_line_text_and_reason(program, line, words):
    with pytest.raises(GcodeError) as err:
        _read(program)
    assert err.value.line == line and words in err.value.reason, str(err.value)
    assert str(err.value).startswith(f"part.ngc:{line}: {program.splitlines()[line - 1]!r}: ")


def test_a_file_that_is_not_text_is_refused_with_its_line(tmp_path):
    path = tmp_path / "binary.ngc"
    path.write_bytes(b"G0 X0\nG1 X1 F100\n\xff\xfe\x00\x01\n")
    with pytest.raises(GcodeError) as err:
        list(read_program(path))
    assert err.value.line == 3 and "not text" in err.value.reason
    with pytest.raises(GcodeError, match="cannot be read"):
        list(read_program(tmp_path / "missing.ngc"))


def test_the_reader_streams_a_long_program_in_bounded_memory():
    """A long program read lazily: nothing is kept but the state (tracemalloc's peak stays far
    below what a list of the moves would take; a million lines is `twin bench`'s case)."""
    import tracemalloc

    def lines():
        yield "G21 G90 G94 F1000"
        for i in range(50_000):
            yield f"G1 X{i % 100} Y{(i * 7) % 50}"

    tracemalloc.start()
    count = sum(1 for _ in Reader(lines()).moves())
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert count == 50_000
    assert peak < 2_000_000, peak  # a list of 50 000 moves would take over 25 MB


def test_inch_programs_and_modal_state():
    moves = _read("G20 G91\nG0 X1 Y1\nG1 X1 F10\nG21 G90\nG1 X0 Y0")
    assert moves[0].end_mm == pytest.approx((25.4, 25.4, 0.0))
    assert moves[1].end_mm == pytest.approx((50.8, 25.4, 0.0)) and moves[1].feed_mm_per_min == pytest.approx(254.0)
    assert moves[2].feed_mm_per_min == pytest.approx(254.0)  # F stays in mm/min after G21
    assert math.isclose(moves[2].end_mm[0], 0.0)


def test_every_word_is_bounded():
    with pytest.raises(GcodeError, match="beyond 1e"):
        _read("G1 X" + "9" * 200 + " F100")
