"""Static report plots of a run (PNG, matplotlib): tracking errors, control inputs, forces, the
chatter indicator when milling and, for two axes, the contour with the magnified error (+x
right, +y up, equal scales)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from twin.machining.chatter import CHATTER_THRESHOLD, rolling_indicator
from twin.machining.part import MachinedPart
from twin.outcome import RunOutcome
from twin.scales import contour_gain
from twin.sim.runner import ProgramTrace


def plot_folder(folder):
    """``(plt, save, written)`` for a report's PNGs: matplotlib's pyplot on the Agg backend, and
    ``save(fig, name)`` that writes ``folder/name`` (folder created) at 120 dpi, closes the
    figure and appends the path to the list ``written``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []

    def save(fig, name):
        written.append(folder / name)
        fig.savefig(written[-1], dpi=120, bbox_inches="tight")
        plt.close(fig)

    return plt, save, written


def _axes_plot(plt, t, series: dict, *, ylabel: str, title: str, path: Path) -> Path:
    """One panel: a curve per name."""
    fig, ax = plt.subplots(figsize=(8, 3.5))
    for label, values in series.items():
        ax.plot(t, values, label=label, linewidth=1.0)
    ax.set(xlabel="time (s)", ylabel=ylabel, title=title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def write_plots(outcome: RunOutcome, directory: Path, name: str = "run") -> list[Path]:
    """Write ``<name>_tracking_error.png``, ``<name>_control.png``, ``<name>_forces.png``, with
    milling ``<name>_chatter.png`` and, for two axes, ``<name>_contour.png`` into ``directory``
    (created if missing); for a program, its part and feed plots (:func:`_program_plots`).

    Returns
    -------
    list of Path
        The files written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    result = outcome.run
    machine, t = result.machine, result.t_s
    axes = result.axis_names
    error_um = result.error_m() * 1e6
    written = [
        _axes_plot(
            plt,
            t,
            {f"{a}": error_um[:, i] for i, a in enumerate(axes)},
            ylabel="reference - actual (µm)",
            title=f"{name}: tracking error",
            path=directory / f"{name}_tracking_error.png",
        ),
        _axes_plot(
            plt,
            t,
            {f"{a}": result.u_V[:, i] for i, a in enumerate(axes)},
            ylabel="control input (V)",
            title=f"{name}: control input",
            path=directory / f"{name}_control.png",
        ),
    ]
    quantity, unit = machine.drive_quantity(machine.axes[0])
    panels = [
        (
            f"drive {quantity} ({unit})",
            {a.name: result.actuator_force[:, machine.model.actuator(a.actuator).id] for a in machine.axes},
        )
    ]
    if result.has_workpiece_force:
        panels.append(
            ("cutting force on the workpiece (N)", {a: result.workpiece_force_N[:, i] for i, a in enumerate(axes)})
        )
    fig, plot_axes = plt.subplots(len(panels), 1, figsize=(8, 3.2 * len(panels)), sharex=True, squeeze=False)
    for ax, (ylabel, series) in zip(plot_axes[:, 0], panels):
        for label, values in series.items():
            ax.plot(t, values, label=label, linewidth=1.0)
        ax.set(ylabel=ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best")
    plot_axes[0, 0].set_title(f"{name}: forces")
    plot_axes[-1, 0].set_xlabel("time (s)")
    written.append(directory / f"{name}_forces.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    if result.vibration_probe.any():  # milling: the chatter indicator against its threshold
        every = max(result.info.get("record_every", 1), 1)
        indicator = rolling_indicator(result.vibration_probe, result.control_period_s * every)
        written.append(
            _axes_plot(
                plt,
                t,
                {"indicator (20 ms)": indicator, "threshold": np.full(len(t), CHATTER_THRESHOLD)},
                ylabel="once-per-tooth vibration / feed per tooth (1)",
                title=f"{name}: chatter indicator",
                path=directory / f"{name}_chatter.png",
            )
        )
    if len(axes) == 2:
        gain = contour_gain(result)
        ref, act = result.ref[:, :, 0] * 1e3, result.table_position_m() * 1e3
        fig, ax = plt.subplots(figsize=(6.5, 6.5))
        ax.plot(ref[:, 0], ref[:, 1], color="0.6", linewidth=1.0, label="reference")
        ax.plot(act[:, 0], act[:, 1], color="tab:blue", linewidth=1.0, label="actual")
        magnified = ref + gain * (act - ref)
        ax.plot(magnified[:, 0], magnified[:, 1], color="tab:red", linewidth=1.0, label=f"error x{gain}")
        ax.plot(*act[0], "o", color="k", markersize=4, label="start")
        ax.set(xlabel=f"{axes[0]} (mm)", ylabel=f"{axes[1]} (mm)", title=f"{name}: contour, error x{gain}")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best")
        written.append(directory / f"{name}_contour.png")
        fig.savefig(written[-1], dpi=120, bbox_inches="tight")
        plt.close(fig)
    if result.program is not None and result.program.lines.size and len(axes) == 2:
        written += _program_plots(plt, outcome, program=result.program, directory=directory, name=name)
    return written


#: Lines of a program the part plot labels, worst first.
LABELLED_LINES = 5
#: Window (s) of the centred moving average the feed plot's actual feed is shown through (the
#: recording keeps the table's positions unfiltered).
FEED_FILTER_S = 0.01


def _program_plots(plt, outcome: RunOutcome, *, program: ProgramTrace, directory: Path, name: str) -> list[Path]:
    """A program's part seen from above (stock and machined outlines, the path coloured by its
    contour error, the worst lines labelled) and its feed profile (programmed, planned, actual)."""
    result = outcome.run
    from matplotlib.collections import LineCollection

    from twin.metrics import contour_error, line_table, run_contour_error

    ref, act = result.ref[:, :, 0] * 1e3, result.table_position_m() * 1e3
    ce = run_contour_error(result)  # the per-line table's own (None: a path that is not 2-D)
    error_um = (contour_error(act * 1e-3, ref * 1e-3) if ce is None else ce) * 1e6
    fig, ax = plt.subplots(figsize=(8, 7))
    for key, color, label in (("stock", "0.55", "stock"), ("machined", "k", "machined outline")):
        for i, ring in enumerate(outcome.outlines.get(key, [])):
            ax.plot(ring[:, 0], ring[:, 1], color=color, linewidth=1.0, label=label if i == 0 else None)
    segments = np.stack([act[:-1], act[1:]], axis=1)
    path = LineCollection(list(segments), array=error_um[1:], cmap="turbo", linewidths=2.0)
    ax.add_collection(path)
    fig.colorbar(path, ax=ax, label="contour error (µm)")
    rows = sorted(line_table(outcome, error_um * 1e-6), key=lambda r: r.worst_error_um, reverse=True)
    # numbered markers on the path and the lines' texts in a key beside the plot: passes that
    # share XY put the worst lines on one spot, where labels would cover one another
    legend_rows = []
    for rank, row in enumerate(rows[:LABELLED_LINES], start=1):
        inside = (result.t_s >= row.t_start_s) & (result.t_s < row.t_end_s)
        where = act[inside][np.argmax(error_um[inside])] if inside.any() else act[0]
        angle = 2.0 * np.pi * rank / LABELLED_LINES
        ax.annotate(
            str(rank),
            where,
            xytext=(14 * np.cos(angle), 14 * np.sin(angle)),
            textcoords="offset points",
            fontsize=8,
            ha="center",
            va="center",
            arrowprops={"arrowstyle": "-", "linewidth": 0.6},
            bbox={"boxstyle": "circle,pad=0.2", "fc": "white", "alpha": 0.9},
        )
        legend_rows.append(f"{rank}: line {row.line}, {row.worst_error_um:.1f} µm  {row.text[:40]}")
    if legend_rows:
        ax.text(
            1.28,
            1.0,
            "worst lines\n" + "\n".join(legend_rows),
            transform=ax.transAxes,
            fontsize=7,
            va="top",
            family="monospace",
        )
    ax.autoscale()
    ax.set(
        xlabel="x (mm)",
        ylabel="y (mm)",
        title=f"{name}: contour error along the path, the {LABELLED_LINES} worst lines",
    )
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    if outcome.outlines:
        ax.legend(loc="lower right", fontsize=8)
    written = [directory / f"{name}_part.png"]
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(9, 3.6))
    t = result.t_s
    planned = np.hypot(result.ref[:, 0, 1], result.ref[:, 1, 1]) * 60e3
    velocity = np.gradient(result.table_position_m(), t, axis=0) if len(t) > 1 else np.zeros_like(act)
    # the encoder's steps differentiated are noise over the feed (1 µm in 0.5 ms is 120 mm/min):
    # each axis's velocity averaged over FEED_FILTER_S, centred, before the magnitude
    width = max(1, round(FEED_FILTER_S / (t[1] - t[0]))) if len(t) > 1 else 1
    smooth = np.stack([np.convolve(v, np.ones(width) / width, mode="same") for v in velocity.T], axis=1)
    ax.plot(t, program.feed_mm_per_min, color="0.5", linewidth=1.2, label="programmed F (0: rapid)")
    ax.plot(t, planned, color="tab:blue", linewidth=1.0, label="planned (reference)")
    actual = np.hypot(smooth[:, 0], smooth[:, 1]) * 60e3
    ax.plot(
        t, actual, color="tab:red", linewidth=0.7, label=f"actual (table), {FEED_FILTER_S * 1e3:g} ms moving average"
    )
    top_feed = float(program.feed_mm_per_min.max())
    if top_feed > 0:  # the feeds in view; rapids run off the top
        ax.set_ylim(0.0, 1.3 * top_feed)
    ax.set(xlabel="time (s)", ylabel="XY feed (mm/min)", title=f"{name}: feed profile (rapids above the view)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    written.append(directory / f"{name}_feed.png")
    fig.savefig(written[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    if outcome.part is not None and len(outcome.part.walls):
        written.append(_wall_error_plot(plt, outcome, part=outcome.part, directory=directory, name=name))
    return written


def _wall_error_plot(plt, outcome: RunOutcome, *, part: MachinedPart, directory: Path, name: str) -> Path:
    """The virtual part from above: its walls coloured by their signed error (µm, material left
    red, overcut blue, one scale either side of zero), the inspected features' results beside."""
    walls = part.walls
    fig, ax = plt.subplots(figsize=(8, 7))
    for i, ring in enumerate(outcome.outlines.get("stock", [])):
        ax.plot(ring[:, 0], ring[:, 1], color="0.55", linewidth=1.0, label="stock" if i == 0 else None)
    order = np.argsort(np.abs(walls[:, 3]))  # the largest errors drawn last, on top
    limit = max(float(np.abs(walls[:, 3]).max()), 1e-3)
    dots = ax.scatter(
        walls[order, 0], walls[order, 1], c=walls[order, 3], s=8, cmap="coolwarm", vmin=-limit, vmax=limit
    )
    fig.colorbar(dots, ax=ax, label="wall error (µm): + material left, − overcut")
    report = [feature.label() for feature in outcome.inspection]
    if report:
        ax.text(
            1.28,
            1.0,
            "inspection\n" + "\n".join(report),
            transform=ax.transAxes,
            fontsize=7,
            va="top",
            family="monospace",
        )
    levels = ", ".join(f"{z:g}" for z in part.levels_mm)
    ax.set(xlabel="x (mm)", ylabel="y (mm)", title=f"{name}: the virtual part's walls at Z {levels} mm")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    path = directory / f"{name}_walls.png"
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path
