"""Property-based fuzzing of every door a user's file comes in by (hypothesis): part programs,
stock and tool tables, machine files and measured traces, each mutated from a real one, through
the CLI's own entry point in process, against the contract of :mod:`twin.exits`.

Whatever the input: the exit code is 0, 2, 3 or 4 (never 1, never 70: a bug); nothing raises
past the CLI (no traceback); no warning is issued; a refusal (2) is exactly one ``error:`` line
on stderr and nothing on stdout; under ``--json`` stdout is one strict JSON document (no NaN,
no Infinity).  A program planned for a machine stays within the machine's limits and the
planner's tolerance wherever the planner reports no violation.

Seeds: the rs274-checked fixtures and the bundled programs (their moves agree with LinuxCNC's),
the example machine files, a trace written by ``twin excite --simulate``.  ``TWIN_FUZZ_PROGRAMS``
names a folder of more ``*.ngc`` programs to mutate (LinuxCNC's ``nc_files``, GPL, are not
committed here; the closing note of issue 33 counts a local run over them).

Profiles (``--hypothesis-profile``): ``default`` (derandomized, a few dozen examples per door),
``thorough`` 10 000 per door.
"""

import json
import os
import re
import tomllib
import warnings
from pathlib import Path

import pytest
from fuzz_toml import mutate, paths, toml_document, toml_value
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from twin.cli import app

ROOT = Path(__file__).resolve().parent.parent
PROGRAMS = sorted(
    [
        *(ROOT / "tests" / "fixtures" / "gcode").glob("*.ngc"),
        *(ROOT / "twin" / "scenarios" / "programs").glob("*.ngc"),
        *(Path(os.environ["TWIN_FUZZ_PROGRAMS"]).glob("*.ngc") if os.environ.get("TWIN_FUZZ_PROGRAMS") else []),
    ]
)
PROGRAM_LINES = {p.name: p.read_text(encoding="utf-8", errors="replace").splitlines() for p in PROGRAMS}
MACHINE_FILES = {
    p.name: p.read_text(encoding="utf-8") for p in sorted((ROOT / "examples" / "machines").glob("*_xy.toml"))
}
STOCK_SCENARIO = tomllib.loads((ROOT / "twin" / "scenarios" / "gcode_choi1999_circle_stock.toml").read_text())

#: Numbers a hostile user types: extremes, zero, negatives, tiny, non-finite.
HOSTILE = [0, -1, 1e308, -1e308, 5e-324, 1e300, 1e-300, 2**63, 1e30, 1e13, -0.0, 1e-12, 3.5]
numbers = st.one_of(
    st.sampled_from(HOSTILE), st.floats(allow_nan=True, allow_infinity=True), st.integers(-(10**20), 10**20)
)


def door_settings(examples: int) -> settings:
    """``examples`` per door under the default profile; the profile's own count (10 000)
    under ``thorough``."""
    profile = settings()
    return settings(
        max_examples=examples if profile.derandomize else profile.max_examples,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    )


def _strict_json(text: str):
    """The document, refusing NaN and Infinity as a strict JSON reader does."""

    def refuse(name):
        raise ValueError(f"{name} is not JSON")

    return json.loads(text, parse_constant=refuse)


def _invoke(args: list[str]):
    """The CLI in process; any warning fails the contract."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = CliRunner().invoke(app, args)
    assert not caught, [str(w.message) for w in caught]
    event(f"exit {result.exit_code}")
    return result


def _assert_contract(result, as_json: bool, what) -> None:
    """The exit-code contract of :mod:`twin.exits`."""
    assert result.exit_code in (0, 2, 3, 4), (result.exit_code, result.stderr[-500:], what)
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert "Traceback" not in result.stderr
    if result.exit_code == 2:
        assert result.stdout == "", (result.stdout[:300], what)
        lines = result.stderr.splitlines()
        assert len(lines) == 1, (result.stderr, what)
        assert lines[0].startswith("error: "), (result.stderr, what)
    elif result.exit_code:
        errors = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
        assert len(errors) == 1, result.stderr
        assert result.stderr.rstrip().endswith(errors[0]), result.stderr
    if as_json and result.stdout:
        _strict_json(result.stdout)


# --- part programs -------------------------------------------------------------------------

#: Programs planned at most this long (bytes): LinuxCNC's 14 kB tort.ngc takes 18 s to plan.
PLANNED_BYTES = 4000
WORD = re.compile(r"([A-Za-z])\s*([-+]?[0-9]*\.?[0-9]+)")


@st.composite
def mutated_programs(draw) -> bytes:
    """A real program with 1-4 mutations: a line deleted, two swapped, a number changed, a
    word dropped, a line duplicated, G20 inserted, or binary bytes."""
    lines = list(PROGRAM_LINES[draw(st.sampled_from(sorted(PROGRAM_LINES)))])
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["delete", "swap", "number", "drop", "duplicate", "g20", "bytes"]))
        if kind == "delete":
            del lines[i]
        elif kind == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif kind == "duplicate":
            lines.insert(i, lines[i])
        elif kind == "g20":
            lines.insert(i, "G20")
        elif kind == "bytes":
            lines[i] += draw(st.binary(max_size=12)).decode("latin-1")
        else:
            words = list(WORD.finditer(lines[i]))
            if not words:
                continue
            w = draw(st.sampled_from(words))
            if kind == "drop":
                lines[i] = lines[i][: w.start()] + lines[i][w.end() :]
            else:
                value = draw(st.sampled_from(["0", "-1", "1e5", "99999", "0.0001", "-0", "7.5", "1e-300", "360"]))
                lines[i] = lines[i][: w.start(2)] + value + lines[i][w.end(2) :]
    return "\n".join(lines).encode("latin-1", "replace") + b"\n"


@door_settings(40)
@given(program=mutated_programs(), planned=st.integers(0, 3))
def test_any_program_gives_moves_or_one_error_line(tmp_path, program, planned):
    path = tmp_path / "fuzz.ngc"
    path.write_bytes(program)
    planned = planned == 0 and len(program) < PLANNED_BYTES
    args = ["gcode", str(path), "--json"] + (["--machine", "cncmt_xy"] if planned else [])
    result = _invoke(args)
    _assert_contract(result, True, program[:300])
    if result.exit_code == 0 and planned:
        summary = _strict_json(result.stdout)["planned"]
        if not summary["violations"]:  # what it does not report, it keeps
            for axis, top in summary["max"].items():
                limit = summary["limits"][axis]
                for q in ("velocity_m_per_s", "acceleration_m_per_s2", "jerk_m_per_s3"):
                    assert top[q] <= limit[q] * 1.02 + 1e-12, (axis, q, top[q], limit[q], program[:300])
        assert summary["max_deviation_over_tolerance"] <= 1.0 + 1e-6, program[:300]


# --- stock and tools -----------------------------------------------------------------------


def _number_paths(data) -> list[tuple]:
    """Paths to every number (not a boolean) in nested dicts and lists."""
    found = []
    for path in paths(data):
        node = data
        for key in path:
            node = node[key]
        if isinstance(node, int | float) and not isinstance(node, bool):
            found.append(path)
    return found


@st.composite
def stock_and_tools(draw) -> dict:
    """The bundled stock scenario, its ``[stock]`` and ``[tool]`` tables' numbers mutated (an
    island over the whole stock now and then)."""
    data = json.loads(json.dumps(STOCK_SCENARIO))
    data["duration_s"] = 0.02
    data["reference"]["file"] = str(ROOT / "twin" / "scenarios" / data["reference"]["file"])
    data["stock"]["islands_mm"] = data["stock"]["islands_mm"] if draw(st.booleans()) else []
    if draw(st.integers(0, 9)) == 0:
        data["stock"]["islands_mm"] = [[[-500.0, -500.0], [500.0, -500.0], [500.0, 500.0], [-500.0, 500.0]]]
    where = [("stock", *p) for p in _number_paths(data["stock"])][:40] + [
        ("tool", *p) for p in _number_paths(data["tool"])
    ]
    for _ in range(draw(st.integers(1, 3))):
        mutate(data, draw(st.sampled_from(where)), draw(numbers))
    if draw(st.booleans()):
        data["tool"]["corner_radius_mm"] = draw(numbers)
    return data


@door_settings(25)
@given(scenario=stock_and_tools())
def test_any_stock_and_tool_give_a_result_or_one_error_line(tmp_path, scenario):
    path = tmp_path / "fuzz.toml"
    text = toml_document(scenario)
    path.write_text(text)
    result = _invoke(["run", str(path), "--json", "--max-steps", "20000"])
    _assert_contract(result, True, text[:300])


# --- machine files -------------------------------------------------------------------------

VALUE = re.compile(r"^(\s*[A-Za-z0-9_]+\s*=\s*)([-+0-9.e]+)", re.M)


@st.composite
def machine_files(draw) -> str:
    """An example machine file with 1-3 of its numbers replaced (or a key deleted)."""
    text = MACHINE_FILES[draw(st.sampled_from(sorted(MACHINE_FILES)))]
    for _ in range(draw(st.integers(1, 3))):
        found = list(VALUE.finditer(text))
        m = draw(st.sampled_from(found))
        if draw(st.integers(0, 7)) == 0:
            text = text[: m.start()] + text[m.end() :]
        else:
            text = text[: m.start(2)] + toml_value(draw(numbers)) + text[m.end(2) :]
    return text


@door_settings(40)
@given(machine=machine_files())
def test_any_machine_file_gives_a_model_or_one_error_line(tmp_path, machine):
    path = tmp_path / "fuzz_xy.toml"
    path.write_text(machine)
    result = _invoke(["mjcf", str(path), "--out", str(tmp_path / "model.xml")])
    _assert_contract(result, False, machine)


# --- traces --------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def trace_columns(tmp_path_factory) -> dict[str, list[float]]:
    """A short open-loop trace of linear_motor_xy written by ``twin excite --simulate``."""
    path = tmp_path_factory.mktemp("trace") / "trace.csv"
    result = CliRunner().invoke(
        app, ["excite", "linear_motor_xy", "--out", str(path), "--simulate", "--duration", "0.06"]
    )
    assert result.exit_code == 0, result.stderr
    rows = [line.split(",") for line in path.read_text().splitlines()]
    header = [h.strip('"') for h in rows[0]]
    return {h: [float(r[i]) for r in rows[1:]] for i, h in enumerate(header)}


@st.composite
def trace_mutations(draw):
    """(column, rows, value) replacements, a column dropped, a constant input, or rows cut."""
    kind = draw(st.sampled_from(["values", "values", "drop", "constant", "cut"]))
    column = draw(st.sampled_from(["time_s", "u_x_V", "pos_x_m"]))
    if kind == "values":
        return kind, column, draw(st.lists(st.integers(0, 599), min_size=1, max_size=5)), draw(numbers)
    if kind == "cut":
        return kind, column, draw(st.integers(0, 600)), None
    return kind, column, None, None


@door_settings(20)
@given(mutation=trace_mutations())
def test_any_trace_gives_a_fit_or_one_error_line(tmp_path, trace_columns, mutation):
    kind, column, where, value = mutation
    columns = {k: list(v) for k, v in trace_columns.items()}
    if kind == "values":
        for row in where:
            columns[column][row] = value
    elif kind == "drop":
        del columns[column]
    elif kind == "constant":
        columns["u_x_V"] = [0.5] * len(columns["u_x_V"])
    else:
        columns = {k: v[:where] for k, v in columns.items()}
    path = tmp_path / "trace.csv"
    names = list(columns)
    rows = zip(*(columns[n] for n in names), strict=True)
    path.write_text(",".join(names) + "\n" + "".join(",".join(repr(float(x)) for x in r) + "\n" for r in rows))
    result = _invoke(["calibrate", "linear_motor_xy", "--trace", str(path), "--fit", "m_x", "--json"])
    _assert_contract(result, True, mutation)


def test_the_mutations_reach_each_door():
    """The strategies' seeds are there: a fuzz test over nothing would pass vacuously."""
    assert len(PROGRAM_LINES) >= 10
    assert all(PROGRAM_LINES.values())
    assert len(MACHINE_FILES) >= 3
    assert all(len(VALUE.findall(t)) > 10 for t in MACHINE_FILES.values())
    assert len(_number_paths(STOCK_SCENARIO["stock"])) > 100
