"""The largest feed override that keeps the contour error under a limit on the bundled part,
over the machine's parameter box: a sweep of the G-code test piece on Dask.

    uv run python examples/feed_override.py [--limit-um 10] [--overrides 0.6 0.8 1.0 1.2 1.4]
        [--workers 2] [--out example_out]

``gcode_test_piece`` (the 2.5-D part cut from its stock on ``linear_motor_xy``) at each feed
override, at every vertex of the carriages' mass box (Choi 1999 Table 1's m_x and m_y, the
``corners`` spec): for each override the worst vertex's max and RMS contour error on the feed
moves (the rapids, which the override does not slow, left out), and the largest override whose
worst case stays under the limit, for either metric.
"""

import argparse
from pathlib import Path

import twin


def main(overrides: list[float], workers: int, out: Path, duration_s: float | None = None):
    """The sweep (one sample per override and vertex) and its rows as a DataFrame."""
    out.mkdir(parents=True, exist_ok=True)
    low, high = min(overrides), max(overrides)
    grid = f"grid({low},{high},{len(overrides)})" if len(overrides) > 1 else f"choice({low})"
    settings = {} if duration_s is None else {"duration_s": duration_s}
    sweep = twin.sweep(
        "gcode_test_piece",
        [f"planner.feed_override={grid}", "overrides.m_x=corners", "overrides.m_y=corners"],
        samples=1,
        workers=workers,
        out=out / "gcode_feed_override.parquet",
        **settings,
    )
    return sweep, sweep.to_pandas()


def answer(frame, limit_um: float) -> dict:
    """Per override the worst vertex's contour errors on the feed moves, and the largest override
    under the limit for the max and for the RMS contour error (None where none is)."""
    ok = frame[frame["status"] == "ok"]
    worst = ok.groupby("planner.feed_override")[["max_contour_error_feed_um", "rms_contour_error_feed_um"]].max()
    best = {}
    for metric in worst.columns:
        passing = worst.index[worst[metric] < limit_um]
        best[metric] = float(passing.max()) if len(passing) else None
    return {"worst": worst, "largest_override": best}


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limit-um", type=float, default=10.0)
    parser.add_argument("--overrides", type=float, nargs="+", default=[0.6, 0.8, 1.0, 1.2, 1.4])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("example_out"))
    parser.add_argument("--duration", type=float, default=None, help="cut the runs short (a quick look)")
    args = parser.parse_args()
    sweep, frame = main(args.overrides, args.workers, args.out, args.duration)
    result = answer(frame, args.limit_um)
    print(f"worst case over the m_x, m_y box corners ({sweep.summary['ran']} runs), µm:")
    print(result["worst"].round(2).to_string())
    for metric, value in result["largest_override"].items():
        verdict = f"{value:g}" if value is not None else f"none of {sorted(set(args.overrides))}"
        print(f"largest feed override with {metric} < {args.limit_um:g} µm: {verdict}")
