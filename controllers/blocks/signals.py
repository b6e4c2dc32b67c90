"""Names of the signals on the bus that every block can read.

At each control tick the loop writes, for every machine axis ``<a>``:

======================  ==========================================================  ======
name                    what                                                         unit
======================  ==========================================================  ======
``ref.<a>``             reference position r[k]                                      m
``ref_vel.<a>``         reference velocity                                           m/s
``ref_acc.<a>``         reference acceleration                                       m/s^2
``pos.<a>``             encoder position y[k] (quantized, noisy)                     m
``vel.<a>``             velocity measurement: backward difference (y[k]-y[k-1])/T    m/s
                        of the encoder (default) or an ideal tachometer
``error.<a>``           ``ref.<a> - pos.<a>``                                        m
``u_prev.<a>``          the previous tick's command after saturation: what the       V
                        controller knows it applied (an input disturbance, unknown
                        to it, is not in it; 0 at k = 0)
``preview.<a>.<i>``     reference position i ticks ahead, r[k+i], i = 1..P           m
======================  ==========================================================  ======

and ``tick``, the tick index k.  Blocks add their own outputs to the bus; a controller's
outputs are ``u.<a>`` (V), one per axis it drives.  P is the largest ``i`` any block reads.
"""

from __future__ import annotations

#: Longest reference preview a block may read (ticks): bounds the bus and the sampled reference.
MAX_PREVIEW_TICKS = 10_000
#: Per-axis signals, in bus order: the one declaration of the bus layout (the loop's sensor
#: kernel, the recording and the transfer-function loop take their offsets from it).
AXIS_SIGNALS = ("ref", "ref_vel", "ref_acc", "pos", "vel", "error", "u_prev")
#: Offset of each per-axis signal within its axis's block of the bus.
OFFSET = {name: i for i, name in enumerate(AXIS_SIGNALS)}
#: Bus index of ``tick``; the axes' blocks follow it, then the previews.
TICK_INDEX = 0
FIRST_AXIS_INDEX = TICK_INDEX + 1


def standard_signals(axes, preview_ticks: int = 0) -> list[str]:
    """Bus layout of the loop's signals: ``tick``, then per axis :data:`AXIS_SIGNALS`, then
    per axis ``preview.<a>.1 .. preview.<a>.P``."""
    names = ["tick"]  # at TICK_INDEX
    for a in axes:
        names += [f"{s}.{a}" for s in AXIS_SIGNALS]
    for a in axes:
        names += [f"preview.{a}.{i}" for i in range(1, preview_ticks + 1)]
    return names


def preview_ticks_needed(signals) -> int:
    """Largest ``i`` of the ``preview.<a>.<i>`` names in ``signals`` (0 if none).

    Raises
    ------
    ValueError
        A preview name whose ``i`` is not a whole number in 1 .. :data:`MAX_PREVIEW_TICKS`.
    """
    most = 0
    for name in signals:
        parts = name.split(".")
        if parts[0] == "preview":
            if len(parts) != 3 or not parts[2].isdigit() or not 1 <= int(parts[2]) <= MAX_PREVIEW_TICKS:
                raise ValueError(
                    f"{name!r}: a preview signal is preview.<axis>.<ticks ahead, 1 to {MAX_PREVIEW_TICKS}>"
                )
            most = max(most, int(parts[2]))
    return most
