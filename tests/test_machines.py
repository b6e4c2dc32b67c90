"""Machines: parameters by source symbol, MjSpec overrides, reference models, open-loop match."""

import control
import mujoco
import numpy as np
import pytest

from twin.errors import TwinInputError
from twin.machines import MACHINES, build


def test_cncmt_tf_is_eq2_of_yadav2020():
    """Eq. (1) with Table 1 nominals and p = 0.05 gives eq. (2): 4.85/(s(s + 9.7))."""
    g = build("cncmt").plant[0][0]
    num, den = g.num, g.den
    assert num[-1] / den[0] == pytest.approx(4.85, rel=1e-3)
    assert den[1] / den[0] == pytest.approx(9.7, rel=1e-3)


def test_cncmt_xy_x_axis_carries_y_mass():
    bm = build("cncmt_xy")
    carried = bm.model.body_subtreemass[bm.model.body("x_table").id]
    assert carried == pytest.approx(50 + 50 + 3 + 6)  # X table + Y table/workpiece + Y rotor + Y screw
    gx, gy = bm.plant[0][0], bm.plant[1][1]
    assert abs(gx(1j)) < abs(gy(1j))


def test_override_applied_with_mjspec():
    bm = build("cncmt", {"m": 70.0, "Im": 0.012})
    assert bm.model.body_subtreemass[bm.model.body("x_table").id] == pytest.approx(70.0)
    J = 0.05**2 * 70 + 4 * 0.012
    g = bm.plant[0][0]
    assert g.den[0] == pytest.approx(J)


@pytest.mark.parametrize(
    "overrides, field",
    [({"mass": 3.0}, "overrides.mass"), ({"m": -5.0}, "overrides.m"), ({"Im": 1e-4}, "overrides.Im")],
)
def test_bad_overrides_name_the_field(overrides, field):
    with pytest.raises(TwinInputError) as err:
        build("cncmt", overrides)
    assert err.value.field == field


def test_unknown_machine():
    with pytest.raises(TwinInputError, match="unknown machine"):
        build("lathe")


@pytest.mark.parametrize("name", list(MACHINES))
def test_open_loop_step_matches_tf(name):
    """1 V on each input for 0.3 s: every table position equals the ZOH-exact TF response."""
    bm = build(name)
    m, d = bm.model, mujoco.MjData(bm.model)
    dt, n = m.opt.timestep, 3000
    g = control.c2d(control.ss(bm.plant_lti()), dt, "zoh")
    idx = [bm.joint_qpos_index(a.table_joint) for a in bm.axes]
    for k in range(m.nu):
        mujoco.mj_resetData(m, d)
        d.ctrl[k] = 1.0
        y = np.empty((n, m.nu))
        for i in range(n):
            y[i] = d.qpos[idx]
            mujoco.mj_step(m, d)
        u = np.zeros((m.nu, n))
        u[k] = 1.0
        yr = np.atleast_2d(control.forced_response(g, T=np.arange(n) * dt, U=u).outputs).T
        assert np.abs(y - yr).max() <= 2e-3 * np.abs(yr).max()


def test_sabau_cross_coupling_eq6():
    """u_x accelerates Y by 24.5 mm/s^2 per V and u_y accelerates X by 15 (eq. 6)."""
    bm = build("coupled_servo_xy")
    m, d = bm.model, mujoco.MjData(bm.model)
    d.ctrl[:] = [1.0, 0.0]
    mujoco.mj_forward(m, d)
    assert d.qacc[1] * 1e3 == pytest.approx(24.5, rel=1e-9)
    assert d.qacc[0] * 1e3 == pytest.approx(1054.0, rel=1e-9)
    d.ctrl[:] = [0.0, 1.0]
    mujoco.mj_forward(m, d)
    assert d.qacc[0] * 1e3 == pytest.approx(15.0, rel=1e-9)


def test_googol_realizes_identified_g_with_any_masses():
    """The drive is sized from the carried mass, so G does not depend on the assumed masses."""
    for overrides in ({}, {"m_workpiece": 20.0, "Jm": 5e-4}):
        bm = build("googol_xy", overrides)
        m, d = bm.model, mujoco.MjData(bm.model)
        d.ctrl[:] = [1.0, 1.0]
        mujoco.mj_forward(m, d)
        # initial table acceleration = b0 (m/s^2 per V): 78.02 from Anang 2017 eq. (1); the soft
        # gear constraints (impedance 0.9999) take about 1e-4 of it
        assert d.qacc[bm.joint_dof_index("x_table")] == pytest.approx(78.02, rel=5e-4)
        assert d.qacc[bm.joint_dof_index("y_table")] == pytest.approx(78.02, rel=5e-4)


@pytest.mark.parametrize(
    "name, overrides, field",
    [("coupled_servo_xy", {"m_y": 1.0}, "overrides.m_y"), ("linear_motor_xy", {"m_x": 10.0}, "overrides.m_x")],
)
def test_stacked_axes_mass_order(name, overrides, field):
    with pytest.raises(TwinInputError) as err:
        build(name, overrides)
    assert err.value.field == field
