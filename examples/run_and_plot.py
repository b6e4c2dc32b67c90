"""Run a bundled scenario from Python and plot its tracking error with pandas and matplotlib.

    uv run python examples/run_and_plot.py [--duration 2.2] [--out example_out]

Choi 1999's cutting circle under the MIMO H-infinity controller; prints the summary (the same as
``twin run --json``) and writes ``run_and_plot.png``.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import twin


def main(duration_s: float, out: Path) -> dict:
    run = twin.run("choi1999_mimo_cutting", duration_s=duration_s)
    frame = run.to_pandas()  # indexed by time (s); columns "<series> (<unit>)"
    fig, ax = plt.subplots(figsize=(8, 4))
    frame[["error/x (µm)", "error/y (µm)"]].plot(ax=ax, linewidth=0.8)
    ax.set(xlabel="time (s)", ylabel="tracking error (µm)", title=f"{run.scenario.name}: tracking error")
    ax.grid(True, alpha=0.3)
    out.mkdir(parents=True, exist_ok=True)
    fig.savefig(out / "run_and_plot.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    return run.summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.2, help="simulated time (s)")
    parser.add_argument("--out", type=Path, default=Path("example_out"), help="folder for the plot")
    args = parser.parse_args()
    summary = main(args.duration, args.out)
    print(
        f"max contour error {summary['max_contour_error_um']:.1f} um, max tracking error x / y "
        f"{summary['max_tracking_error_um']['x']:.1f} / {summary['max_tracking_error_um']['y']:.1f} um; "
        f"plot in {args.out / 'run_and_plot.png'}"
    )
