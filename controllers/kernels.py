"""The numba kernels every control block runs on, in the compiled loop and in the Python loop.

A controller is compiled (:class:`controllers.blocks.program.BlockProgram`) into flat arrays:

- ``ops``, int64 (n_blocks, 8): per block ``kind, in_start, n_in, out_start, n_out, par_start,
  state_start, n_state`` (for :data:`SEQUENCE` the last column is the sequence length);
- ``io``, int64: bus indices of every block's inputs and outputs (``in_start``/``out_start``
  point into it);
- ``par``, float64: every block's parameters; ``state``, float64: every block's state;
- ``scratch``, float64: work space;
- ``bus``, float64: the signal bus (:mod:`controllers.blocks.signals`).

:func:`run_blocks` runs a range of blocks: each reads its inputs from the bus and writes its
outputs to it.  Block kinds:

:data:`LINEAR`
    Discrete state space: ``y = C x + D v``, then ``x <- A x + B v`` (``par`` holds A, B, C, D
    row-major; ``n_state`` = order).
:data:`SUM`
    ``y = sum_j w_j v_j`` (``par`` holds the weights; one output).
:data:`STATIC`
    Elementwise static nonlinearity ``y_i = f(v_i)`` (``par``: code, then its parameters):
    :data:`NL_SATURATION` (limit L: ``clip(v, -L, L)``), :data:`NL_DEAD_ZONE` (width w:
    ``0`` for ``|v| <= w``, else ``v - w sign(v)``), :data:`NL_COSH_GAIN` (k, e_max:
    ``cosh(k clip(v, -e_max, e_max)) v``, Anang 2017's eqs. 7-8), :data:`NL_RELAY` (amplitude d:
    ``d`` for ``v >= 0``, else ``-d``; with ``u_prev`` fed back into ``v`` it is a relay with
    hysteresis, see :func:`controllers.blocks.compose.relay_feedback`).
:data:`SEQUENCE`
    Plays a stored sequence: output row ``tick`` (the block's one input), zero after its end.
:data:`PYTHON`
    A Python object's ``step``; only the Python loop runs it.
"""

from __future__ import annotations

import math

from numba import njit

LINEAR, SUM, STATIC, SEQUENCE, PYTHON = 0, 1, 2, 3, 4
NL_SATURATION, NL_DEAD_ZONE, NL_COSH_GAIN, NL_RELAY = 0, 1, 2, 3
#: Columns of ``ops``, one row per block: its kind, where its inputs and outputs lie in ``io``,
#: where its parameters and state start, and its state's length.
OP_COLUMNS = ("kind", "in_start", "n_in", "out_start", "n_out", "par_start", "state_start", "n_state")
KIND, IN_START, N_IN, OUT_START, N_OUT, PAR_START, STATE_START, N_STATE = (OP_COLUMNS.index(c) for c in OP_COLUMNS)


@njit(cache=True, inline="always")
def run_blocks(b0, b1, ops, io, par, state, scratch, bus):  # pragma: no cover - compiled
    """Run blocks ``b0 <= b < b1`` in order: read their inputs from ``bus``, update their
    state, write their outputs.  (Written as one flat function: in numba, helper calls on
    arrays cost reference counting on every tick.)"""
    for b in range(b0, b1):
        kind = ops[b, KIND]
        i0, ni, o0, no = ops[b, IN_START], ops[b, N_IN], ops[b, OUT_START], ops[b, N_OUT]
        p0, s0, ns = ops[b, PAR_START], ops[b, STATE_START], ops[b, N_STATE]
        if kind == LINEAR:
            # y = C x + D v, then x <- A x + B v, each accumulated in that order;
            # scratch: v at 0, y at ni, the next x at ni + no; A at p0, B at pb, C at pc, D at pd
            pb = p0 + ns * ns
            pc = pb + ns * ni
            pd = pc + no * ns
            for j in range(ni):
                scratch[j] = bus[io[i0 + j]]
            for i in range(no):
                acc = 0.0
                for j in range(ns):
                    acc += par[pc + i * ns + j] * state[s0 + j]
                for j in range(ni):
                    acc += par[pd + i * ni + j] * scratch[j]
                scratch[ni + i] = acc
            for i in range(ns):
                acc = 0.0
                for j in range(ns):
                    acc += par[p0 + i * ns + j] * state[s0 + j]
                for j in range(ni):
                    acc += par[pb + i * ni + j] * scratch[j]
                scratch[ni + no + i] = acc
            for i in range(ns):
                state[s0 + i] = scratch[ni + no + i]
            for i in range(no):
                bus[io[o0 + i]] = scratch[ni + i]
        elif kind == SUM:
            acc = 0.0
            for j in range(ni):
                acc += par[p0 + j] * bus[io[i0 + j]]
            bus[io[o0]] = acc
        elif kind == STATIC:
            code, p1, p2 = int(par[p0]), par[p0 + 1], par[p0 + 2]
            for j in range(ni):
                v = bus[io[i0 + j]]
                if code == NL_SATURATION:
                    y = min(max(v, -p1), p1)
                elif code == NL_DEAD_ZONE:
                    y = 0.0 if abs(v) <= p1 else (v - p1 if v > 0 else v + p1)
                elif code == NL_RELAY:
                    y = p1 if v >= 0.0 else -p1
                else:  # NL_COSH_GAIN: p1 = k, p2 = e_max
                    y = math.cosh(p1 * min(max(v, -p2), p2)) * v
                bus[io[o0 + j]] = y
        elif kind == SEQUENCE:
            k = int(bus[io[i0]])
            for i in range(no):
                bus[io[o0 + i]] = par[p0 + k * no + i] if k < ns else 0.0
