"""Part programs: the G-code reader (:mod:`.reader`, LinuxCNC's dialect, built of the
``interp_*`` modules by topic as LinuxCNC's ``interp_*.cc``; :mod:`.modal` LinuxCNC's names for
its numbers; :mod:`.moves` what it reads a program into), the path geometry
(:mod:`.path`), the look-ahead, jerk-limited interpolator (:mod:`.planner`) and what ``twin
gcode`` reports (:mod:`.report`).  The G-code reference kind is :mod:`twin.references.gcode`."""
