"""Compile controllers into the flat arrays of :mod:`controllers.kernels` on one signal bus."""

from __future__ import annotations

import numpy as np

from controllers import kernels
from controllers.blocks.signals import AXIS_SIGNALS


class SignalError(ValueError):
    """A block reads a signal nothing provides, or two blocks write the same signal.

    Attributes
    ----------
    block : str
        The block's name (``controller/block``).
    signal : str
    """

    def __init__(self, block: str, signal: str, reason: str):
        self.block, self.signal, self.reason = block, signal, reason
        super().__init__(f"block {block!r}, signal {signal!r}: {reason}")


class BlockProgram:
    """Controllers compiled onto one bus: the arrays the loops hand to the kernels.

    Parameters
    ----------
    controllers : sequence of Controller
        Run in order, each block in its order.
    loop_signals : list of str
        Signals the loop writes before the blocks run, in bus order
        (:func:`controllers.blocks.signals.standard_signals`).

    Raises
    ------
    SignalError
        A block reads a signal that neither the loop nor an earlier block writes, or writes
        one that already has a writer.

    Attributes
    ----------
    names : list of str
        Bus signal names; ``bus[i]`` holds ``names[i]``.
    ops, io, par, state, scratch, bus : ndarray
        See :mod:`controllers.kernels`.
    blocks : list
        The blocks in run order.
    """

    def __init__(self, controllers, loop_signals: list[str]):
        self.names = list(loop_signals)
        index = {s: i for i, s in enumerate(self.names)}
        self.blocks = []
        ops: list[list[int]] = []
        io: list[int] = []
        pars: list[np.ndarray] = []
        n_par, n_state, scratch = 0, 0, 0
        for ctrl in controllers:
            for b in ctrl.blocks:
                label = f"{ctrl.name}/{b.name}"
                ins = []
                for s in b.inputs:
                    if s not in index:
                        raise SignalError(
                            label,
                            s,
                            "no such signal: neither the loop nor an earlier "
                            f"block writes it (loop signals: {_summary(loop_signals)})",
                        )
                    ins.append(index[s])
                outs = []
                for s in b.outputs:
                    if s in index:
                        raise SignalError(label, s, "already written by the loop or an earlier block")
                    index[s] = len(self.names)
                    self.names.append(s)
                    outs.append(index[s])
                kind = getattr(b, "kind", kernels.PYTHON)
                p = b.params() if kind != kernels.PYTHON else np.zeros(0)
                length = len(b.values) if kind == kernels.SEQUENCE else getattr(b, "n_state", 0)
                row = {
                    "kind": kind,
                    "in_start": len(io),
                    "n_in": len(ins),
                    "out_start": len(io) + len(ins),
                    "n_out": len(outs),
                    "par_start": n_par,
                    "state_start": n_state,
                    "n_state": length,
                }
                ops.append([row[c] for c in kernels.OP_COLUMNS])
                io += ins + outs
                pars.append(p)
                n_par += len(p)
                n_state += b.n_state if kind == kernels.LINEAR else 0
                scratch = max(scratch, len(ins) + len(outs) + (b.n_state if kind == kernels.LINEAR else 0))
                self.blocks.append(b)
        self.ops = np.array(ops, np.int64).reshape(-1, len(kernels.OP_COLUMNS))
        self.io = np.array(io, np.int64)
        self.par = np.concatenate(pars) if pars else np.zeros(0)
        self.state = np.zeros(n_state)
        self.scratch = np.zeros(scratch)
        self.bus = np.zeros(len(self.names))
        self.compiled = all(k != kernels.PYTHON for k in self.ops[:, kernels.KIND])

    def index(self, signal: str) -> int:
        """Bus index of ``signal``."""
        return self.names.index(signal)

    def reset(self) -> None:
        """Zero every state and signal (and reset Python blocks)."""
        self.state[:] = 0.0
        self.bus[:] = 0.0
        for b in self.blocks:
            if not hasattr(b, "kind"):
                b.reset()

    def run(self) -> None:
        """One tick of every block on the current bus: the kernels, and Python blocks' ``step``."""
        if self.compiled:
            kernels.run_blocks(0, len(self.blocks), self.ops, self.io, self.par, self.state, self.scratch, self.bus)
            return
        for i, b in enumerate(self.blocks):
            if hasattr(b, "kind"):
                kernels.run_blocks(i, i + 1, self.ops, self.io, self.par, self.state, self.scratch, self.bus)
            else:
                row = self.ops[i]
                ins = self.io[row[kernels.IN_START] : row[kernels.IN_START] + row[kernels.N_IN]]
                outs = self.io[row[kernels.OUT_START] : row[kernels.OUT_START] + row[kernels.N_OUT]]
                self.bus[outs] = b.step(self.bus[ins].copy())


def _summary(names: list[str]) -> str:
    axes = sorted({s.split(".")[1] for s in names if "." in s})
    return f"tick, and per axis ({', '.join(axes)}): {', '.join(AXIS_SIGNALS)}, preview.<axis>.<i>"
