"""LinuxCNC's names for the numbers its interpreter works with: the G modal groups
(``ModalGroups`` of ``interp_internal.hh``), the G codes as ten times their number (``GCodes``
there: ``G_61_1`` is 611), the M modal groups and the numbered parameters the twin reads or
sets (LinuxCNC's G-code overview, "Modal Groups" and "Numbered Parameters").

A block's codes are kept by group (``g_modes[ModalGroup.CONTROL_MODE]``), as LinuxCNC's
``block->g_modes[GM_CONTROL_MODE]``; the parameters are numbered as in LinuxCNC's ``#5161``, an
axis's one the first (X) plus the axis index (x 0, y 1, z 2). The names are plain ``int``
constants in a class a kind (as LinuxCNC's unscoped C enums): the interpreter compares them on
every line, and an ``IntEnum`` member costs Python 3.11 five times a class attribute to look up.
"""

from __future__ import annotations

from typing import Final


class ModalGroup:
    """The G modal groups: LinuxCNC's ``GM_*`` (``GM_MOTION`` is ``MOTION``); 9 and 11 are
    unused."""

    MODAL_0: Final = 0
    MOTION: Final = 1
    SET_PLANE: Final = 2
    DISTANCE_MODE: Final = 3
    IJK_DISTANCE_MODE: Final = 4
    FEED_MODE: Final = 5
    LENGTH_UNITS: Final = 6
    CUTTER_COMP: Final = 7
    TOOL_LENGTH_OFFSET: Final = 8
    RETRACT_MODE: Final = 10
    COORD_SYSTEM: Final = 12
    CONTROL_MODE: Final = 13
    SPINDLE_MODE: Final = 14
    LATHE_DIAMETER_MODE: Final = 15
    G92_IS_APPLIED: Final = 16


class MGroup:
    """The M modal groups (LinuxCNC's ``m_modes`` indices, named as its documentation's table)."""

    STOPPING: Final = 4
    IO: Final = 5
    TOOL_CHANGE: Final = 6
    SPINDLE: Final = 7
    COOLANT: Final = 8
    OVERRIDES: Final = 9
    USER_DEFINED: Final = 10


class GCode:
    """The G codes, ten times their number: LinuxCNC's ``GCodes`` (``G_59_3`` is 593)."""

    G_0: Final = 0
    G_1: Final = 10
    G_2: Final = 20
    G_3: Final = 30
    G_4: Final = 40
    G_5: Final = 50
    G_5_1: Final = 51
    G_5_2: Final = 52
    G_5_3: Final = 53
    G_6: Final = 60
    G_6_1: Final = 61
    G_6_2: Final = 62
    G_6_3: Final = 63
    G_7: Final = 70
    G_8: Final = 80
    G_10: Final = 100
    G_17: Final = 170
    G_17_1: Final = 171
    G_18: Final = 180
    G_18_1: Final = 181
    G_19: Final = 190
    G_19_1: Final = 191
    G_20: Final = 200
    G_21: Final = 210
    G_28: Final = 280
    G_28_1: Final = 281
    G_30: Final = 300
    G_30_1: Final = 301
    G_33: Final = 330
    G_33_1: Final = 331
    G_38_2: Final = 382
    G_38_3: Final = 383
    G_38_4: Final = 384
    G_38_5: Final = 385
    G_40: Final = 400
    G_41: Final = 410
    G_41_1: Final = 411
    G_42: Final = 420
    G_42_1: Final = 421
    G_43: Final = 430
    G_43_1: Final = 431
    G_43_2: Final = 432
    G_49: Final = 490
    G_52: Final = 520
    G_53: Final = 530
    G_54: Final = 540
    G_55: Final = 550
    G_56: Final = 560
    G_57: Final = 570
    G_58: Final = 580
    G_59: Final = 590
    G_59_1: Final = 591
    G_59_2: Final = 592
    G_59_3: Final = 593
    G_61: Final = 610
    G_61_1: Final = 611
    G_64: Final = 640
    G_70: Final = 700
    G_71: Final = 710
    G_71_1: Final = 711
    G_71_2: Final = 712
    G_72: Final = 720
    G_72_1: Final = 721
    G_72_2: Final = 722
    G_73: Final = 730
    G_74: Final = 740
    G_76: Final = 760
    G_80: Final = 800
    G_81: Final = 810
    G_82: Final = 820
    G_83: Final = 830
    G_84: Final = 840
    G_85: Final = 850
    G_86: Final = 860
    G_87: Final = 870
    G_88: Final = 880
    G_89: Final = 890
    G_90: Final = 900
    G_90_1: Final = 901
    G_91: Final = 910
    G_91_1: Final = 911
    G_92: Final = 920
    G_92_1: Final = 921
    G_92_2: Final = 922
    G_92_3: Final = 923
    G_93: Final = 930
    G_94: Final = 940
    G_95: Final = 950
    G_96: Final = 960
    G_97: Final = 970
    G_98: Final = 980
    G_99: Final = 990


class Param:
    """The numbered parameters the twin reads or sets; an axis's parameter is the X one plus
    the axis index (LinuxCNC's G-code overview, "Numbered Parameters")."""

    #: ``#5161``-``#5163``: G28's home, X, Y, Z (user units, machine coordinates).
    G28_HOME: Final = 5161
    #: ``#5181``-``#5183``: G30's home.
    G30_HOME: Final = 5181
    #: ``#5210``: 1 while a G52 / G92 offset is applied, else 0.
    AXIS_OFFSET_APPLIED: Final = 5210
    #: ``#5211``-``#5213``: the G52 / G92 offset shared by both, X, Y, Z.
    AXIS_OFFSET: Final = 5211
    #: ``#5220``: the coordinate system in force, 1-9 (G54-G59.3).
    COORD_SYSTEM: Final = 5220
    #: ``#5400``: the tool in the spindle.
    TOOL_NUMBER: Final = 5400
    #: ``#5401``-``#5409``: the loaded tool's stored offset (X, Y, Z, A, B, C, U, V, W).
    TOOL_OFFSET: Final = 5401
    #: ``#5420``-``#5428``: the current point in the active coordinate system (program units).
    POSITION: Final = 5420


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
