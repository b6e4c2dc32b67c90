"""Property-based fuzzing of ``twin run`` with generated scenario files (hypothesis).

Mutations of the bundled scenarios (fields replaced by values of any type, including nan, inf,
huge, tiny and negative numbers, strings with control characters, nested tables; fields
deleted; or the file replaced by arbitrary bytes) go through the CLI's own entry point in
process.  Whatever the input: the exit code is 0, 2 or 3; no Python warning is issued; on 2 and
3 stderr ends in exactly one ``error:`` line; nothing raises past the CLI (no traceback); on 0 stdout is valid JSON with
finite numbers.  Each run is capped at 20 000 physics steps (``--max-steps``) so an example
takes well under a second.  Profiles (``--hypothesis-profile``): ``default`` 150 examples,
``thorough`` 10 000.
"""

import json
import math
import tomllib
import warnings

from fuzz_toml import mutate, paths, toml_document
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from twin.cli import app
from twin.scenario import bundled_scenarios

BUNDLED = {name: tomllib.loads(path.read_text()) for name, path in sorted(bundled_scenarios().items())}

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**30), 10**30),
    st.sampled_from([0, -1, 1e308, 5e-324, -0.0, 1e-12, 2**63]),
)
texts = st.text(max_size=20)
scalars = st.one_of(numbers, texts, st.booleans())
values = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(texts, inner, max_size=3)),
    max_leaves=8,
)


@st.composite
def scenario_files(draw) -> bytes:
    if draw(st.integers(0, 19)) == 0:  # now and then: any bytes at all
        return draw(st.binary(max_size=200))
    data = json.loads(json.dumps(BUNDLED[draw(st.sampled_from(sorted(BUNDLED)))]))
    data["duration_s"] = 0.02
    for _ in range(draw(st.integers(1, 3))):
        where = list(paths(data))
        if not where:
            break
        mutate(data, draw(st.sampled_from(where)), draw(values), draw(st.booleans()) and draw(st.booleans()))
    return toml_document(data).encode("utf-8", "surrogatepass")


def _finite(value) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    if isinstance(value, list):
        return all(_finite(v) for v in value)
    return True


@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(content=scenario_files())
def test_any_scenario_file_gives_a_result_or_one_error_line(tmp_path, content):
    path = tmp_path / "fuzz.toml"
    path.write_bytes(content)
    with warnings.catch_warnings(record=True) as caught:  # a warning is a second stderr line for a user
        warnings.simplefilter("always")
        result = CliRunner().invoke(app, ["run", str(path), "--json", "--max-steps", "20000"])
    event(f"exit {result.exit_code}")
    assert not caught, [str(w.message) for w in caught]
    assert result.exit_code in (0, 2, 3), (result.exit_code, repr(result.exception), content[:300])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    if result.exit_code == 0:
        out = json.loads(result.stdout)
        assert out["status"] == "ok"
        assert _finite(out)
    else:
        errors = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
        assert len(errors) == 1, result.stderr
        assert result.stderr.rstrip().endswith(errors[0]), result.stderr
