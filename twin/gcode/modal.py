"""LinuxCNC's names for the numbers its interpreter works with: the G modal groups
(``ModalGroups`` of ``interp_internal.hh``), the G codes as ten times their number (``GCodes``
there: ``G_61_1`` is 611), the M modal groups and the numbered parameters the twin reads or
sets (LinuxCNC's G-code overview, "Modal Groups" and "Numbered Parameters").

A block's codes are kept by group (``g_modes[ModalGroup.CONTROL_MODE]``), as LinuxCNC's
``block->g_modes[GM_CONTROL_MODE]``; the parameters are numbered as in LinuxCNC's ``#5161``, an
axis's one the first (X) plus the axis index (x 0, y 1, z 2).
"""

from __future__ import annotations

from enum import IntEnum


class ModalGroup(IntEnum):
    """The G modal groups: LinuxCNC's ``GM_*`` (``GM_MOTION`` is ``MOTION``); 9 and 11 are
    unused."""

    MODAL_0 = 0
    MOTION = 1
    SET_PLANE = 2
    DISTANCE_MODE = 3
    IJK_DISTANCE_MODE = 4
    FEED_MODE = 5
    LENGTH_UNITS = 6
    CUTTER_COMP = 7
    TOOL_LENGTH_OFFSET = 8
    RETRACT_MODE = 10
    COORD_SYSTEM = 12
    CONTROL_MODE = 13
    SPINDLE_MODE = 14
    LATHE_DIAMETER_MODE = 15
    G92_IS_APPLIED = 16


class MGroup(IntEnum):
    """The M modal groups (LinuxCNC's ``m_modes`` indices, named as its documentation's table)."""

    STOPPING = 4
    IO = 5
    TOOL_CHANGE = 6
    SPINDLE = 7
    COOLANT = 8
    OVERRIDES = 9
    USER_DEFINED = 10


class GCode(IntEnum):
    """The G codes, ten times their number: LinuxCNC's ``GCodes`` (``G_59_3`` is 593)."""

    G_0 = 0
    G_1 = 10
    G_2 = 20
    G_3 = 30
    G_4 = 40
    G_5 = 50
    G_5_1 = 51
    G_5_2 = 52
    G_5_3 = 53
    G_6 = 60
    G_6_1 = 61
    G_6_2 = 62
    G_6_3 = 63
    G_7 = 70
    G_8 = 80
    G_10 = 100
    G_17 = 170
    G_17_1 = 171
    G_18 = 180
    G_18_1 = 181
    G_19 = 190
    G_19_1 = 191
    G_20 = 200
    G_21 = 210
    G_28 = 280
    G_28_1 = 281
    G_30 = 300
    G_30_1 = 301
    G_33 = 330
    G_33_1 = 331
    G_38_2 = 382
    G_38_3 = 383
    G_38_4 = 384
    G_38_5 = 385
    G_40 = 400
    G_41 = 410
    G_41_1 = 411
    G_42 = 420
    G_42_1 = 421
    G_43 = 430
    G_43_1 = 431
    G_43_2 = 432
    G_49 = 490
    G_52 = 520
    G_53 = 530
    G_54 = 540
    G_55 = 550
    G_56 = 560
    G_57 = 570
    G_58 = 580
    G_59 = 590
    G_59_1 = 591
    G_59_2 = 592
    G_59_3 = 593
    G_61 = 610
    G_61_1 = 611
    G_64 = 640
    G_70 = 700
    G_71 = 710
    G_71_1 = 711
    G_71_2 = 712
    G_72 = 720
    G_72_1 = 721
    G_72_2 = 722
    G_73 = 730
    G_74 = 740
    G_76 = 760
    G_80 = 800
    G_81 = 810
    G_82 = 820
    G_83 = 830
    G_84 = 840
    G_85 = 850
    G_86 = 860
    G_87 = 870
    G_88 = 880
    G_89 = 890
    G_90 = 900
    G_90_1 = 901
    G_91 = 910
    G_91_1 = 911
    G_92 = 920
    G_92_1 = 921
    G_92_2 = 922
    G_92_3 = 923
    G_93 = 930
    G_94 = 940
    G_95 = 950
    G_96 = 960
    G_97 = 970
    G_98 = 980
    G_99 = 990


class Param(IntEnum):
    """The numbered parameters the twin reads or sets; an axis's parameter is the X one plus
    the axis index (LinuxCNC's G-code overview, "Numbered Parameters")."""

    #: ``#5161``-``#5163``: G28's home, X, Y, Z (user units, machine coordinates).
    G28_HOME = 5161
    #: ``#5181``-``#5183``: G30's home.
    G30_HOME = 5181
    #: ``#5210``: 1 while a G52 / G92 offset is applied, else 0.
    AXIS_OFFSET_APPLIED = 5210
    #: ``#5211``-``#5213``: the G52 / G92 offset shared by both, X, Y, Z.
    AXIS_OFFSET = 5211
    #: ``#5220``: the coordinate system in force, 1-9 (G54-G59.3).
    COORD_SYSTEM = 5220
    #: ``#5400``: the tool in the spindle.
    TOOL_NUMBER = 5400
    #: ``#5401``-``#5409``: the loaded tool's stored offset (X, Y, Z, A, B, C, U, V, W).
    TOOL_OFFSET = 5401
    #: ``#5420``-``#5428``: the current point in the active coordinate system (program units).
    POSITION = 5420


#: Numbered parameters an axis set takes (LinuxCNC's nine axes: X Y Z A B C U V W).
AXES_IN_PARAMETERS = 9
#: Parameters between one coordinate system's offsets and the next (``#5221`` G54 X, ``#5241`` G55 X).
COORD_SYSTEM_STRIDE = 20


def coord_system_offset(system: int) -> int:
    """The parameter of coordinate system ``system``'s (1-9: G54-G59.3) X offset; Y and Z
    follow (``#5221`` for G54, ``#5381`` for G59.3)."""
    return 5201 + COORD_SYSTEM_STRIDE * system  # LinuxCNC's ``5201 + (origin * 20)``


#: The code selecting each coordinate system 1-9 (G54 ... G59.3), in order.
COORD_SYSTEM_CODES = (
    GCode.G_54,
    GCode.G_55,
    GCode.G_56,
    GCode.G_57,
    GCode.G_58,
    GCode.G_59,
    GCode.G_59_1,
    GCode.G_59_2,
    GCode.G_59_3,
)
#: The coordinate system (1-9) each of those codes selects.
COORD_SYSTEM_OF: dict[int, int] = {code: system for system, code in enumerate(COORD_SYSTEM_CODES, start=1)}
