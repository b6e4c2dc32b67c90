"""A run goes one way down the twin's layers (issue 49): followed call by call with
``.ci/callwalk.py`` (a developer's tool, loaded from its file: it is not part of the twin's
package and its layers), a G-code run with a stock never calls back up a layer; and the walk
does see a climb where there is one."""

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _callwalk():
    spec = importlib.util.spec_from_file_location("callwalk", ROOT / ".ci" / "callwalk.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks its module up while defined
    spec.loader.exec_module(module)
    return module


def test_a_run_never_climbs_back_up_a_layer():
    callwalk = _callwalk()
    opening, whole = callwalk.scenario_walk(duration_s=0.005, first=400)
    assert opening.calls == 400
    assert whole.calls > opening.calls
    # Measured on the one-way path (twin.outcome) and before it (826cc96): no climb at all in
    # either (the layers contract already forbids the imports one needs; only a callback could
    # climb, and none does). What remains are 4 sideways calls between the
    # independent layers twin.machining | twin.gcode | twin.machines, each a method of an object
    # handed down (machining.program_cut and machining.misuse call the plan's methods in
    # twin.gcode.planner, program_cut the machine's in twin.machines.base): no import, no climb.
    assert whole.climbs == []
    assert set(whole.sideways) <= {
        ("twin.machining.program_cut", "twin.gcode.planner"),
        ("twin.machining.misuse", "twin.gcode.planner"),
        ("twin.machining.program_cut", "twin.machines.base"),
    }
    assert whole.unlayered == set()


def test_the_walk_counts_a_callback_up_a_layer_and_a_reentry():
    callwalk = _callwalk()

    def in_module(module: str, source: str):
        namespace: dict = {"__name__": module}
        exec(source, namespace)
        return namespace["f"]

    up = in_module("twin.cli.fake", "def f():\n    return 1\n")
    down = in_module("twin.errors", "def f(callback):\n    return callback() + callback()\n")
    opening, whole = callwalk.walk_calls(lambda: down(up), pyproject=ROOT / "pyproject.toml", first=2)
    assert (opening.calls, whole.calls) == (2, 3)
    assert whole.climbs == [("twin.errors", "twin.cli.fake")] * 2
    assert opening.climbs == [("twin.errors", "twin.cli.fake")]
    assert whole.reentries == [("twin.errors", "twin.cli.fake")]
