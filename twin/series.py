"""The named time series of a run, in display units: what a recording shows and what
:meth:`twin.api.Run.to_pandas` returns, from one list.

Each :class:`Series` has a path (``reference/x``, ``error/x``, ``force/cutting/y``,
``joints/x/motor/angle``...), values at the recorded ticks in its unit, a legend name that
states the unit, and a colour and width for the plots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.machining.chatter import CHATTER_THRESHOLD, rolling_indicator

#: Per axis: (actual, reference) colours, RGB.  Actual strong, reference pale of the same hue.
AXIS_COLORS = {"x": ((31, 119, 180), (140, 190, 230)), "y": ((230, 85, 13), (250, 180, 120))}
OTHER_AXIS_COLORS = ((44, 160, 44), (160, 220, 150))


def axis_colors(axis: str):
    """(actual, reference) colours of an axis."""
    return AXIS_COLORS.get(axis, OTHER_AXIS_COLORS)


@dataclass(frozen=True)
class Series:
    """One named series of a run at its recorded ticks."""

    path: str
    values: np.ndarray
    name: str
    unit: str
    color: tuple[int, int, int]
    width: float = 1.5


def named_series(result, rows: slice = slice(None)) -> list[Series]:
    """Every series of a run (see the module docstring of :mod:`twin.recording`) at ``rows`` of
    its recorded ticks."""
    machine = result.machine
    pos = result.table_position_m()[rows]
    ref = result.ref[rows, :, 0]
    out = []
    for i, axis in enumerate(machine.axes):
        a = axis.name
        strong, pale = axis_colors(a)
        out += [
            Series(f"reference/{a}", ref[:, i] * 1e3, f"{a} reference", "mm", pale, 3.0),
            Series(f"actual/{a}", pos[:, i] * 1e3, f"{a} actual", "mm", strong),
            Series(f"error/{a}", (ref[:, i] - pos[:, i]) * 1e6, f"{a} error", "µm", strong),
            Series(f"control/{a}", result.u_V[rows, i], f"{a} control input", "V", strong),
        ]
        quantity, unit = machine.drive_quantity(axis)
        out.append(
            Series(
                f"{quantity}/drive/{a}",
                result.actuator_force[rows, machine.model.actuator(axis.actuator).id],
                f"{a} drive {quantity}",
                unit,
                strong,
            )
        )
        if result.has_workpiece_force:
            out.append(
                Series(
                    f"force/cutting/{a}",
                    result.workpiece_force_N[rows, i],
                    f"{a} cutting force on the workpiece",
                    "N",
                    strong,
                )
            )
        for part, joint, color in (("motor", axis.motor_joint, strong), ("screw", axis.screw_joint, pale)):
            if joint:
                out += [
                    Series(
                        f"joints/{a}/{part}/angle",
                        result.qpos[rows, machine.joint_qpos_index(joint)],
                        f"{a} {part} angle",
                        "rad",
                        color,
                    ),
                    Series(
                        f"joints/{a}/{part}/velocity",
                        result.qvel[rows, machine.joint_dof_index(joint)],
                        f"{a} {part} speed",
                        "rad/s",
                        color,
                    ),
                ]
        out.append(
            Series(
                f"joints/{a}/table/velocity",
                result.qvel[rows, machine.joint_dof_index(axis.table_joint)] * 1e3,
                f"{a} table velocity",
                "mm/s",
                strong,
            )
        )
    if result.vibration_probe.any():  # milling: the chatter indicator
        every = max(result.info.get("record_every", 1), 1)
        indicator = rolling_indicator(result.vibration_probe, result.control_period_s * every)[rows]
        out += [
            Series("chatter/indicator", indicator, "chatter indicator", "1", OTHER_AXIS_COLORS[0]),
            Series(
                "chatter/threshold",
                np.full(len(indicator), CHATTER_THRESHOLD),
                "chatter threshold",
                "1",
                OTHER_AXIS_COLORS[1],
                3.0,
            ),
        ]
    if result.program is None:
        return out
    engagement = result.program.engagement
    if engagement.size:  # a stock: how the tool meets the material
        out += [
            Series("engagement/angle", engagement[rows, 0], "engaged angle", "deg", OTHER_AXIS_COLORS[0]),
            Series("engagement/axial_depth", engagement[rows, 1], "axial depth", "mm", OTHER_AXIS_COLORS[1]),
        ]
    for name, values in result.program.extra_axes.items():  # planned axes the machine has not (G-code z)
        out.append(
            Series(f"reference/{name}", values[rows] * 1e3, f"{name} reference", "mm", OTHER_AXIS_COLORS[1], 3.0)
        )
    return out
