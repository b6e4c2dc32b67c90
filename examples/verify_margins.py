"""The whole cascade's margins that ``twin tune`` reports beside the twin's own stability
boundaries, on every catalogue machine, axis and feedback.

    uv run python examples/verify_margins.py [--machines NAME ...] [--gains kp_vel ...] [--json]

Per machine (the catalogue's machine files under examples/machines and the Googol table; the
rigid papers' axes, linear_motor_xy, cncmt_xy, coupled_servo_xy, tune to crossings at 1-2 kHz
that need a finer physics step than these conditions take: see docs/pages/your_machine.md) and
feedback
(dual, motor, table, less those that tune the same loops; a machine without a motor's encoder:
its own), ``twin.tune`` designs the
cascade and :meth:`twin.results.Tuning.verify_margins` bisects each gain on the twin to 0.1 dB
(a 1 mm step, 0.5 s; growth: the table's peak-to-peak over the last quarter 1 % above the
quarter's before), four ways: the twin as run, without the guideways' Coulomb friction, linear
(no Coulomb friction, ideal encoders) at the machine's physics step and at a quarter of it;
and from the last two the linear boundary extrapolated to a zero step. Printed: a Markdown
table, each boundary and, in brackets, less the reported margin (dB); ``--json`` prints the
rows (``tests/fixtures/margins/verify_margins.json`` is that output).
"""

import argparse
import json
from dataclasses import replace
from pathlib import Path

import twin
from twin.commissioning.boundary import MarginCheck, margin_table
from twin.machines import build

FILES = Path(__file__).resolve().parent / "machines"
MACHINES = [
    *(str(FILES / f"{name}.toml") for name in ("compact_xy", "mid_size_xy", "heavy_xy", "sgm7j_xy", "sgm7j_axis")),
    "googol_xy",
]


def feedbacks(machine: str) -> list[str | None]:
    """The three feedbacks where an axis has a motor's encoder, else the machine's own (None)."""
    return ["dual", "motor", "table"] if any(a.motor_joint for a in build(machine).axes) else [None]


def main(machines: list[str], gains: tuple[str, ...]) -> list[MarginCheck]:
    rows = []
    for machine in machines:
        designs: list[dict] = []
        for feedback in feedbacks(machine):
            tuned = twin.tune(machine, feedback=feedback)
            gains_of = {a: r["gains"] for a, r in tuned.summary["axes"].items()}
            if gains_of in designs:
                continue  # the same loops as a feedback before (one transfer function per axis)
            designs.append(gains_of)
            checked = tuned.verify_margins(gains)
            rows += [replace(row, machine=Path(machine).stem) for row in checked]
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machines", nargs="*", default=MACHINES)
    parser.add_argument("--gains", nargs="*", default=["kp_pos", "kp_vel", "ki_vel"])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = main(args.machines, tuple(args.gains))
    print(json.dumps([row.to_json() for row in result], indent=1) if args.json else margin_table(result))
