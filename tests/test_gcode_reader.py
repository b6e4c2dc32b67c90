"""The G-code reader against LinuxCNC's interpreter: the fixtures are ``rs274``'s canonical
calls for the test programs (tests/fixtures/gcode/regenerate.py), read back and compared move by
move to rs274's printed precision (4 decimals of its unit) with the spindle, coolant and feed in
force; every program in ``refused/`` is refused by both at the same block. What rs274 cannot
show (limits, memory, LinuxCNC's manual where rs274 2.9 departs from it) is tested after."""

import itertools
import math
import sys
from pathlib import Path

import pytest

from twin.gcode.flow import MAX_CALL_DEPTH, MAX_ITERATIONS
from twin.gcode.reader import GcodeError, Reader, Settings, read_program
from twin.gcode.words import MAX_LINE_CHARS

FIXTURES = Path(__file__).parent / "fixtures" / "gcode"
sys.path.insert(0, str(FIXTURES))
from canon import canonical_moves, first_difference  # noqa: E402

INCH = 25.4
#: The settings rs274 ran with (regenerate.py's parameter file and tool table, in mm).
SETTINGS = Settings(
    work_offsets_mm={1: (0.5 * INCH, 0.25 * INCH, 0.0), 2: (INCH, -INCH, 0.5 * INCH), 3: (-2 * INCH, 0.0, 0.0)},
    tool_lengths_mm={1: 0.2 * INCH},
    g28_home_mm=(0.1 * INCH, 0.2 * INCH, 0.3 * INCH),
    tool_diameters_mm={1: 0.25 * INCH, 2: 0.5 * INCH, 3: -0.125 * INCH, 4: 0.0625 * INCH},
)
PROGRAMS = sorted(p.name for p in FIXTURES.glob("*.ngc"))
REFUSED = sorted(p.name for p in (FIXTURES / "refused").glob("*.ngc"))


def _settings() -> Settings:
    """A fresh copy (G10 L1 may change a program's tool table)."""
    return Settings(
        dict(SETTINGS.work_offsets_mm),
        dict(SETTINGS.tool_lengths_mm),
        SETTINGS.g28_home_mm,
        SETTINGS.g30_home_mm,
        tool_diameters_mm=dict(SETTINGS.tool_diameters_mm),
    )


@pytest.mark.parametrize("program", PROGRAMS)
def test_moves_match_linuxcnc_rs274(program):
    ours = list(read_program(FIXTURES / program, _settings()))
    canon = (FIXTURES / program).with_suffix(".canon").read_text()
    assert canon.rstrip().endswith("rc=0"), "rs274 read the program"
    theirs = canonical_moves(canon)
    assert len(theirs) > 8
    assert first_difference(ours, theirs) is None


def test_the_fixtures_exercise_the_language():
    """Each construct the reader takes appears in a fixture rs274 read (so a comparison covers it)."""
    text = "\n".join((FIXTURES / p).read_text().lower() for p in PROGRAMS)
    for construct in (
        *("g73", "g81", "g82", "g83", "g85", "g86", "g89", "g98", "g99", " l4", "g91 g81", "@10 ^0"),
        *("sub", "endsub [", "call [", "while [", "endwhile", " do", "repeat [", "if [", "elseif", "else", "break"),
        *("#<_", "#<depth>", "##10", "exists[", "atan[", "mod", "**", " xor ", "#5220", "#5421"),
        *("g92 ", "g92.1", "g92.2", "g92.3", "g52 ", "g10 l2", "g10 l20", "g28.1", "g30.1", "g53 ", "m70", "m72"),
        *("g61", "g61.1", "g64 p", "g64p.01q.005", "g80 g00", "m7", "m8", "m9", "f9991300", "g00\n", "g20", "g91.1"),
    ):
        assert construct in text, construct


@pytest.mark.parametrize("program", REFUSED)
def test_refused_where_linuxcnc_refuses(program):
    """rs274 stops at a block with an error; the reader refuses the same block (its error names
    the file, line, block and reason)."""
    path = FIXTURES / "refused" / program
    canon = path.with_suffix(".canon").read_text().rstrip().splitlines()
    assert canon[-1] == "rc=1", "rs274 refused the program"
    with pytest.raises(GcodeError) as err:
        list(read_program(path, _settings()))
    lines = path.read_text(encoding="utf-8").splitlines()
    assert canon[-2].strip() == lines[err.value.line - 1].strip()[: len(canon[-2].strip())], err.value
    shown, marker, _ = str(err.value).partition(f":{err.value.line} = ")
    assert marker, err.value
    assert shown == str(path) or (shown.startswith("...") and str(path).endswith(shown[3:])), shown


def _read(text: str, settings: Settings | None = None):
    return list(Reader(text.splitlines(), settings, "part.ngc").moves())


@pytest.mark.parametrize(
    "program, line, words",
    [
        ("G21 F100\nG41 G1 X1 Y1 D5", 2, "Requested tool 5 not found in the tool table (reference.tool_diameters_mm)"),
        ("G93 G1 X1 F2", 1, "inverse-time feed (G93)"),
        ("G5 X1 Y1 I1 J1 P1 Q1", 1, "splines (G5)"),
        ("G38.2 Z-1 F10", 1, "probing"),
        ("G1 X1 A2 F100", 1, "axis A is not one of"),
        ("M98 P100", 1, "M98/M99"),
        ("M101", 1, "user M codes"),
        ("G43 H7", 1, "tool 7 is not in the tool table (reference.tool_lengths_mm)"),
        ("G10 L2 P1 R45", 1, "rotated coordinate system"),
        ("G84 X1 Y1 Z-1 R1 F100", 1, "tapping (G84)"),
    ],
)
def test_what_the_twin_refuses_names_line_text_and_reason(program, line, words):
    with pytest.raises(GcodeError) as err:
        _read(program)
    assert err.value.line == line
    assert words in err.value.reason, str(err.value)
    assert str(err.value).startswith(f"part.ngc:{line} = {program.splitlines()[line - 1]!r}: ")


def test_a_file_that_is_not_text_is_refused_with_its_line(tmp_path):
    path = tmp_path / "binary.ngc"
    path.write_bytes(b"G0 X0\nG1 X1 F100\n\xff\xfe\x00\x01\n")
    with pytest.raises(GcodeError) as err:
        list(read_program(path))
    assert err.value.line == 3
    assert "NUL" in err.value.reason
    with pytest.raises(GcodeError, match="cannot be read"):
        list(read_program(tmp_path / "missing.ngc"))


def test_bytes_that_are_not_utf8_are_read_in_comments_and_refused_outside(tmp_path):
    """rs274 reads bytes: a Latin-1 degree sign in a comment is no error, outside one it is."""
    path = tmp_path / "latin1.ngc"
    path.write_bytes(b"G21 (angle 90\xb0)\nG0 X1\nG0 X\xb01\nM2\n")
    moves = []
    with pytest.raises(GcodeError) as err:
        moves.extend(read_program(path))
    assert len(moves) == 1
    assert err.value.line == 3
    assert "bad number format" in err.value.reason


def test_a_huge_line_is_refused_after_reading_at_most_its_limit(tmp_path):
    """A 64 MiB line with no newline: refused with the first characters in the message, having
    read no more than LinuxCNC's line length of it (tracemalloc's peak stays tiny)."""
    import tracemalloc

    path = tmp_path / "one_line.ngc"
    with path.open("wb") as out:
        out.write(b"G0 X1\n")
        for _ in range(64):
            out.write(b"X" * (1 << 20))
    tracemalloc.start()
    with pytest.raises(GcodeError) as err:
        list(read_program(path))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert err.value.line == 2
    assert f"more than {MAX_LINE_CHARS} characters" in err.value.reason
    assert peak < 200_000, peak


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


def test_a_loop_read_from_a_file_goes_back_by_seeking_in_bounded_memory(tmp_path):
    """A while loop of 10 000 iterations: the file is read again by byte offset, nothing kept
    (14 kB at its peak; the moves kept would take 5.6 MB)."""
    import tracemalloc

    path = tmp_path / "loop.ngc"
    path.write_text("G21 F1000\n#1 = 0\no1 while [#1 LT 10000]\nG1 X[#1 MOD 7] Y#1\n#1 = [#1 + 1]\no1 endwhile\nM2\n")
    tracemalloc.start()
    count = sum(1 for _ in read_program(path))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert count == 10_000
    assert peak < 300_000, peak


def test_loops_that_never_end_and_calls_too_deep_are_refused_at_their_limit(monkeypatch):
    """The iteration limit lowered to 20 000 (the real one, a million, takes 30 s to reach)."""
    import twin.gcode.flow

    assert MAX_ITERATIONS == 1_000_000
    monkeypatch.setattr(twin.gcode.flow, "MAX_ITERATIONS", 20_000)
    with pytest.raises(GcodeError) as err:
        _read("#1 = 0\no1 while [1]\n#1 = [#1 + 1]\no1 endwhile")
    assert err.value.line == 4
    assert "more than 20,000 loop iterations" in err.value.reason
    with pytest.raises(GcodeError, match=f"more than {MAX_CALL_DEPTH} nested subroutine calls"):
        _read("o1 sub\no1 call\no1 endsub\no1 call")


def test_continue_in_a_do_loop_continues_it_as_the_manual_says():
    """LinuxCNC's manual: continue skips to the loop's test. rs274 2.9.0~pre1 leaves a do loop at
    a continue when a break of the same loop follows it (a difference the docs page names)."""
    moves = _read(
        "G21 F100\n#1 = 0\no1 do\n#1 = [#1 + 1]\no2 if [#1 EQ 2]\no1 continue\no2 endif\nG1 X#1\n"
        "o3 if [#1 GE 4]\no1 break\no3 endif\no1 while [#1 LT 100]\nG1 Y1"
    )
    assert [m.end_mm[0] for m in moves] == [1.0, 3.0, 4.0, 4.0]
    assert moves[-1].end_mm[1] == 1.0


def test_m73_restores_the_callers_state_at_the_return():
    moves = _read("G21 G90 F100\no1 sub\nM73\nG20 G91\nG1 X1\no1 endsub\no1 call\nG1 X0")
    assert moves[0].end_mm[0] == pytest.approx(25.4)
    assert moves[1].end_mm[0] == 0.0  # G21 G90 back


def test_system_parameters_hold_the_machines_units_and_the_programs():
    """The work offsets' parameters are in the machine's units (mm); #5420 and #<_x> in the
    program's (as LinuxCNC's user and program units)."""
    settings = Settings(work_offsets_mm={1: (10.0, 0.0, 0.0)})
    moves = _read("G20 G0 X1\nG0 X#5221 Y#5420 Z#<_metric>", settings)
    assert moves[1].end_mm == pytest.approx((10.0 * INCH, INCH, 0.0))


@pytest.mark.parametrize(
    "program, feeds",
    [
        ("G21\nG1 X1 F9991300", [9991300.0]),  # a post's "as fast as allowed": the planner clamps it
        ("G21\nG20 F10\nG1 X1", [10.0]),  # F before G20 in a block: in the units before it (LinuxCNC)
        ("G20\nF10\nG21 G1 X1", [254.0]),  # a feed keeps its speed across G20/G21
    ],
)
def test_feeds_as_linuxcnc_moves_them(program, feeds):
    assert [m.feed_mm_per_min for m in _read(program)] == pytest.approx(feeds)


def test_path_modes_and_tolerances_per_block():
    moves = _read("G21 F100\nG1 X1\nG64 P0.02\nG1 X2\nG61\nG1 X3\nG61.1\nG1 X4\nG64 P-1\nG1 X5\nG20 G64 P0.001\nG1 X6")
    assert [m.path_mode for m in moves] == ["G64", "G64", "G61", "G61.1", "G64", "G64"]
    assert [m.tolerance_mm for m in moves][:5] == [None, 0.02, None, None, None]
    assert moves[5].tolerance_mm == pytest.approx(0.0254)


def test_a_bare_motion_word_is_a_null_move_and_coolant_is_per_move():
    moves = _read("G21\nG0 X1\nM8\nG0\nM7\nG0 X2\nM9\nG0 X3")
    assert [m.end_mm[0] for m in moves] == [1.0, 1.0, 2.0, 3.0]
    assert [m.coolant for m in moves] == ["off", "flood", "mist+flood", "off"]


def test_inch_programs_and_modal_state():
    moves = _read("G20 G91\nG0 X1 Y1\nG1 X1 F10\nG21 G90\nG1 X0 Y0")
    assert moves[0].end_mm == pytest.approx((25.4, 25.4, 0.0))
    assert moves[1].end_mm == pytest.approx((50.8, 25.4, 0.0))
    assert moves[1].feed_mm_per_min == pytest.approx(254.0)
    assert moves[2].feed_mm_per_min == pytest.approx(254.0)
    assert math.isclose(moves[2].end_mm[0], 0.0)


def test_every_word_and_coordinate_is_bounded():
    with pytest.raises(GcodeError, match="beyond 1e"):
        _read("G1 X" + "9" * 200 + " F100")
    with pytest.raises(GcodeError, match="beyond 1e"):
        _read("G21 F100\n#1 = 999999\no1 repeat [3]\nG91 G1 X#1\no1 endrepeat")


def test_an_error_in_a_file_deep_in_folders_keeps_its_name_and_line(tmp_path):
    deep = tmp_path / ("a_folder_with_a_long_name_" * 4) / "part.ngc"
    deep.parent.mkdir()
    deep.write_text("G21\nG0 X1\nG93 X2\n")
    with pytest.raises(GcodeError) as err:
        list(read_program(deep))
    field = str(err.value).split(" = ")[0]
    assert field.startswith("...")
    assert field.endswith("_name_/part.ngc:3")
    assert len(field) <= 80
    assert str(err.value).startswith(f"{field} = 'G93 X2': inverse-time feed")


def test_a_line_separator_before_percent_is_a_bad_character(tmp_path):
    """U+2028 is white space to Python's ``str.strip``, not to LinuxCNC's ``isspace``. rs274
    (``rs274 -g`` as regenerate.py runs it) on this file: ``Bad character '\\342' used``, rc=1, at
    line 1 (a vertical tab before the % it reads; its .canon cannot hold the line: U+2028 splits
    it). The no-break space is ``refused/nbsp_percent.ngc``."""
    path = tmp_path / "separator.ngc"
    path.write_bytes("\u2028%\nG21\nG0 X1\n%\n".encode())
    with pytest.raises(GcodeError) as err:
        list(read_program(path))
    assert err.value.line == 1
    assert "bad character" in err.value.reason and "\\u2028" in err.value.reason
    path.write_bytes(b"\x0b%\nG21\nG0 X1\n%\n")
    assert len(list(read_program(path))) == 1


def test_a_percent_never_closed_is_read_to_m2():
    """rs274 reads ``%`` / ``G21`` / ``G0 X1`` / ``M2`` (rc=0, with the comment "interpreter:
    percent sign missing from end of file"); without the M2 it refuses the last line ("File
    ended with no percent sign": ``refused/percent_not_closed.ngc``)."""
    assert len(_read("%\nG21\nG0 X1\nM2\n")) == 1
    with pytest.raises(GcodeError) as err:
        _read("%\nG21\nG0 X1\n")
    assert err.value.line == 3
    assert "without its closing %" in err.value.reason


def test_a_negative_dwell_in_a_cycle_is_refused():
    """rs274 refuses G82 / G89 with P-1 (its "P word missing": ``refused/g82_negative_p.ngc``),
    but reads ``G82 X1 Y1 Z-1 R1 P-2`` with ``DWELL(-2.0000)`` (rc=0): the twin refuses every
    negative dwell, as for G4 (a negative time has no meaning for the machine)."""
    for program in ("G21 F100\nG82 X1 Y1 Z-1 R1 P-2", "G21 F100\nG89 X1 Y1 Z-1 R1 P1\nX2 P-0.5"):
        with pytest.raises(GcodeError) as err:
            _read(program)
        assert err.value.line == program.count("\n") + 1
        assert "a dwell cannot be negative" in err.value.reason


@pytest.mark.parametrize(
    "program, line, words",
    [
        ("G21 F100\nG17 G2 X1 I0.5 K1", 2, "K = 1: K word given for an arc in the XY plane"),
        ("G21 F100\nG18 G2 X1 I0.5 J-2", 2, "J = -2: J word given for an arc in the ZX plane"),
        ("G21\no1 while [0]\no1 endwhile\no1 if [1]\no1 endif", 4, "already defined on line 2 (o1 while)"),
        ("G21\no7 if [1]\no7 endif\no7 else", 4, "the file ends inside o7 (started on line 4), looking for its endif"),
        ("G21\no1 if [0]\no1 endrepeat\no1 endif", 3, "o1 is an if, not a loop"),
        ("G21\no100 sub\no1 endif\no100 endsub\no1 if [1]\no1 endif\no100 call", 3, "without its if"),
    ],
)
def test_labels_and_arc_words_refused_as_rs274_refuses(program, line, words):
    """Each refused by rs274 at the same line (the 4th at the end of the file: rs274 takes ``o7
    else`` after its endif as a branch to skip and reads on to the end of the file for an ``o7
    endif``: "File ended with no percent sign or program end", rc=1; ``if_branches.ngc`` has
    such branches closed)."""
    with pytest.raises(GcodeError) as err:
        _read(program)
    assert err.value.line == line
    assert words in err.value.reason, str(err.value)


COMPENSATION_REFUSED = sorted(p for p in REFUSED if p.startswith("comp_"))


@pytest.mark.parametrize("program", COMPENSATION_REFUSED)
def test_compensation_refused_with_linuxcnc_words(program):
    """Cutter compensation's errors in rs274's own words (its message is the .canon's line
    before the block)."""
    path = FIXTURES / "refused" / program
    message = path.with_suffix(".canon").read_text().rstrip().splitlines()[-3].strip()
    with pytest.raises(GcodeError) as err:
        list(read_program(path, _settings()))
    assert err.value.reason.startswith(message), (message, err.value.reason)


@pytest.mark.parametrize("program", ["cutter_comp.ngc", "cutter_comp_xz.ngc"])
def test_compensated_moves_join_end_to_start(program):
    """Held moves are released with their ends moved: each starts where the one before ends
    (machine coordinates), through G40 too, where the reader's current point jumps back to the
    programmed point while the tool has not moved."""
    moves = list(read_program(FIXTURES / program, _settings()))
    for before, after in itertools.pairwise(moves):
        end = [e + o for e, o in zip(before.end_mm, before.offset_mm)]
        start = [s + o for s, o in zip(after.start_mm, after.offset_mm)]
        assert start == pytest.approx(end, abs=1e-9), (before, after)


def test_the_compensation_fixtures_exercise_it():
    """Each kind of corner and move the compensation has appears in a fixture rs274 read."""
    text = "\n".join((FIXTURES / p).read_text().lower() for p in ("cutter_comp.ngc", "cutter_comp_xz.ngc"))
    for construct in ("g41 d1", "g42 g1", "g41 d3", "g41.1 d4", "g42.1 d5", "g41.1 d0.1 l2", "g42.1 d0.1 l6"):
        assert construct in text, construct
    for construct in ("g18", "g20 (inches under", "g4 p0.5", "m8 (", "g0 y40", "g91 x-10", "r-15", "p2 (", "g40"):
        assert construct in text, construct


def test_tool_diameters_come_from_the_scenario():
    """A 6 mm tool around a square corner: inside (G41 turning left), the lines meet 3 mm from
    both edges; outside (G42), an arc of radius 3 about the corner joins them."""
    from twin.references.gcode import GcodeRef

    spec = GcodeRef(type="gcode", file="part.ngc", tool_diameters_mm={1: 6.0})
    inside = _read("G21 F600\nG0 X0 Y0\nG41 D1 G1 X20 Y0\nY20\nM2", spec.reader_settings())
    assert [v for m in inside[1:] for v in m.end_mm[:2]] == pytest.approx([17.0, 3.0, 17.0, 20.0])
    outside = _read("G21 F600\nG0 X0 Y0\nG42 D1 G1 X20 Y0\nY20\nM2", spec.reader_settings())
    assert [v for m in outside[1:] for v in m.end_mm[:2]] == pytest.approx([20.0, -3.0, 23.0, 0.0, 23.0, 20.0])
    assert outside[2].kind == "arc" and outside[2].center_mm == (20.0, 0.0) and outside[2].turns == 1
    # the scenario's [[tools]] give diameters too; the reference's table wins over them
    merged = spec.reader_settings(frozenset({1, 2}), {1: 10.0, 2: 8.0}).tool_diameters_mm
    assert merged == {1: 6.0, 2: 8.0}


def test_a_program_without_an_end_is_read_to_its_last_line():
    """rs274 gives every move of a program with neither % nor M2 / M30, then exits 1 "File
    ended with no percent sign or program end" (``unended/no_program_end.canon``): the twin
    reads the same moves and takes the end of the file as the program's end."""
    path = FIXTURES / "unended" / "no_program_end.ngc"
    canon = path.with_suffix(".canon").read_text().rstrip().splitlines()
    assert canon[-1] == "rc=1" and canon[-3] == "File ended with no percent sign or program end"
    theirs = canonical_moves("\n".join(canon))
    assert len(theirs) == 9
    assert first_difference(list(read_program(path, _settings())), theirs) is None


def test_compensation_holds_a_bounded_number_of_moves(monkeypatch):
    """Moves along Z are held until a move in the plane: a loop of them is refused at the limit."""
    from twin.gcode import compensation

    monkeypatch.setattr(compensation, "MAX_HELD", 50)
    program = "G21 F600\nG0 X0 Y0\nG41 D1 G1 X20 Y0\no1 repeat [100]\nG1 Z-1\nG1 Z0\no1 endrepeat\nM2"
    with pytest.raises(GcodeError) as err:
        _read(program, _settings())
    assert err.value.line == 6 and "more than 50 moves and dwells held" in err.value.reason
    assert len(_read(program.replace("[100]", "[20]"), _settings())) == 2 + 40


def test_the_end_of_a_file_releases_the_moves_compensation_holds():
    """No M2: the held move is released at the end of the file, as M2 would release it (rs274
    prints the moves before it, then "File ended with no percent sign or program end")."""
    moves = _read("G21 F600\nG0 X0 Y0\nG41 D1 G1 X20 Y0\nY20", _settings())
    radius = 0.125 * INCH
    assert [m.kind for m in moves] == ["rapid", "feed", "feed"]
    assert moves[1].end_mm[:2] == pytest.approx((20 - radius, radius))
    assert moves[2].end_mm[:2] == pytest.approx((20 - radius, 20.0))
    assert moves[2].start_mm == moves[1].end_mm
