"""Commissioning a machine on the twin, as a drive's tools do it on the real one: measure an
axis's frequency response (:mod:`.frf`), fit the machine's parameters to measurements
(:mod:`.calibration`) and tune its cascade (:mod:`.tuning`)."""
