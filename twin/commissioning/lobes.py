"""Stability lobes of a scenario's tool (``twin lobes``), and its program's lines on them.

The tool is the scenario's first one with ``dynamics`` (``[tool]``, an entry of ``[[tools]]``,
or an ``end_milling`` disturbance), or the ``[[tools]]`` entry of ``tool_number``.  The cut:
its radial immersion (``a_e/D``; default the ``end_milling``'s, else a full slot) in up or down
milling (default the ``end_milling``'s, else down milling), feeding along the machine's X, with
the tool's material (a Kienzle material linearised at ``feed_per_tooth_mm``).  The lobes by the
zero-order solution and/or semi-discretization (:mod:`twin.machining.stability`) over the speeds
asked (default: a quarter of the scenario's lowest spindle speed to twice its highest, 200
speeds).  With a stock and a program, each cutting line checked
(:func:`twin.machining.program_stability.line_stability`) with its stable speeds searched over the
same range.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twin.disturbances.cutting_forces import EndMillingSpec
from twin.errors import TwinInputError
from twin.machining.cutting import immersion_angles
from twin.machining.materials import CuttingCoefficients
from twin.machining.program_stability import ProgramSamples, default_rpm_range, line_stability, milling_cut
from twin.machining.stability import Lobes, sd_critical_depths, zoa_critical_depths
from twin.machining.tool_dynamics import ToolDynamicsSpec
from twin.scenario import Scenario

#: The methods, and "both".
METHODS = ("zoa", "sd", "both")
#: Speeds of the lobes by default.
DEFAULT_SPEEDS = 200
#: Depths of the semi-discretization's grid.
SD_DEPTHS = 100


@dataclass(frozen=True)
class LobesSettings:
    """What ``twin lobes`` is asked: ``method`` (zoa, sd or both), ``rpm`` (low, high, count;
    None: the default range), ``depth_max_mm`` (the semi-discretization's deepest; None: ten
    times the zero-order lowest, at most 1.2 times its highest), ``immersion`` (``a_e/D`` in (0,
    1]; None: the scenario's), ``mode`` ("up", "down"; None: the scenario's), ``tool_number``
    (None: the first tool with dynamics) and ``feed_per_tooth_mm`` (a Kienzle material's chip)."""

    method: str = "both"
    rpm: tuple[float, float, int] | None = None
    depth_max_mm: float | None = None
    immersion: float | None = None
    mode: str | None = None
    tool_number: int | None = None
    feed_per_tooth_mm: float = 0.1


@dataclass(frozen=True)
class LobesTool:
    """The tool the lobes are of: where the scenario gives it, flutes, diameter (mm), material
    coefficients and dynamics, and the immersion and mode its ``end_milling`` gives (or None)."""

    label: str
    n_flutes: int
    diameter_mm: float
    material: str
    coefficients: CuttingCoefficients
    dynamics: ToolDynamicsSpec
    immersion: float | None = None
    mode: str | None = None
    spindle_rpm: float | None = None


def scenario_tool(scn: Scenario, number: int | None) -> LobesTool:
    """The tool of ``scn`` whose lobes are computed (module docstring).

    Raises
    ------
    TwinInputError
        No tool with dynamics, or no tool of that number (or it has none).
    """
    found: list[LobesTool] = []
    for label, tool in [("tool", scn.tool), *((f"tools.{i}", t) for i, t in enumerate(scn.tools))]:
        if tool is not None and tool.dynamics is not None and (number is None or tool.number == number):
            found.append(
                LobesTool(
                    label, tool.n_flutes, tool.diameter_mm, tool.material, tool.cutting_coefficients(), tool.dynamics
                )
            )
    for i, d in enumerate(scn.disturbances):
        if number is None and isinstance(d, EndMillingSpec) and d.dynamics is not None:
            found.append(
                LobesTool(
                    f"disturbances.{i}",
                    d.n_flutes,
                    d.diameter_mm,
                    d.material,
                    d.coefficients.applied_to(d.material),
                    d.dynamics,
                    min(1.0, d.radial_depth_mm / d.diameter_mm),
                    d.mode,
                    d.spindle_rpm,
                )
            )
    if not found:
        what = "no tool" if number is None else f"no tool T{number}"
        raise TwinInputError(
            "--tool" if number is not None else "tool.dynamics",
            number,
            f"{what} of the scenario has dynamics: give [tool.dynamics] (modes or frf_file), see docs/pages/chatter.md",
        )
    return found[0]


def _program_samples(scn: Scenario) -> tuple[ProgramSamples, dict[int, str]] | None:
    """With a stock and a program: what the planned program does at each sample through it
    (:meth:`twin.machining.program_cut.ProgramCut.samples`) and its lines' texts; else None."""
    if scn.stock is None or scn.reference.type != "gcode":
        return None
    from twin.scenario.assembly import assemble

    program = assemble(scn).program
    if program is None or program.cut is None or program.plan is None:
        return None
    return program.cut.samples(program.plan), program.plan.texts


def lobes(scn: Scenario, settings: LobesSettings) -> dict:
    """The lobes of the scenario's tool and its program's lines: what ``twin lobes --json``
    prints (``lobes`` per method a list of ``{spindle_rpm, critical_depth_mm, chatter_hz}``,
    their lowest, the seconds each took, the cut, and ``lines`` with each line's ``stability``).

    Raises
    ------
    TwinInputError
        A bad setting (named), no tool with dynamics, semi-discretization of a measured FRF.
    """
    if settings.method not in METHODS:
        raise TwinInputError("--method", settings.method, f"one of {', '.join(METHODS)}")
    tool = scenario_tool(scn, settings.tool_number)
    immersion = settings.immersion if settings.immersion is not None else tool.immersion or 1.0
    mode = settings.mode or tool.mode or "down"
    if not 0 < immersion <= 1:
        raise TwinInputError("--immersion", immersion, "the radial depth over the diameter, in (0, 1]")
    if not (math.isfinite(settings.feed_per_tooth_mm) and settings.feed_per_tooth_mm > 0):
        raise TwinInputError("--feed-per-tooth", settings.feed_per_tooth_mm, "must be positive (mm)")
    phi_st, phi_ex = immersion_angles(immersion * tool.diameter_mm, tool.diameter_mm, mode)
    cut = milling_cut(tool.coefficients, tool.n_flutes, ((phi_st, phi_ex, 1.0),), 0.0, settings.feed_per_tooth_mm)
    planned = _program_samples(scn)
    samples = None if planned is None else planned[0]
    speeds = _speeds(settings.rpm, tool, samples)
    methods = ["zoa", "sd"] if settings.method == "both" else [settings.method]
    if "sd" in methods and tool.dynamics.measured is not None:
        if settings.method == "sd":
            raise TwinInputError(f"{tool.label}.dynamics.frf_file", tool.dynamics.frf_file, "sd needs modes: use zoa")
        methods = ["zoa"]
    found: dict[str, Lobes] = {}
    seconds: dict[str, float] = {}
    start = time.perf_counter()
    zoa = zoa_critical_depths(cut, tool.dynamics, speeds)
    seconds["zoa"] = time.perf_counter() - start
    if "zoa" in methods:
        found["zoa"] = zoa
    depth_max_mm = settings.depth_max_mm
    if depth_max_mm is None:
        finite = zoa.critical_depth_m[np.isfinite(zoa.critical_depth_m)] * 1e3
        depth_max_mm = float(min(10 * finite.min(), 1.2 * finite.max())) if finite.size else 10.0
    if not (math.isfinite(depth_max_mm) and 0 < depth_max_mm <= 1e4):
        raise TwinInputError("--depth-max", depth_max_mm, "must be in (0, 10000] mm")
    if "sd" in methods:
        start = time.perf_counter()
        found["sd"] = sd_critical_depths(
            cut, tool.dynamics, spindle_rpm=speeds, depth_max_m=depth_max_mm * 1e-3, n_depths=SD_DEPTHS
        )
        seconds["sd"] = time.perf_counter() - start
    summary: dict = {
        "scenario": scn.name,
        "tool": tool.label,
        "n_flutes": tool.n_flutes,
        "diameter_mm": tool.diameter_mm,
        "material": tool.material,
        "K_t_N_per_mm2": round(cut.K_t * 1e-6, 3),
        "K_r": round(cut.K_r, 5),
        "immersion": immersion,
        "mode": mode,
        "engaged_deg": [round(math.degrees(phi_st), 3), round(math.degrees(phi_ex), 3)],
        "dynamics": "frf_file" if tool.dynamics.measured is not None else f"{len(tool.dynamics.modes)} mode(s)",
        "depth_max_mm": round(depth_max_mm, 4),
        "lobes": {name: result.records() for name, result in found.items()},
        "lowest": {name: _lowest(result) for name, result in found.items()},
        "seconds": {name: round(seconds[name], 3) for name in found},
    }
    if planned is not None:
        samples, texts = planned
        checked = line_stability(samples, (float(speeds.min()), float(speeds.max())))
        summary["lines"] = [
            {"line": n, "text": texts.get(n, ""), "stability": check.to_json()} for n, check in checked.items()
        ]
    return summary


def _speeds(rpm: tuple[float, float, int] | None, tool: LobesTool, samples) -> np.ndarray:
    """The speeds asked, or the default range (module docstring).

    Raises
    ------
    TwinInputError
        A bad range (named ``--rpm``).
    """
    if rpm is None:
        known = [tool.spindle_rpm] if tool.spindle_rpm is not None else []
        turning = samples.spindle_rpm if samples is not None else np.array(known, float)
        low, high = default_rpm_range(np.asarray(turning, float))
        return np.linspace(low, high, DEFAULT_SPEEDS)
    low, high, count = rpm
    if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high):
        raise TwinInputError("--rpm", f"{low:g}:{high:g}:{count}", "give MIN:MAX:N with 0 < MIN < MAX")
    if not 1 <= count <= 10_000:
        raise TwinInputError("--rpm", f"{low:g}:{high:g}:{count}", "N must be 1 to 10000 speeds")
    return np.linspace(low, high, count)


def _lowest(result: Lobes) -> dict | None:
    """The lowest critical depth of ``result`` and its speed (None: no boundary)."""
    depth = result.critical_depth_m
    if not np.isfinite(depth).any():
        return None
    i = int(np.nanargmin(depth))
    return {"spindle_rpm": round(float(result.spindle_rpm[i]), 3), "critical_depth_mm": round(float(depth[i]) * 1e3, 5)}


def write_lobes_png(summary: dict, path: str | Path) -> Path:
    """The lobes (critical depth against speed, per method), the program's lines on them
    (each at its depth and speed: green stable, red not, at its own engagement), and the
    chatter frequency beneath, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_d, ax_f) = plt.subplots(2, 1, figsize=(9, 7.5), sharex=True, height_ratios=(3, 1.4))
    styles = {"zoa": ("tab:blue", "zero-order (Altintas-Budak)"), "sd": ("k", "semi-discretization")}
    curves = []
    for name, rows in summary["lobes"].items():
        color, label = styles[name]
        rpm = np.array([r["spindle_rpm"] for r in rows])
        depth = np.array([np.nan if r["critical_depth_mm"] is None else r["critical_depth_mm"] for r in rows])
        hz = np.array([np.nan if r["chatter_hz"] is None else r["chatter_hz"] for r in rows])
        ax_d.plot(rpm, depth, color=color, lw=1.2, label=label)
        ax_f.plot(rpm, hz, ".", color=color, ms=2.5)
        curves.append(depth)
    lines = summary.get("lines", [])
    deepest = max([r["stability"]["depth_mm"] for r in lines], default=0.0)
    top = [r["critical_depth_mm"] for rows in summary["lobes"].values() for r in rows if r["critical_depth_mm"]]
    ceiling = max(min(max(top), 4 * min(top)) if top else 1.0, deepest) * 1.1
    with np.errstate(all="ignore"):
        lowest = np.nanmin(np.array(curves), axis=0) if curves else None
    if lowest is not None:  # above the lower of the methods' boundaries: chatter
        ax_d.fill_between(rpm, np.nan_to_num(lowest, nan=ceiling), ceiling, color="tab:red", alpha=0.08, lw=0)
    if lines:
        for ok, color, label in (
            (True, "tab:green", "program lines, stable"),
            (False, "tab:red", "program lines, chatter"),
        ):
            pts = [r["stability"] for r in lines if ((r["stability"]["margin"] or math.inf) >= 1) == ok]
            if pts:
                ax_d.plot(
                    [p["spindle_rpm"] for p in pts],
                    [p["depth_mm"] for p in pts],
                    "o",
                    color=color,
                    ms=5,
                    label=label,
                    alpha=0.8,
                )
        at: dict[tuple[float, float], list[int]] = {}  # lines at one point share a label
        for r in sorted(lines, key=lambda r: r["stability"]["margin"] or math.inf):
            at.setdefault((r["stability"]["spindle_rpm"], r["stability"]["depth_mm"]), []).append(r["line"])
        for (rpm_at, depth_at), numbers in list(at.items())[:6]:
            shown = ", ".join(str(n) for n in numbers[:4]) + (", ..." if len(numbers) > 4 else "")
            ax_d.annotate(
                f"line{'s' if len(numbers) > 1 else ''} {shown}",
                (rpm_at, depth_at),
                fontsize=8,
                xytext=(4, 4),
                textcoords="offset points",
            )
    ax_d.set_ylim(0, ceiling)
    ax_d.set_ylabel("critical axial depth (mm)")
    ax_d.legend(fontsize=8, loc="upper left")
    ax_f.set_ylabel("chatter (Hz)")
    ax_f.set_xlabel("spindle speed (rpm)")
    fig.suptitle(
        f"{summary['scenario']}: {summary['tool']}, {summary['n_flutes']} flutes, D {summary['diameter_mm']:g} mm, "
        f"{summary['material']}, a_e/D {summary['immersion']:g} {summary['mode']} milling (red: chatter)",
        fontsize=10,
    )
    for ax in (ax_d, ax_f):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
