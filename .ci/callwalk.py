"""Follow one run call by call: how often does it climb back up a layer of the twin?

A developer's measurement (issue 49, item 1), not part of the twin: ``sys.settrace`` records
every Python-level call into a ``twin.*`` module while ``twin.scenario.run_scenario`` runs one
bundled G-code scenario with a stock (numba-compiled kernels make no Python calls and do not
show). Each module gets the index of its layer in the import-linter ``layers`` contract of the
pyproject.toml beside the ``twin`` package imported (0 the top, ``twin.launcher``; a module
belongs to the deepest listed layer that prefixes it).

A call's caller is the nearest ``twin.*`` frame below it on the stack (``f_back``), so a
callback through a library (a pydantic validator, a scipy solver) still counts from the twin
module that handed it over. Returns are not calls. (``sys.settrace`` rather than
``sys.setprofile``: the same call events, without one for each call into C, which made a run
over ten times slower.) Module bodies run by an import (a lazy
import inside a function) and everything they call are left out.

- a climb: a call from a module of a lower layer into one of a higher layer;
- a sideways call: between two independent layers of one line of the contract (``a | b``);
- a re-entry: a call from another module into a module the walk had entered before and left
  (no frame of it on the stack).

Usage (from a checkout's root, with its environment)::

    uv run python .ci/callwalk.py [--first 400] [--duration 0.02] [--scenario NAME]
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from types import CodeType, FrameType

SCENARIO = "gcode_choi1999_circle_stock"
DURATION_S = 0.02
FIRST_CALLS = 400
LAYERS_CONTRACT = "layers"


def layer_index(pyproject: Path) -> dict[str, int]:
    """The twin's layers from the import-linter ``layers`` contract of ``pyproject``: each
    listed module (``a | b`` lists two, independent) to its layer's index, 0 the top."""
    config = tomllib.loads(pyproject.read_text())["tool"]["importlinter"]
    (contract,) = (c for c in config["contracts"] if c["type"] == LAYERS_CONTRACT)
    return {
        name.strip(): index for index, line in enumerate(contract["layers"]) for name in line.split("|") if name.strip()
    }


def layer_of(module: str, layers: dict[str, int]) -> tuple[str, int] | None:
    """The deepest listed layer module that prefixes ``module`` and its index, or None."""
    owners = [name for name in layers if module == name or module.startswith(name + ".")]
    if not owners:
        return None
    owner = max(owners, key=len)
    return owner, layers[owner]


@dataclass
class CallWalk:
    """The calls into the twin's modules of one run, in order.

    Attributes
    ----------
    calls : int
        Python-level calls into ``twin.*`` modules.
    climbs : list of (str, str)
        (caller module, callee module) of each call up a layer.
    sideways : list of (str, str)
        (caller, callee) of each call between two independent layers of one line.
    reentries : list of (str, str)
        (caller, callee) of each call into a module entered before and since left.
    unlayered : set of str
        Modules called that no layer of the contract holds.
    """

    calls: int = 0
    climbs: list[tuple[str, str]] = field(default_factory=list)
    sideways: list[tuple[str, str]] = field(default_factory=list)
    reentries: list[tuple[str, str]] = field(default_factory=list)
    unlayered: set[str] = field(default_factory=set)


class _Recorder:
    """The trace function: counts every call into the twin, the first ``first`` also apart."""

    def __init__(self, layers: dict[str, int], first: int) -> None:
        self.layers = layers
        self.first = first
        self.whole = CallWalk()
        self.opening = CallWalk()
        self.entered: set[str] = set()
        self.importing: FrameType | None = None
        self.module_of_code: dict[CodeType, str | None] = {}

    def _twin_module(self, frame: FrameType) -> str | None:
        code = frame.f_code
        if code not in self.module_of_code:
            name = frame.f_globals.get("__name__", "")
            self.module_of_code[code] = name if name == "twin" or name.startswith("twin.") else None
        return self.module_of_code[code]

    def _caller(self, frame: FrameType) -> tuple[str | None, set[str]]:
        """The nearest twin module below ``frame`` and the twin modules on the stack."""
        caller = None
        on_stack: set[str] = set()
        below = frame.f_back
        while below is not None:
            module = self._twin_module(below)
            if module is not None:
                caller = caller or module
                on_stack.add(module)
            below = below.f_back
        return caller, on_stack

    def __call__(self, frame: FrameType, event: str, arg: object) -> Callable | None:
        """The global trace function: called for each Python-level call (C calls make none)."""
        if self.importing is not None or event != "call":
            return None
        if frame.f_code.co_name == "<module>":
            self.importing = frame
            return self._end_of_import
        callee = self._twin_module(frame)
        if callee is None:
            return None
        caller, on_stack = self._caller(frame)
        walks = [self.whole] if self.whole.calls >= self.first else [self.whole, self.opening]
        for walk in walks:
            self._count(walk, caller, callee, on_stack)
        self.entered.add(callee)
        return None

    def _end_of_import(self, frame: FrameType, event: str, arg: object) -> Callable | None:
        if event == "return":
            self.importing = None
        return self._end_of_import

    def _count(self, walk: CallWalk, caller: str | None, callee: str, on_stack: set[str]) -> None:
        walk.calls += 1
        to = layer_of(callee, self.layers)
        if to is None:
            walk.unlayered.add(callee)
        if caller is None or caller == callee:
            return
        if callee in self.entered and callee not in on_stack:
            walk.reentries.append((caller, callee))
        source = layer_of(caller, self.layers)
        if source is None or to is None or source[0] == to[0]:
            return
        if to[1] < source[1]:
            walk.climbs.append((caller, callee))
        elif to[1] == source[1]:
            walk.sideways.append((caller, callee))


def walk_calls(run: Callable[[], object], *, pyproject: Path, first: int = FIRST_CALLS) -> tuple[CallWalk, CallWalk]:
    """Run ``run`` under ``sys.settrace``; the walk of its first ``first`` calls into the
    twin and of the whole run."""
    recorder = _Recorder(layer_index(pyproject), first)
    previous = sys.gettrace()
    sys.settrace(recorder)
    try:
        run()
    finally:
        sys.settrace(previous)
    return recorder.opening, recorder.whole


def twin_pyproject() -> Path:
    """The pyproject.toml of the checkout the ``twin`` package is imported from."""
    import twin

    return Path(twin.__file__).resolve().parent.parent / "pyproject.toml"


def scenario_walk(
    scenario: str = SCENARIO, *, duration_s: float = DURATION_S, first: int = FIRST_CALLS
) -> tuple[CallWalk, CallWalk]:
    """The walk of ``twin.scenario.run_scenario`` on a bundled scenario cut to ``duration_s``
    (s): its first ``first`` calls into the twin and the whole run."""
    from twin.scenario import load_scenario, run_scenario

    scn = load_scenario(scenario, {"duration_s": duration_s})
    return walk_calls(lambda: run_scenario(scn, progress=False), pyproject=twin_pyproject(), first=first)


def _pairs(pairs: list[tuple[str, str]]) -> list[str]:
    counts: dict[tuple[str, str], int] = {}
    for pair in pairs:
        counts[pair] = counts.get(pair, 0) + 1
    return [f"    {n:5d} x {caller} -> {callee}" for (caller, callee), n in counts.items()]


def report(title: str, walk: CallWalk) -> str:
    """The walk as text: the counts, then each climb and sideways call with how often."""
    lines = [
        f"{title}: {walk.calls} calls, {len(walk.climbs)} climbs up a layer, "
        f"{len(walk.sideways)} sideways, {len(walk.reentries)} re-entries "
        f"into {len({callee for _, callee in walk.reentries})} modules"
    ]
    if walk.climbs:
        lines += ["  climbs (caller -> callee):", *_pairs(walk.climbs)]
    if walk.sideways:
        lines += ["  sideways:", *_pairs(walk.sideways)]
    if walk.unlayered:
        lines.append("  modules under no layer: " + ", ".join(sorted(walk.unlayered)))
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=SCENARIO)
    parser.add_argument("--duration", type=float, default=DURATION_S, help="simulated time, s")
    parser.add_argument("--first", type=int, default=FIRST_CALLS, help="calls in the opening walk")
    args = parser.parse_args()
    opening, whole = scenario_walk(args.scenario, duration_s=args.duration, first=args.first)
    print(f"{args.scenario} for {args.duration} s, layers of {twin_pyproject()}")
    print(report(f"first {args.first}", opening))
    print(report("whole run", whole))


if __name__ == "__main__":
    main()
