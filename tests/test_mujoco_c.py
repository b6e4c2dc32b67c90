"""The one private attribute the twin uses: fails loudly if a MuJoCo upgrade changes it."""

import mujoco
import numpy as np

from twin.machines import build
from twin.sim import mujoco_c


def test_ctypes_mj_step_on_the_bindings_structs_equals_mujoco_mj_step():
    bm = build("googol_xy")
    a, b = mujoco.MjData(bm.model), mujoco.MjData(bm.model)
    for d in (a, b):
        d.ctrl[:] = [0.3, -0.2]
    assert mujoco_c.available()
    m_addr, d_addr = mujoco_c.struct_addresses(bm.model, a)
    for _ in range(50):
        mujoco_c.MJ_STEP(m_addr, d_addr)
        mujoco.mj_step(bm.model, b)
    assert a.time == b.time
    assert a.time > 0
    assert np.array_equal(a.qpos, b.qpos)
    assert np.array_equal(a.qvel, b.qvel)
    assert np.abs(a.qvel).max() > 0
