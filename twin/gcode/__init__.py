"""Part programs: the G-code reader (:mod:`.reader`, LinuxCNC's dialect), the path geometry
(:mod:`.path`), the look-ahead, jerk-limited interpolator (:mod:`.planner`) and what ``twin
gcode`` reports (:mod:`.report`).  The G-code reference kind is :mod:`twin.references.gcode`."""
