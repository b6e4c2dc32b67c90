"""The one place the twin reaches below MuJoCo's Python API: ``mj_step`` called from numba.

The compiled loop (:mod:`twin.sim.loop`) calls MuJoCo's C function ``mj_step(const mjModel*,
mjData*)`` through ctypes from the ``libmujoco`` shared library the bindings themselves load,
on the bindings' own ``MjModel`` and ``MjData``.  The bindings document no public way to get
the C struct addresses, so :func:`struct_addresses` reads their ``_address`` attribute: the
only private attribute the twin uses.  ``tests/test_mujoco_c.py`` checks that a ctypes step
equals ``mujoco.mj_step`` bit for bit, so a MuJoCo upgrade that changes either fails loudly
there.  Everything else (arrays, warnings, flags) goes through the documented bindings.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import mujoco


def _load_mj_step():
    """``mj_step`` from the libmujoco the bindings use, or None where it is not found."""
    folder = Path(mujoco.__file__).parent
    libs = sorted(folder.glob("libmujoco.so*")) + sorted(folder.glob("libmujoco*.dylib"))
    if not libs:
        return None
    fn = ctypes.CDLL(str(libs[0])).mj_step
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    fn.restype = None
    return fn


#: ctypes ``mj_step``; passed to the numba loop as an argument so numba can cache the loop.
MJ_STEP = _load_mj_step()


def available() -> bool:
    """Whether MuJoCo's shared library was found (the compiled loop can run)."""
    return MJ_STEP is not None


def struct_addresses(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[int, int]:
    """C addresses of the ``mjModel`` and ``mjData`` behind the bindings' objects.

    Raises
    ------
    RuntimeError
        If the bindings no longer expose them (a MuJoCo upgrade): the compiled loop then needs
        a new route, and the Python loop still runs.
    """
    try:
        return int(model._address), int(data._address)
    except AttributeError:
        raise RuntimeError(
            f"mujoco {mujoco.__version__}: MjModel/MjData have no _address; twin.sim.mujoco_c needs updating"
        ) from None
