"""Named time series of a run: what each is, in its unit, with a legend name and colour."""

from __future__ import annotations

import numpy as np
import rerun as rr

#: Per axis: (actual, reference) colours, RGB.  Actual strong, reference pale of the same hue.
AXIS_COLORS = {"x": ((31, 119, 180), (140, 190, 230)), "y": ((230, 85, 13), (250, 180, 120))}
OTHER_AXIS_COLORS = ((44, 160, 44), (160, 220, 150))


def axis_colors(axis: str):
    """(actual, reference) colours of an axis."""
    return AXIS_COLORS.get(axis, OTHER_AXIS_COLORS)


def _series(rec, path: str, t, values, name: str, color, width: float = 1.5) -> None:
    rec.log(path, rr.SeriesLines(names=name, colors=color, widths=width), static=True)
    rec.send_columns(path, indexes=[rr.TimeColumn("sim_time", duration=t)],
                     columns=rr.Scalars.columns(scalars=np.ascontiguousarray(values, float)))


def log_series(rec, result, prefix: str, rows: slice) -> None:
    """Every series of the module docstring of :mod:`twin.recording` at the recorded ``rows``."""
    machine = result.machine
    t = result.t_s[rows]
    pos = result.table_position_m()[rows]
    ref = result.ref[rows, :, 0]
    for i, axis in enumerate(machine.axes):
        a = axis.name
        strong, pale = axis_colors(a)
        _series(rec, f"{prefix}reference/{a}", t, ref[:, i] * 1e3, f"{a} reference (mm)", pale, 3.0)
        _series(rec, f"{prefix}actual/{a}", t, pos[:, i] * 1e3, f"{a} actual (mm)", strong, 1.5)
        _series(rec, f"{prefix}error/{a}", t, (ref[:, i] - pos[:, i]) * 1e6, f"{a} error (µm)", strong)
        _series(rec, f"{prefix}control/{a}", t, result.u_V[rows, i], f"{a} control input (V)", strong)
        quantity, unit = machine.drive_quantity(axis)
        _series(rec, f"{prefix}{quantity}/drive/{a}", t,
                result.actuator_force[rows, machine.model.actuator(axis.actuator).id],
                f"{a} drive {quantity} ({unit})", strong)
        if result.has_workpiece_force:
            _series(rec, f"{prefix}force/cutting/{a}", t, result.workpiece_force_N[rows, i],
                    f"{a} cutting force on the workpiece (N)", strong)
        joints = f"{prefix}joints/{a}"
        for part, joint, color in (("motor", axis.motor_joint, strong), ("screw", axis.screw_joint, pale)):
            if joint:
                _series(rec, f"{joints}/{part}/angle", t, result.qpos[rows, machine.joint_qpos_index(joint)],
                        f"{a} {part} angle (rad)", color)
                _series(rec, f"{joints}/{part}/velocity", t, result.qvel[rows, machine.joint_dof_index(joint)],
                        f"{a} {part} speed (rad/s)", color)
        _series(rec, f"{joints}/table/velocity", t, result.qvel[rows, machine.joint_dof_index(axis.table_joint)] * 1e3,
                f"{a} table velocity (mm/s)", strong)
