"""Sweep a machine's parameter box on Dask and read the samples back with pandas.

    uv run python examples/sweep_box.py [--samples 20] [--workers 2] [--out example_out]

The square on Sabau 2022's table (bundled ``square_sabau_pid``) with the identified gains K_x,
K_y drawn in their +-10 % box: the summary's worst case, and each sample's row as a DataFrame.
"""

import argparse
from pathlib import Path

import twin


def main(samples: int, workers: int, out: Path, duration_s: float = 0.5):
    out.mkdir(parents=True, exist_ok=True)
    return twin.sweep(
        "square_sabau_pid",
        ["overrides.K_x=box", "overrides.K_y=box"],
        samples=samples,
        workers=workers,
        out=out / "square_sabau_pid_sweep.parquet",
        duration_s=duration_s,
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("example_out"))
    args = parser.parse_args()
    sweep = main(args.samples, args.workers, args.out)
    frame = sweep.to_pandas()
    print(
        frame[["index", "overrides.K_x", "overrides.K_y", "status", "max_tracking_error_um_x"]].to_string(index=False)
    )
    print(f"{sweep.summary['ran']} samples in {sweep.summary['wall_s']:.1f} s; results in {sweep.out}")
