"""The numba kernels every control block runs on, in the compiled loop and in the Python loop.

A controller is compiled (:class:`controllers.blocks.program.Program`) into flat arrays:

- ``ops``, int64 (n_blocks, 8): per block ``kind, in_start, n_in, out_start, n_out, par_start,
  state_start, n_state`` (for :data:`SEQUENCE` the last column is the sequence length);
- ``io``, int64: bus indices of every block's inputs and outputs (``in_start``/``out_start``
  point into it);
- ``par``, float64: every block's parameters; ``state``, float64: every block's state;
- ``scratch``, float64: work space;
- ``bus``, float64: the signal bus (:mod:`controllers.blocks.signals`).

A block reads its inputs from the bus and writes its outputs to it.  Block kinds:

:data:`LINEAR`
    Discrete state space: ``y = C x + D v``, then ``x <- A x + B v`` (``par`` holds A, B, C, D
    row-major; ``n_state`` = order).
:data:`SUM`
    ``y = sum_j w_j v_j`` (``par`` holds the weights; one output).
:data:`STATIC`
    Elementwise static nonlinearity ``y_i = f(v_i)`` (``par``: code, then its parameters):
    :data:`NL_SATURATION` (limit L: ``clip(v, -L, L)``), :data:`NL_DEAD_ZONE` (width w:
    ``0`` for ``|v| <= w``, else ``v - w sign(v)``), :data:`NL_COSH_GAIN` (k, e_max:
    ``cosh(k clip(v, -e_max, e_max)) v``, seed 002's eqs. 7-8).
:data:`SEQUENCE`
    Plays a stored sequence: output row ``tick`` (the block's one input), zero after its end.
:data:`PYTHON`
    A Python object's ``step``; only the Python loop runs it.
"""

from __future__ import annotations

import math

from numba import njit

LINEAR, SUM, STATIC, SEQUENCE, PYTHON = 0, 1, 2, 3, 4
NL_SATURATION, NL_DEAD_ZONE, NL_COSH_GAIN = 0, 1, 2
#: Columns of ``ops``.
KIND, IN_START, N_IN, OUT_START, N_OUT, PAR_START, STATE_START, N_STATE = range(8)


@njit(cache=True)
def affine(P, Q, x, v, out):  # pragma: no cover - compiled
    """out = P x + Q v (in place), accumulated in that order."""
    for i in range(P.shape[0]):
        acc = 0.0
        for j in range(P.shape[1]):
            acc += P[i, j] * x[j]
        for j in range(Q.shape[1]):
            acc += Q[i, j] * v[j]
        out[i] = acc


@njit(cache=True)
def static_nonlinearity(code, p, v):  # pragma: no cover - compiled
    """One value through the static nonlinearity ``code`` with parameters ``p``."""
    if code == NL_SATURATION:
        return min(max(v, -p[0]), p[0])
    if code == NL_DEAD_ZONE:
        if abs(v) <= p[0]:
            return 0.0
        return v - p[0] if v > 0 else v + p[0]
    # NL_COSH_GAIN
    e = min(max(v, -p[1]), p[1])
    return math.cosh(p[0] * e) * v


@njit(cache=True)
def run_block(b, ops, io, par, state, scratch, bus):  # pragma: no cover - compiled
    """Run block ``b`` once: read its inputs from ``bus``, update its state, write its outputs."""
    kind = ops[b, KIND]
    i0, ni, o0, no = ops[b, IN_START], ops[b, N_IN], ops[b, OUT_START], ops[b, N_OUT]
    p0, s0, ns = ops[b, PAR_START], ops[b, STATE_START], ops[b, N_STATE]
    if kind == LINEAR:
        v = scratch[:ni]
        for j in range(ni):
            v[j] = bus[io[i0 + j]]
        x = state[s0:s0 + ns]
        a = p0 + ns * ns
        c = a + ns * ni
        d = c + no * ns
        y = scratch[ni:ni + no]
        xn = scratch[ni + no:ni + no + ns]
        affine(par[c:d].reshape((no, ns)), par[d:d + no * ni].reshape((no, ni)), x, v, y)
        affine(par[p0:a].reshape((ns, ns)), par[a:c].reshape((ns, ni)), x, v, xn)
        x[:] = xn
        for i in range(no):
            bus[io[o0 + i]] = y[i]
    elif kind == SUM:
        acc = 0.0
        for j in range(ni):
            acc += par[p0 + j] * bus[io[i0 + j]]
        bus[io[o0]] = acc
    elif kind == STATIC:
        code = int(par[p0])
        for j in range(ni):
            bus[io[o0 + j]] = static_nonlinearity(code, par[p0 + 1:], bus[io[i0 + j]])
    elif kind == SEQUENCE:
        k = int(bus[io[i0]])
        for i in range(no):
            bus[io[o0 + i]] = par[p0 + k * no + i] if k < ns else 0.0


@njit(cache=True)
def run_program(ops, io, par, state, scratch, bus):  # pragma: no cover - compiled
    """Run every block in order (compiled blocks only: no :data:`PYTHON` block)."""
    for b in range(ops.shape[0]):
        run_block(b, ops, io, par, state, scratch, bus)
