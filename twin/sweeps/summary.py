"""What a sweep found: bands of every metric, the worst case and its parameters, plots, and
the robustness certificates that cover the same box, printed beside the sampled evidence."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from twin.sampling import SamplePlan
from twin.sweeps.run import metric_columns

#: The metric the worst case is chosen by: the largest max tracking error over the axes.
WORST_BY = "max_tracking_error_um"


def _column(table, name: str) -> np.ndarray:
    """A numeric column of the sweep table as floats (NaN where missing)."""
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False), float)


def _worst_axis(table, axes) -> np.ndarray:
    """Per sample, the largest :data:`WORST_BY` over the axes."""
    return np.max([_column(table, f"{WORST_BY}_{a}") for a in axes], axis=0)


def summarize(table, plan: SamplePlan, axes) -> dict:
    """Counts by status, bands (min, 5 %, median, 95 %, max) of each metric over the ``ok``
    rows, and the worst sample by :data:`WORST_BY` (over the axes) with its values."""
    status = np.array(table.column("status").to_pylist())
    out: dict[str, Any] = {
        "samples": len(status),
        "planned": len(plan),
        "status": {s: int((status == s).sum()) for s in set(status)},
        "bands": {},
        "worst": None,
    }
    ok = status == "ok"
    for c in [c for c in metric_columns(axes, program=True) if c in table.column_names]:
        v = _column(table, c)[ok]
        if v.size and np.isfinite(v).any():
            q = np.nanpercentile(v, [0, 5, 50, 95, 100])
            out["bands"][c] = dict(zip(("min", "p5", "median", "p95", "max"), q.tolist()))
    if ok.any():
        worst = np.where(ok, _worst_axis(table, axes), -np.inf)
        i = int(np.argmax(worst))
        out["worst"] = {
            "by": WORST_BY,
            "value": float(worst[i]),
            "index": int(table.column("index")[i].as_py()),
            "seed": int(table.column("seed")[i].as_py()),
            "values": {v.path: table.column(v.path)[i].as_py() for v in plan.variations},
        }
    bad = [
        (table.column("index")[i].as_py(), status[i], table.column("error")[i].as_py()) for i in np.flatnonzero(~ok)[:5]
    ]
    out["first_failures"] = [{"index": int(i), "status": s, "error": e} for i, s, e in bad]
    return out


def certificates(machine: str, controller: str | None, plan: SamplePlan) -> list[dict]:
    """The robustness certificates of ``controller`` on ``machine`` over a box containing the
    sweep's, from every reproduction that offers one (:func:`twin.reproductions.certificates`):
    Yadav 2020's Kharitonov verdict over Table 1's box, Choi 1999's mu upper bounds.  Empty when
    none applies."""
    from twin.reproductions.registry import certificates as offered

    symbols = {v.path.removeprefix("overrides.") for v in plan.variations if v.path.startswith("overrides.")}
    others = [v.path for v in plan.variations if not v.path.startswith("overrides.")]
    return offered(machine, controller, symbols, others)


def format_summary(summary: dict, certs: list[dict], axes) -> str:
    """The printed summary: counts, bands, worst case, certificates."""
    counts = ", ".join(f"{k} {v}" for k, v in sorted(summary["status"].items()))
    out = [
        f"sweep: {summary['samples']} of {summary['planned']} samples ({counts})",
        "",
        f"  {'metric':<28} {'min':>10} {'5 %':>10} {'median':>10} {'95 %':>10} {'max':>10}",
    ]
    for c, b in summary["bands"].items():
        out.append(f"  {c:<28} " + " ".join(f"{b[k]:10.3f}" for k in ("min", "p5", "median", "p95", "max")))
    w = summary["worst"]
    if w:
        out += [
            "",
            f"  worst case ({w['by']}, largest axis): {w['value']:.3f} at sample {w['index']} "
            f"(seed {w['seed']}): "
            + ", ".join(f"{k} = {v:.6g}" if isinstance(v, float) else f"{k} = {v}" for k, v in w["values"].items()),
        ]
    for f in summary["first_failures"]:
        out.append(f"  sample {f['index']} {f['status']}: {f['error']}")
    if certs:
        out.append("")
        for c in certs:
            out.append(f"  certificate ({c['source']}):")
            out.append(
                "    "
                + ", ".join(
                    f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                    for k, v in c.items()
                    if k not in ("source", "note")
                )
            )
            out.append(f"    ({c['note']})")
    else:
        out += ["", "  no robustness certificate covers this machine, controller and box"]
    return "\n".join(out)


def write_sweep_plots(table, plan: SamplePlan, axes, folder) -> list:
    """Histograms of each metric and the worst-axis max tracking error against each varied
    parameter (``ok`` samples)."""
    from twin.plots import plot_folder

    plt, save, written = plot_folder(folder)
    ok = np.array(table.column("status").to_pylist()) == "ok"
    present = [c for c in metric_columns(axes, program=True) if c in table.column_names]
    columns = [c for c in present if np.isfinite(_column(table, c)[ok]).any()]
    n = len(columns)
    fig, grid = plt.subplots(
        math.ceil(n / len(axes)), len(axes), figsize=(5 * len(axes), 3 * math.ceil(n / len(axes))), squeeze=False
    )
    for ax, c in zip(grid.ravel(), columns):
        ax.hist(_column(table, c)[ok], bins=40)
        ax.set(xlabel=c.replace("_um", " (um)").replace("_N", " (N)"), ylabel="samples")
        ax.grid(alpha=0.3)
    fig.suptitle(f"sweep: {int(ok.sum())} ok samples")
    save(fig, "sweep_histograms.png")
    worst = _worst_axis(table, axes)[ok]
    numeric = [v for v in plan.variations if table.schema.field(v.path).type != "string"]
    if numeric:
        fig, grid = plt.subplots(1, len(numeric), figsize=(5 * len(numeric), 4), squeeze=False)
        for ax, v in zip(grid.ravel(), numeric):
            ax.scatter(_column(table, v.path)[ok], worst, s=6)
            ax.set(xlabel=v.path, ylabel="max tracking error, worst axis (um)")
            ax.tick_params(axis="x", labelrotation=30)
            ax.grid(alpha=0.3)
        save(fig, "sweep_metric_vs_parameters.png")
    return written
