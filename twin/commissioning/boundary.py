"""The twin's own stability boundary of a tuned cascade, by bisection, beside the margins the
design reports (:func:`twin.commissioning.tuning.cascade_margins`).

One gain of one axis (``kp_pos``, ``kp_vel``, or the integral gain ``ki_vel`` = kv / Ti) is
scaled by a factor in dB and the tuned scenario (``twin tune --out``'s, with a 1 mm step) runs
on the twin (MuJoCo) for :data:`DURATION_S`. The growth criterion: the peak-to-peak of that
axis's table position over the run's last quarter against the quarter before it (a constant
offset, such as the drive train's deflection under friction, drops out); a ratio above
:data:`GROWTH_RATIO` with the last quarter's peak-to-peak above :data:`GROWTH_FLOOR_M`, or a
run that diverges, is growth. Both bounds keep out the bounded limit cycles of the twin's
nonlinearities: the Coulomb friction's hunting (heavy_xy's X on the scale: about 0.6 µm
peak-to-peak at 85 Hz 2 dB below the boundary, its ratio 1.00) and the encoders' quantization's
(about 1.5 steps of the 10 nm scale, its ratio up to 1.0125). The factor is bisected between
one that decays and one that grows until they are :data:`RESOLUTION_DB` apart; the boundary is
where the ratio, interpolated linearly in its log between the two, crosses the threshold.

The cascade's margins assume a linear plant sampled exactly (zero-order hold). The twin
differs in three ways, each one an option here so that the comparison can be made like for like:
the guideways' Coulomb friction (MuJoCo's friction loss), the encoders' quantization and the
physics step (MuJoCo's Euler integrator, not an exact hold, whose error is of first order in
the step: :func:`zero_step_boundary`).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from typing import Any

import numpy as np

from twin.commissioning.tuning import scenario_text
from twin.errors import SimulationDiverged, TwinInputError
from twin.machines import get_machine
from twin.scenario import run_scenario, scenario_from_dict

#: The gains whose boundaries are bisected (the cascade's margins' keys).
GAINS = ("kp_pos", "kp_vel", "ki_vel")
#: Length of each run (s): the growth of the least damped mode shows over its last half.
DURATION_S = 0.5
#: The growth criterion's threshold: the last quarter's peak-to-peak over the quarter's before.
GROWTH_RATIO = 1.01
#: The growth criterion's floor (m): the last quarter's peak-to-peak, ten times the catalogue's
#: finest scale (a growing oscillation near the boundary is tens of µm there after a 1 mm step).
GROWTH_FLOOR_M = 1e-7
#: Width of the final bracket (dB).
RESOLUTION_DB = 0.1
#: The first bracket: the reported margin less and plus this much (dB), widened by as much
#: again (at most :data:`MAX_WIDENINGS` times) while it does not bracket the boundary.
BRACKET_DB = 1.0
MAX_WIDENINGS = 8


@dataclass(frozen=True)
class TwinConditions:
    """How the twin runs for a bisection.

    Attributes
    ----------
    coulomb : bool
        Keep the guideways' Coulomb friction (False: every axis's set to 0).
    timestep_divisor : int
        The machine's physics step divided by this (1: as the machine sets it).
    ideal_sensors : bool
        Encoders without quantization (the table's scale and the motor's).
    """

    coulomb: bool = True
    timestep_divisor: int = 1
    ideal_sensors: bool = False


#: The twin as a user runs it; without the Coulomb friction; linear (without the friction and
#: the quantization) at the machine's physics step and at a quarter of it.
AS_RUN = TwinConditions()
WITHOUT_COULOMB = TwinConditions(coulomb=False)
LINEAR = TwinConditions(coulomb=False, ideal_sensors=True)
LINEAR_QUARTER_STEP = TwinConditions(coulomb=False, timestep_divisor=4, ideal_sensors=True)
#: The conditions by name (``twin tune --verify-margins``'s columns).
CONDITIONS = {
    "twin": AS_RUN,
    "without_coulomb": WITHOUT_COULOMB,
    "linear": LINEAR,
    "linear_quarter_step": LINEAR_QUARTER_STEP,
}


@dataclass(frozen=True)
class Boundary:
    """The twin's bisected stability boundary of one gain (:func:`twin_boundary`).

    Attributes
    ----------
    boundary_db : float
        The interpolated crossing of the growth threshold (dB on the gain).
    decays_db, grows_db : float
        The final bracket (dB), at most :data:`RESOLUTION_DB` apart.
    runs : int
        The twin runs the bisection took.
    """

    boundary_db: float
    decays_db: float
    grows_db: float
    runs: int

    def to_json(self) -> dict[str, float | int]:
        """``boundary_db``, ``decays_db``, ``grows_db``, ``runs``."""
        return {
            "boundary_db": self.boundary_db,
            "decays_db": self.decays_db,
            "grows_db": self.grows_db,
            "runs": self.runs,
        }


@dataclass(frozen=True, kw_only=True)
class MarginCheck:
    """One axis's gain: its cascade margin beside the twin's bisected boundaries (:func:`verify_margins`).

    Attributes
    ----------
    machine : str or None
        The machine's name where a table of several names it (``examples/verify_margins.py``).
    axis, gain, feedback : str
    margin_db, margin_hz : float
        The reported cascade margin (dB) and its phase crossover (Hz).
    boundaries : dict of str to Boundary or None
        Per condition of :data:`CONDITIONS` checked, in order, the twin's boundary; None where the
        twin does not grow within :data:`MAX_WIDENINGS` dB of the margin.
    minus_margin_db : dict of str to float or None
        Per condition, the boundary less the margin (dB, to 3 decimals).
    zero_step_db, zero_step_minus_margin_db : float or None
        With ``linear`` and ``linear_quarter_step`` both found, the linear boundary extrapolated
        to a zero physics step (:func:`zero_step_boundary`) and it less the margin (dB).
    """

    machine: str | None = None
    axis: str
    gain: str
    feedback: str
    margin_db: float
    margin_hz: float
    boundaries: dict[str, Boundary | None]
    minus_margin_db: dict[str, float | None]
    zero_step_db: float | None = None
    zero_step_minus_margin_db: float | None = None

    def to_json(self) -> dict[str, Any]:
        """``machine`` (where named), ``axis``, ``gain``, ``feedback``, ``margin_db``,
        ``margin_hz``, per condition its boundary and ``<name>_minus_margin_db``, and where
        found ``zero_step_db`` and ``zero_step_minus_margin_db``."""
        out: dict[str, Any] = {} if self.machine is None else {"machine": self.machine}
        out |= {
            "axis": self.axis,
            "gain": self.gain,
            "feedback": self.feedback,
            "margin_db": self.margin_db,
            "margin_hz": self.margin_hz,
        }
        for name, found in self.boundaries.items():
            out[name] = None if found is None else found.to_json()
            out[f"{name}_minus_margin_db"] = self.minus_margin_db[name]
        if self.zero_step_db is not None:
            out["zero_step_db"] = self.zero_step_db
            out["zero_step_minus_margin_db"] = self.zero_step_minus_margin_db
        return out

    @classmethod
    def from_json(cls, row: dict[str, Any]) -> MarginCheck:
        """The check :meth:`to_json` gave (a committed table's row), every condition of
        :data:`CONDITIONS` in it."""
        return cls(
            machine=row.get("machine"),
            axis=row["axis"],
            gain=row["gain"],
            feedback=row["feedback"],
            margin_db=row["margin_db"],
            margin_hz=row["margin_hz"],
            boundaries={name: None if row[name] is None else Boundary(**row[name]) for name in CONDITIONS},
            minus_margin_db={name: row[f"{name}_minus_margin_db"] for name in CONDITIONS},
            zero_step_db=row.get("zero_step_db"),
            zero_step_minus_margin_db=row.get("zero_step_minus_margin_db"),
        )

    def _boundaries(self, number: str) -> list[str]:
        """Each condition's boundary beside the margin (:func:`_beside`, ``number`` its format)."""
        return [
            _beside(None if found is None else found.boundary_db, self.minus_margin_db[name], number)
            for name, found in self.boundaries.items()
        ]

    def report_line(self) -> str:
        """The check as ``twin tune --verify-margins`` prints it: the margin, each condition's
        boundary (less the margin) and the zero step's (``-``: not found)."""
        zero = "-" if self.zero_step_db is None else _beside(self.zero_step_db, self.zero_step_minus_margin_db, "6.2f")
        return f"{self.axis} {self.gain:<7} margin {self.margin_db:6.2f} dB: " + ", ".join(
            [*self._boundaries("6.2f"), zero]
        )

    def table_row(self) -> str:
        """The check as a row of :func:`margin_table` (Markdown)."""
        zero = "-" if self.zero_step_db is None else _beside(self.zero_step_db, self.zero_step_minus_margin_db, ".2f")
        return (
            f"| {self.machine} | {self.feedback} | {self.axis} | {self.gain} "
            f"| {self.margin_db:.2f} dB at {self.margin_hz:.0f} Hz |"
            + "".join(f" {cell} |" for cell in [*self._boundaries(".2f"), zero])
        )


def _beside(boundary_db: float | None, less_margin_db: float | None, number: str) -> str:
    """A boundary (dB, formatted as ``number``) with it less the cascade margin in brackets, or
    that the twin did not grow within :data:`MAX_WIDENINGS` dB (None)."""
    if boundary_db is None:
        return f"none within {MAX_WIDENINGS} dB"
    return f"{boundary_db:{number}} ({less_margin_db:+.2f})"


def _scaled(design: dict, axis: str, gain: str, db: float) -> dict:
    """A copy of ``design`` with ``axis``'s ``gain`` times 10^(db/20)."""
    factor = 10 ** (db / 20)
    axes = {a: {**r, "gains": dict(r["gains"])} for a, r in design["axes"].items()}
    gains = axes[axis]["gains"]
    if gain == "ki_vel":
        gains["ti_vel_s"] /= factor  # ki = kv / Ti
    else:
        gains[gain] *= factor
    return {**design, "axes": axes}


def growth_ratio(design: dict, machine: str, axis: str, gain: str, db: float, conditions: TwinConditions) -> float:
    """The peak-to-peak of ``axis``'s table position over the run's last quarter divided by the
    quarter's before it, with ``gain`` times 10^(db/20) (``inf`` where the run diverges, 0 where
    the last quarter's is below :data:`GROWTH_FLOOR_M`).

    Parameters
    ----------
    design : dict
        :func:`twin.commissioning.tuning.tune`'s result.
    machine : str
        The machine as the scenario names it (a bundled name or an absolute path).
    """
    changed = _scaled(design, axis, gain, db)
    if not conditions.coulomb:
        changed["overrides"] = {**changed["overrides"], **dict.fromkeys(get_machine(machine).coulomb_symbols(), 0.0)}
    scenario = tomllib.loads(scenario_text(changed, machine, "step"))
    scenario["duration_s"] = DURATION_S
    scenario["record_every_ticks"] = 1
    if conditions.timestep_divisor != 1:
        step = get_machine(machine).build(changed["overrides"]).model.opt.timestep
        scenario["timestep_s"] = step / conditions.timestep_divisor
    if conditions.ideal_sensors:
        scenario["sensors"].update(encoder_resolution_m=0.0, motor_encoder_resolution_m=0.0)
    try:
        result = run_scenario(scenario_from_dict(scenario)).run
    except SimulationDiverged:
        return math.inf
    y = result.table_position_m()[:, list(design["axes"]).index(axis)]
    n = len(y)
    earlier, last = y[n // 2 : 3 * n // 4], y[3 * n // 4 :]
    spread, final = float(np.ptp(earlier)), float(np.ptp(last))
    if final < GROWTH_FLOOR_M:
        return 0.0
    return math.inf if spread == 0.0 else final / spread


def twin_boundary(design: dict, machine: str, axis: str, gain: str, conditions: TwinConditions = AS_RUN) -> Boundary:
    """The factor (dB) on ``gain`` of ``axis`` at which the twin's tuned cascade starts to grow,
    bisected from the reported cascade margin (see the module docstring).

    Returns
    -------
    Boundary
        The interpolated crossing, the final bracket (at most :data:`RESOLUTION_DB` apart) and
        the runs it took.

    Raises
    ------
    TwinInputError
        Where the gain has no reported margin, or no bracket is found.
    """
    start = design["axes"][axis]["cascade_margins"][gain]["gain_margin_db"]
    if start is None:
        raise TwinInputError(gain, "inf", f"axis {axis} reports no cascade margin to check")
    ratios: dict[float, float] = {}

    def ratio(db: float) -> float:
        if db not in ratios:
            ratios[db] = growth_ratio(design, machine, axis, gain, db, conditions)
        return ratios[db]

    low, high = start - BRACKET_DB, start + BRACKET_DB
    for _ in range(MAX_WIDENINGS):
        if ratio(low) > GROWTH_RATIO:
            low, high = low - BRACKET_DB, low
        elif ratio(high) <= GROWTH_RATIO:
            low, high = high, high + BRACKET_DB
        else:
            break
    if not (ratio(low) <= GROWTH_RATIO < ratio(high)):
        raise TwinInputError(gain, start, f"no growth boundary within {MAX_WIDENINGS} dB of the margin on axis {axis}")
    while high - low > RESOLUTION_DB + 1e-9:
        middle = 0.5 * (low + high)
        if ratio(middle) > GROWTH_RATIO:
            high = middle
        else:
            low = middle
    at_low, at_high = (math.log(max(ratio(db), 1e-300) / GROWTH_RATIO) for db in (low, high))
    share = 0.5 if not math.isfinite(at_high) or at_high == at_low else -at_low / (at_high - at_low)
    return Boundary(
        boundary_db=round(low + share * (high - low), 3),
        decays_db=round(low, 4),
        grows_db=round(high, 4),
        runs=len(ratios),
    )


def zero_step_boundary(at_step_db: float, at_fine_step_db: float, divisor: int) -> float:
    """The boundary extrapolated to a physics step of zero (Richardson, first order: the Euler
    integrator's error), from the boundaries at the machine's step and at the step / ``divisor``
    (dB)."""
    return (divisor * at_fine_step_db - at_step_db) / (divisor - 1)


def verify_margins(
    design: dict,
    machine: str,
    gains: tuple[str, ...] = GAINS,
    conditions: dict[str, TwinConditions] | None = None,
) -> list[MarginCheck]:
    """Each axis's reported cascade margins beside the twin's bisected boundaries.

    Parameters
    ----------
    conditions : dict, optional
        Named :class:`TwinConditions` (default :data:`CONDITIONS`).

    Returns
    -------
    list of MarginCheck
        Per axis and gain with a finite margin, each condition's :func:`twin_boundary` (None
        where the twin does not grow within :data:`MAX_WIDENINGS` dB of the margin), and with
        ``linear`` and ``linear_quarter_step`` both found, the linear boundary extrapolated to a
        zero step (:func:`zero_step_boundary`).
    """
    conditions = conditions or CONDITIONS
    rows = []
    for axis, r in design["axes"].items():
        for gain in gains:
            margin = r["cascade_margins"][gain]
            margin_db = margin["gain_margin_db"]
            if margin_db is None:
                continue  # no crossing bounds it: nothing to bisect
            boundaries: dict[str, Boundary | None] = {}
            for name, condition in conditions.items():
                try:
                    boundaries[name] = twin_boundary(design, machine, axis, gain, condition)
                except TwinInputError:  # no growth within MAX_WIDENINGS dB of the margin
                    boundaries[name] = None
            linear, quarter = boundaries.get("linear"), boundaries.get("linear_quarter_step")
            zero = (
                None
                if linear is None or quarter is None
                else zero_step_boundary(linear.boundary_db, quarter.boundary_db, LINEAR_QUARTER_STEP.timestep_divisor)
            )
            rows.append(
                MarginCheck(
                    axis=axis,
                    gain=gain,
                    feedback=design["feedback"],
                    margin_db=margin_db,
                    margin_hz=margin["gain_margin_hz"],
                    boundaries=boundaries,
                    minus_margin_db={
                        name: None if found is None else round(found.boundary_db - margin_db, 3)
                        for name, found in boundaries.items()
                    },
                    zero_step_db=None if zero is None else round(zero, 3),
                    zero_step_minus_margin_db=None if zero is None else round(zero - margin_db, 3),
                )
            )
    return rows


def margin_table(rows: list[MarginCheck]) -> str:
    """:func:`verify_margins`'s rows (each with its ``machine``, every condition of
    :data:`CONDITIONS`) as a Markdown table: the cascade margin and each boundary with the
    boundary less the margin (dB)."""
    lines = [
        "| machine | feedback | axis | gain | cascade margin | twin | without Coulomb | linear "
        "| linear, 1/4 step | zero step |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    return "\n".join(lines + [row.table_row() for row in rows]) + "\n"
