"""What a sweep varies and the samples it draws: ``PATH=SPEC`` variations over a scenario.

Specs (``PATH`` is a scenario field as for ``twin run --set``; ``overrides.<symbol>`` names a
machine parameter):

- ``box``: uniform over the machine's documented uncertainty box of that symbol;
- ``uniform(a, b)``, ``normal(mu, sigma)``, ``choice(v1, v2, ...)``: random draws;
- ``grid(a, b, n)``: n equally spaced values; ``corners``: the two ends of the symbol's box;
- ``line(n)``: Yadav 2020's "samples between the lower and upper limit via nominal": every
  ``line`` symbol moves together from its box's lower to its upper end in n steps.

Structured specs (grid, corners, line) are combined as a full product; random specs are drawn
``samples`` times for each structured combination.  Sample ``i`` draws its random values and
its scenario seed from ``numpy.random.SeedSequence([sweep_seed, i])`` alone, so a sample is the
same whatever the number of workers or the order they run in; with ``latin_hypercube`` the
uniform numbers of every random spec come instead from one Latin hypercube design of all the
sweep's random samples (``scipy.stats.qmc``, seeded), also fixed per index.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from twin.errors import TwinInputError

RANDOM_KINDS = ("box", "uniform", "normal", "choice")
STRUCTURED_KINDS = ("grid", "corners", "line")
#: Most samples one sweep may hold (the plan and the file stay bounded).
MAX_SAMPLES = 1_000_000
_SPEC = re.compile(r"^\s*([a-z_]+)\s*(?:\((.*)\))?\s*$")


@dataclass(frozen=True)
class Variation:
    """One varied field: ``path``, ``kind`` (a spec name) and its arguments ``args``
    (numbers, or the values of a ``choice``); ``box`` is the (lower, upper) range that box,
    corners and line use (the machine's)."""

    path: str
    kind: str
    args: tuple = ()
    box: tuple[float, float] | None = None

    @property
    def random(self) -> bool:
        return self.kind in RANDOM_KINDS

    @property
    def range(self) -> tuple[float, float]:
        """``box`` of the specs that need it (box, corners, line)."""
        if self.box is None:
            raise ValueError(f"{self.path}: {self.kind} needs the parameter's box")
        return self.box

    def levels(self) -> list:
        """The values of a structured spec, in order."""
        if self.kind == "grid":
            a, b, n = self.args
            return np.linspace(a, b, int(n)).tolist()
        if self.kind == "corners":
            return list(self.range)
        raise ValueError(f"{self.kind} has no levels")

    def from_unit(self, u: float):
        """The random value whose cumulative probability is ``u`` (0 <= u < 1)."""
        if self.kind == "box":
            lo, hi = self.range
            return lo + u * (hi - lo)
        if self.kind == "uniform":
            a, b = self.args
            return a + u * (b - a)
        if self.kind == "normal":
            from scipy.special import ndtri

            mu, sigma = self.args
            return mu + sigma * float(ndtri(min(max(u, 1e-12), 1 - 1e-12)))
        return self.args[min(int(u * len(self.args)), len(self.args) - 1)]


def _number(text: str, field_: str, spec: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise TwinInputError(field_, spec, f"{text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise TwinInputError(field_, spec, "arguments must be finite")
    return value


def parse_variation(text: str, parameters: dict) -> Variation:
    """A ``PATH=SPEC`` string as a :class:`Variation`, checked against the machine's
    ``parameters`` (name -> :class:`~twin.machines.base.Parameter`).

    Raises
    ------
    TwinInputError
        Malformed text, an unknown spec, wrong arguments, or box/corners/line on a path that is
        not a machine symbol with a documented box.
    """
    path, sep, spec = text.partition("=")
    path = path.strip()
    field_ = f"--vary {path}" if path else "--vary"
    match = _SPEC.match(spec)
    if not sep or not path or not match:
        raise TwinInputError(
            "--vary", text, "use PATH=SPEC, e.g. overrides.m_x=box or disturbances.0.spindle_rpm=uniform(5000,12000)"
        )
    kind, inner = match.group(1), match.group(2)
    args = [a.strip() for a in inner.split(",")] if inner not in (None, "") else []
    if kind not in RANDOM_KINDS + STRUCTURED_KINDS:
        raise TwinInputError(field_, spec, f"unknown spec (use {', '.join(RANDOM_KINDS + STRUCTURED_KINDS)})")
    want = {"box": 0, "corners": 0, "uniform": 2, "normal": 2, "grid": 3, "line": 1}
    if kind in want and len(args) != want[kind]:
        raise TwinInputError(field_, spec, f"{kind} takes {want[kind]} argument(s)")
    box = None
    if kind in ("box", "corners", "line"):
        symbol = path.removeprefix("overrides.")
        if not path.startswith("overrides.") or symbol not in parameters:
            raise TwinInputError(
                field_,
                spec,
                f"{kind} needs a machine parameter, overrides.<symbol> (this machine's: {', '.join(parameters)})",
            )
        box = parameters[symbol].box
        if box is None:
            boxed = [k for k, p in parameters.items() if p.box is not None]
            raise TwinInputError(
                field_, spec, f"the machine documents no box for {symbol} (boxed: {', '.join(boxed) or 'none'})"
            )
        box = (float(box[0]), float(box[1]))
    if kind == "choice":
        if not args:
            raise TwinInputError(field_, spec, "choice needs at least one value")
        values: list[float | str] = []
        for a in args:
            try:
                values.append(float(a))
            except ValueError:
                values.append(a.strip("'\""))
        return Variation(path, kind, tuple(values))
    numbers = tuple(_number(a, field_, spec) for a in args)
    if kind == "uniform" and not numbers[0] < numbers[1]:
        raise TwinInputError(field_, spec, "uniform(a, b) needs a < b")
    if kind == "normal" and not numbers[1] > 0:
        raise TwinInputError(field_, spec, "normal(mu, sigma) needs sigma > 0")
    if kind == "grid" and not (numbers[2] == int(numbers[2]) and 2 <= numbers[2] <= 10_000):
        raise TwinInputError(field_, spec, "grid(a, b, n) needs a whole n from 2 to 10000")
    if kind == "line" and not (numbers[0] == int(numbers[0]) and 2 <= numbers[0] <= 10_000):
        raise TwinInputError(field_, spec, "line(n) needs a whole n from 2 to 10000")
    return Variation(path, kind, numbers, box)


@dataclass
class SamplePlan:
    """The samples of a sweep: ``variations``, ``samples`` random draws per structured
    combination, the sweep ``seed`` and the ``latin_hypercube`` option."""

    variations: list[Variation]
    samples: int
    seed: int = 0
    latin_hypercube: bool = False
    _unit: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        if not self.variations:
            raise TwinInputError("--vary", None, "give at least one PATH=SPEC")
        paths = [v.path for v in self.variations]
        if len(set(paths)) != len(paths):
            raise TwinInputError("--vary", sorted(p for p in paths if paths.count(p) > 1)[0], "varied twice")
        if not (isinstance(self.samples, int) and 1 <= self.samples <= MAX_SAMPLES):
            raise TwinInputError("--samples", self.samples, f"must be a whole number from 1 to {MAX_SAMPLES}")
        if not (isinstance(self.seed, int) and self.seed >= 0):
            raise TwinInputError("seed", self.seed, "must be a whole number >= 0")
        self.random = [v for v in self.variations if v.random]
        self.line = [v for v in self.variations if v.kind == "line"]
        self.axes = [v for v in self.variations if v.kind in ("grid", "corners")]
        self.levels = [v.levels() for v in self.axes]
        counts = [len(lv) for lv in self.levels] + ([int(self.line[0].args[0])] if self.line else [])
        if len({int(v.args[0]) for v in self.line}) > 1:
            raise TwinInputError("--vary", [v.path for v in self.line], "line(n) symbols move together: give one n")
        self.structured = math.prod(counts) if counts else 1
        self.counts = counts
        self.draws = self.samples if self.random else 1
        if self.structured * self.draws > MAX_SAMPLES:
            raise TwinInputError(
                "--samples", self.structured * self.draws, f"the sweep would hold more than {MAX_SAMPLES} samples"
            )
        if self.latin_hypercube and self.random:
            from scipy.stats import qmc

            self._unit = qmc.LatinHypercube(d=len(self.random), seed=self.seed).random(len(self))

    def __len__(self) -> int:
        return self.structured * self.draws

    def sample_seed(self, index: int) -> int:
        """The scenario seed of sample ``index`` (sensor noise, spindle phase, ...)."""
        return int(np.random.SeedSequence([self.seed, index]).generate_state(1)[0])

    def values(self, index: int) -> dict:
        """``path -> value`` of sample ``index`` (0 <= index < len(self))."""
        if not 0 <= index < len(self):
            raise IndexError(index)
        combo = index // self.draws
        out = {}
        if self.counts:
            position = np.unravel_index(combo, self.counts)
            for v, levels, k in zip(self.axes, self.levels, position):
                out[v.path] = levels[k]
            if self.line:
                t = position[-1] / (self.counts[-1] - 1)
                for v in self.line:
                    lo, hi = v.range
                    out[v.path] = lo + t * (hi - lo)
        if self.random:
            u = (
                self._unit[index]
                if self._unit is not None
                else np.random.default_rng(np.random.SeedSequence([self.seed, index, 1])).random(len(self.random))
            )
            for v, ui in zip(self.random, u):
                out[v.path] = v.from_unit(float(ui))
        return {v.path: out[v.path] for v in self.variations}
