"""Maharof (2021), thesis front matter: the loops its cascade P/PI was shaped for, and
that design done here on the machine's model.

Only margins survive in the text (Figs. 4.3 and 4.7): velocity open loop GM 9.37 dB at 194 Hz,
PM 56.4 deg at 96.4 Hz; position open loop GM 9.1 dB at 123 Hz, PM 67.1 deg at 31.4 Hz.  The
gains are not given, so :func:`design_cascade` computes them from the plant with
:mod:`controllers.design.cascade`: a velocity PI meeting both velocity margins on
``s G(s) e^(-sT)`` times the velocity measurement (the encoder's backward difference), and a
position P meeting the position phase margin around the closed velocity loop (one gain cannot
also set the 9.1 dB: it comes out near 10.9 dB).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

VELOCITY_GM_DB, VELOCITY_GM_HZ, VELOCITY_PM_DEG, VELOCITY_PM_HZ = 9.37, 194.0, 56.4, 96.4
POSITION_GM_DB, POSITION_GM_HZ, POSITION_PM_DEG, POSITION_PM_HZ = 9.1, 123.0, 67.1, 31.4
#: Harmonics of the thesis's input disturbances (Hz), one, two and three at a time.
HARMONICS_HZ = (0.2, 0.5, 0.8)


@lru_cache(maxsize=16)
def design_cascade(plant, delay_s: float, dt: float) -> dict:
    """Gains (SI) and achieved margins of the cascade on ``plant`` (m/V, a SisoTf) with the drive
    delay (s), velocity measured by backward difference at ``dt`` (s).

    Returns
    -------
    dict
        ``kp_pos`` (1/s), ``kp_vel`` (V s/m), ``ki_vel`` (V/m), and ``velocity`` / ``position``
        :class:`~controllers.design.loop_analysis.LoopMargins`.  Cached per (plant, delay, dt):
        treat it as read-only.
    """
    from controllers.design.cascade import (
        backward_difference,
        closed_loop,
        gain_for_phase_margin,
        pi_for_margins,
        pi_loop,
    )

    measure = backward_difference(dt)

    def velocity_plant(w):
        w = np.asarray(w, float)
        return 1j * w * plant(1j * w) * np.exp(-1j * w * delay_s) * measure(w)

    # a guess from the plant's high-frequency gain: |kp s G| = 1 near 100 Hz
    w0 = 2 * np.pi * VELOCITY_PM_HZ
    kp0 = 1.0 / abs(velocity_plant(np.array([w0]))[0])
    kp, ki, velocity = pi_for_margins(velocity_plant, VELOCITY_GM_DB, VELOCITY_PM_DEG, guess=(kp0, 100.0 * kp0))

    def position_plant(w):
        w = np.asarray(w, float)
        through = closed_loop(pi_loop(kp, ki, velocity_plant))(w) / measure(w)  # true velocity per reference
        return through / (1j * w)

    k, position = gain_for_phase_margin(position_plant, POSITION_PM_DEG, 1.0, 1e4)
    return {"kp_pos": k, "kp_vel": kp, "ki_vel": ki, "velocity": velocity, "position": position}
