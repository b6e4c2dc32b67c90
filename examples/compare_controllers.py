"""Compare two controllers on the same cut: Choi 1999's MIMO H-infinity controller and our PID.

    uv run python examples/compare_controllers.py [--duration 2.2]

Both run the bundled MIMO cutting circle (R 28 mm, 4800 mm/min, mechanistic milling force);
only the controller differs, set as a keyword argument with a dotted path as ``--set`` takes it.
"""

import argparse

import twin


def main(duration_s: float) -> dict:
    controllers = {
        "MIMO H-infinity (Choi 1999)": {"type": "choi1999_mimo"},
        "PID (ours, the MIMO loop's margins)": {"type": "choi1999_pid"},
        "PD with the MIMO's static gain": {
            "type": "choi1999_pid",
            "params": {"tuning": "mimo_diagonal", "ki_scale": 0.0},
        },
    }
    return {
        name: twin.run("choi1999_mimo_cutting", duration_s=duration_s, controller=controller).summary
        for name, controller in controllers.items()
    }


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.2, help="simulated time (s)")
    args = parser.parse_args()
    print(f"{'controller':<38} {'max tracking x / y (um)':>24} {'max contour (um)':>17}")
    for name, s in main(args.duration).items():
        e = s["max_tracking_error_um"]
        print(f"{name:<38} {e['x']:>11.1f} / {e['y']:<10.1f} {s['max_contour_error_um']:>17.1f}")
