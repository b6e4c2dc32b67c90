"""Virtual machining: the work materials and the tool's structure, the milling force models
and their compiled kernels (:mod:`.cutting`), the stock's height map and the program's
engagement along the planned path (:mod:`.engagement`), the program's cut with its warnings
(:mod:`.program_cut`, :mod:`.misuse`), the machined part (:mod:`.sweep`, :mod:`.part_map`,
:mod:`.part`) and its inspection (:mod:`.inspection`), and chatter: stability lobes per cut and
per program line, and the run's indicator (:mod:`.stability`, :mod:`.program_stability`,
:mod:`.chatter`).

The scenario's ``[[disturbances]]`` kinds built on these models are :mod:`twin.disturbances`.
"""
