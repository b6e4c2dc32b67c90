"""The auto-tuned cascade against the papers' controllers, on the papers' machines and scenarios.

    uv run python examples/tune_vs_papers.py [--duration S]

For each paper scenario, `twin.tune` designs the cascade for the scenario's machine at the
scenario's control period (phase margin >= 45 deg, gain margin >= 6 dB on the sampled loop),
and the same scenario runs twice: with the paper's controller and with the tuned
`servo_cascade` on every axis. Printed: the tuned loops' bandwidth and margins, and both runs'
tracking (and, on a 2-D path, contour) errors.
"""

import argparse

import twin

#: (scenario, what the paper's controller is)
CASES = [
    ("choi1999_mimo_cutting", "Choi 1999 MIMO H-infinity + ZPETC"),
    ("choi1999_pid_cutting", "Choi 1999 PID + feedforward"),
    ("maharof2021_cascade", "Maharof 2021 cascade P/PI"),
    ("demo_circle_cncmt_xy", "Yadav 2020 robust PI"),
]


def main(duration_s: float | None) -> list[dict]:
    rows = []
    for scenario, paper in CASES:
        settings = {} if duration_s is None else {"duration_s": duration_s}
        base = twin.load(scenario, **settings)
        design = twin.tune(base.machine, dict(base.overrides), base.control_period_s).summary
        tuned = {a: {"type": "servo_cascade", "params": r["gains"]} for a, r in design["axes"].items()}
        ours = twin.run(scenario, controller=None, controllers=tuned, **settings).summary
        theirs = twin.run(scenario, **settings).summary
        rows.append({"scenario": scenario, "paper": paper, "design": design, "paper_run": theirs, "tuned_run": ours})
    return rows


def _errors(summary: dict) -> str:
    e = summary["max_tracking_error_um"]
    text = " / ".join(f"{v:.1f}" for v in e.values())
    return text + (f", contour {summary['max_contour_error_um']:.1f}" if "max_contour_error_um" in summary else "")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=None, help="simulated time (s); default each scenario's")
    args = parser.parse_args()
    for row in main(args.duration):
        x = next(iter(row["design"]["axes"].values()))
        print(f"{row['scenario']} ({row['design']['machine']}, {1e3 * row['design']['control_period_s']:g} ms):")
        print(
            f"  tuned: position bandwidth {x['bandwidth_hz']:.1f} Hz, PM {x['phase_margin_deg']:.1f} deg, "
            + ("GM infinite" if x["gain_margin_db"] is None else f"GM {x['gain_margin_db']:.1f} dB")
            + " (first axis)"
        )
        print(f"  max tracking error (um), {row['paper']:<34} {_errors(row['paper_run'])}")
        print(f"  max tracking error (um), {'tuned servo_cascade (ours)':<34} {_errors(row['tuned_run'])}")
