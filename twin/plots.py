"""Static report plots of a run (PNG, matplotlib): tracking errors, control inputs, forces and,
for two axes, the contour with the magnified error (+x right, +y up, equal scales)."""

from __future__ import annotations

from pathlib import Path

from twin.scales import contour_gain


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


def _axes_plot(plt, t, series: dict, ylabel: str, title: str, path: Path) -> Path:
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


def write_plots(result, directory: Path, name: str = "run") -> list[Path]:
    """Write ``<name>_tracking_error.png``, ``<name>_control.png``, ``<name>_forces.png`` and,
    for two axes, ``<name>_contour.png`` into ``directory`` (created if missing).

    Returns
    -------
    list of Path
        The files written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    machine, t = result.machine, result.t_s
    axes = result.axis_names
    error_um = result.error_m() * 1e6
    written = [
        _axes_plot(
            plt,
            t,
            {f"{a}": error_um[:, i] for i, a in enumerate(axes)},
            "reference - actual (µm)",
            f"{name}: tracking error",
            directory / f"{name}_tracking_error.png",
        ),
        _axes_plot(
            plt,
            t,
            {f"{a}": result.u_V[:, i] for i, a in enumerate(axes)},
            "control input (V)",
            f"{name}: control input",
            directory / f"{name}_control.png",
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
    return written
