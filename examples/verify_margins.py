"""The whole cascade's margins that ``twin tune`` reports beside the twin's own stability
boundaries, on every catalogue machine, axis and feedback.

    uv run python examples/verify_margins.py [--machines NAME ...] [--gains kp_vel ...] [--json]

Per machine (the machine files under examples/machines and the bundled machines) and feedback
(dual, motor, table; a machine without a motor's encoder: its own), ``twin.tune`` designs the
cascade and :meth:`twin.results.Tuning.verify_margins` bisects each gain on the twin to 0.1 dB
(a 1 mm step, 0.5 s; growth: the table's peak-to-peak over the last quarter against the quarter
before), three ways: the twin as run, without the guideways' Coulomb friction, and like for
like (no Coulomb friction, ideal encoders, a quarter of the physics step). Printed: a Markdown
table, each boundary less the reported margin (dB); ``--json`` prints the rows.
"""

import argparse
import json
from pathlib import Path

import twin
from twin.commissioning.boundary import margin_table
from twin.machines import build

FILES = Path(__file__).resolve().parent / "machines"
MACHINES = [
    *(str(FILES / f"{name}.toml") for name in ("compact_xy", "mid_size_xy", "heavy_xy", "sgm7j_xy", "sgm7j_axis")),
    str(FILES / "linear_motor_xy.toml"),
    "googol_xy",
    "cncmt_xy",
    "coupled_servo_xy",
]


def feedbacks(machine: str) -> list[str | None]:
    """The three feedbacks where an axis has a motor's encoder, else the machine's own (None)."""
    return ["dual", "motor", "table"] if any(a.motor_joint for a in build(machine).axes) else [None]


def main(machines: list[str], gains: tuple[str, ...]) -> list[dict]:
    rows = []
    for machine in machines:
        for feedback in feedbacks(machine):
            tuned = twin.tune(machine, feedback=feedback)
            checked = tuned.verify_margins(gains)
            rows += [{"machine": Path(machine).stem, **row} for row in checked]
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machines", nargs="*", default=MACHINES)
    parser.add_argument("--gains", nargs="*", default=["kp_pos", "kp_vel", "ki_vel"])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = main(args.machines, tuple(args.gains))
    print(json.dumps(result, indent=1) if args.json else margin_table(result))
