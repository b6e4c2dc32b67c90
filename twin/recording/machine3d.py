"""The machine in 3-D: every body's geoms from the compiled MJCF, the bodies' poses over time,
and the cutting force as an arrow at the tool tip.  Lengths in m, as in the model."""

from __future__ import annotations

import mujoco
import numpy as np
import rerun as rr

from twin.scales import round_up

#: Longest cutting-force arrow (m) the scale aims at, and its height above the tool tip (m).
ARROW_MAX_M, ARROW_LIFT_M = 0.1, 0.005


def _name(model, kind, i: int) -> str:
    return mujoco.mj_id2name(model, kind, i) or f"{'body' if kind == mujoco.mjtObj.mjOBJ_BODY else 'geom'}{i}"


def _xyzw(wxyz) -> np.ndarray:
    return np.asarray(wxyz)[..., [1, 2, 3, 0]]


def geom_shape(model, g: int):
    """The Rerun archetype of geom ``g`` in its own frame, or None for kinds not drawn."""
    size, color = model.geom_size[g], (model.geom_rgba[g] * 255).astype(np.uint8)
    if model.geom_matid[g] >= 0:
        color = (model.mat_rgba[model.geom_matid[g]] * 255).astype(np.uint8)
    kind = model.geom_type[g]
    solid = rr.components.FillMode.Solid
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return rr.Boxes3D(half_sizes=[size], colors=[color], fill_mode=solid)
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return rr.Cylinders3D(lengths=[2 * size[1]], radii=[size[0]], colors=[color], fill_mode=solid)
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return rr.Capsules3D(
            lengths=[2 * size[1]], radii=[size[0]], translations=[[0.0, 0.0, -size[1]]], colors=[color]
        )
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return rr.Ellipsoids3D(half_sizes=[[size[0]] * 3], colors=[color], fill_mode=solid)
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return rr.Ellipsoids3D(half_sizes=[size], colors=[color], fill_mode=solid)
    if kind == mujoco.mjtGeom.mjGEOM_PLANE and size[0] > 0 and size[1] > 0:
        return rr.Boxes3D(half_sizes=[[size[0], size[1], 1e-4]], colors=[color], fill_mode=solid)
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        m = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[m], model.mesh_vertnum[m]
        f0, nf = model.mesh_faceadr[m], model.mesh_facenum[m]
        return rr.Mesh3D(
            vertex_positions=model.mesh_vert[v0 : v0 + nv],
            triangle_indices=model.mesh_face[f0 : f0 + nf],
            albedo_factor=color,
        )
    return None


def log_geometry(rec, model, prefix: str) -> None:
    """Every drawable geom, once, under ``<prefix>machine/<body>/<geom>`` (its pose in the body)."""
    rec.log(f"{prefix}machine", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for g in range(model.ngeom):
        shape = geom_shape(model, g)
        if shape is None:
            continue
        b = model.geom_bodyid[g]
        path = (
            f"{prefix}machine/{_name(model, mujoco.mjtObj.mjOBJ_BODY, b)}/{_name(model, mujoco.mjtObj.mjOBJ_GEOM, g)}"
        )
        rec.log(
            path,
            rr.Transform3D(translation=model.geom_pos[g], quaternion=rr.Quaternion(xyzw=_xyzw(model.geom_quat[g]))),
            static=True,
        )
        rec.log(path, shape, static=True)


def body_poses(model, qpos: np.ndarray):
    """World positions (m) and orientations (quaternions w, x, y, z) of every body at each row of
    ``qpos``, by MuJoCo's forward kinematics: arrays (n, nbody, 3) and (n, nbody, 4)."""
    data = mujoco.MjData(model)
    xpos = np.empty((len(qpos), model.nbody, 3))
    xquat = np.empty((len(qpos), model.nbody, 4))
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        xpos[k], xquat[k] = data.xpos, data.xquat
    return xpos, xquat


def log_poses(rec, model, *, t, qpos, prefix: str) -> None:
    """Each body's pose: over time for bodies that move, once for those welded to the world."""
    xpos, xquat = body_poses(model, qpos)
    for b in range(1, model.nbody):
        path = f"{prefix}machine/{_name(model, mujoco.mjtObj.mjOBJ_BODY, b)}"
        if model.body_weldid[b] == 0:
            rec.log(
                path,
                rr.Transform3D(translation=xpos[0, b], quaternion=rr.Quaternion(xyzw=_xyzw(xquat[0, b]))),
                static=True,
            )
        else:
            rec.send_columns(
                path,
                indexes=[rr.TimeColumn("sim_time", duration=t)],
                columns=rr.Transform3D.columns(translation=xpos[:, b], quaternion=_xyzw(xquat[:, b])),
            )


def arrow_scale_N_per_mm(force_N: np.ndarray) -> float:
    """Round number of N per mm of arrow that draws the largest force at most
    :data:`ARROW_MAX_M` long."""
    return round_up(max(float(np.abs(force_N).max()), 1e-9) / (ARROW_MAX_M * 1e3))


def log_cutting_force(rec, model, *, t, force_N, n_per_mm: float, prefix: str) -> None:
    """The force on the workpiece (N, world frame) as an arrow from the tool tip (site
    ``tool_tip``, else the workpiece), ``n_per_mm`` N per mm of arrow.  The arrow starts
    :data:`ARROW_LIFT_M` above the tip, where the workpiece's top face does not hide it."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tool_tip")
    tip = (data.site_xpos[site] if site >= 0 else data.xpos[model.body("workpiece").id]) + [0.0, 0.0, ARROW_LIFT_M]
    path = f"{prefix}machine/cutting_force"
    rec.log(path, rr.Arrows3D.from_fields(colors=[(230, 30, 30)], radii=[0.002]), static=True)
    rec.send_columns(
        path,
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Arrows3D.columns(vectors=force_N * 1e-3 / n_per_mm, origins=np.broadcast_to(tip, force_N.shape)),
    )
