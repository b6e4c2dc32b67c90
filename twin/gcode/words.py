"""One line of RS-274/NGC read into a block of words, as LinuxCNC's interpreter reads it
(``interp_read.cc``): comments, case and spaces, numbers, parameters, expressions and the
unary functions, parameter settings and O-word lines.

Values are evaluated while the line is read, with the parameters as they were before the line:
``#1=10 #2=#1`` sets #2 to the old #1 (parameter settings take effect after the line, in
:meth:`twin.gcode.reader.Reader`). G codes are kept as ten times their number (``G64`` is 640,
``G91.1`` is 911), as LinuxCNC keeps them.

Most CAM lines are plain words (``G1 X12.5 Y-3 F1200``): they take a fast path of two regular
expressions; everything else is read character by character by :class:`_LineReader`, which
follows LinuxCNC's readers one for one.
"""

from __future__ import annotations

import math
import re
from typing import NamedTuple, Protocol

from twin.gcode.modal import MGroup, ModalGroup

#: Longest line LinuxCNC reads (characters, the newline excluded): its LINELEN buffer of 255
#: holds 253 characters and the newline, and a line that fills it is "Command too long".
MAX_LINE_CHARS = 252
#: Largest magnitude of any word or expression (ours: LinuxCNC has none; 1e9 mm is 1000 km,
#: 1e9 mm/min 16 700 m/s).
MAX_VALUE = 1e9
#: EQ and NE: two numbers closer than this are equal (LinuxCNC's TOLERANCE_EQUAL; LE, GE, LT and
#: GT compare exactly, as rs274 does: ``[1 EQ 1.00001]`` is 1, ``[1 LE 0.99999]`` 0).
TOLERANCE_EQUAL = 0.0001
#: Numbered parameters are 1 .. 5601 (LinuxCNC's RS274NGC_MAX_PARAMETERS is 5602).
MAX_PARAMETER = 5601
#: Arguments an O-word call may pass (#1 .. #30).
MAX_CALL_ARGUMENTS = 30

#: The modal group of each G code (ten times its number); LinuxCNC's ``gees`` table.
G_GROUPS: dict[int, int] = {
    **dict.fromkeys((40, 53, 63, 100, 280, 281, 300, 301, 520, 530, 920), ModalGroup.MODAL_0),
    **dict.fromkeys((0, 10, 20, 30, 50, 51, 52, 60, 61, 62, 330, 331, 382, 383, 384, 385), ModalGroup.MOTION),
    **dict.fromkeys((700, 710, 711, 712, 720, 721, 722, 730, 740, 760, 800), ModalGroup.MOTION),
    **dict.fromkeys(range(810, 900, 10), ModalGroup.MOTION),
    **dict.fromkeys((170, 171, 180, 181, 190, 191), ModalGroup.SET_PLANE),
    **dict.fromkeys((900, 910), ModalGroup.DISTANCE_MODE),
    **dict.fromkeys((901, 911), ModalGroup.IJK_DISTANCE_MODE),
    **dict.fromkeys((930, 940, 950), ModalGroup.FEED_MODE),
    **dict.fromkeys((200, 210), ModalGroup.LENGTH_UNITS),
    **dict.fromkeys((400, 410, 411, 420, 421), ModalGroup.CUTTER_COMP),
    **dict.fromkeys((430, 431, 432, 490), ModalGroup.TOOL_LENGTH_OFFSET),
    **dict.fromkeys((980, 990), ModalGroup.RETRACT_MODE),
    **dict.fromkeys((540, 550, 560, 570, 580, 590, 591, 592, 593), ModalGroup.COORD_SYSTEM),
    **dict.fromkeys((610, 611, 640), ModalGroup.CONTROL_MODE),
    **dict.fromkeys((960, 970), ModalGroup.SPINDLE_MODE),
    **dict.fromkeys((70, 80), ModalGroup.LATHE_DIAMETER_MODE),
    **dict.fromkeys((921, 922, 923), ModalGroup.G92_IS_APPLIED),
}
#: The modal group of each M code; LinuxCNC's ``ems`` table.
M_GROUPS: dict[int, int] = {
    **dict.fromkeys((0, 1, 2, 30, 60, 99), MGroup.STOPPING),
    **dict.fromkeys((3, 4, 5, 19, 70, 71, 72, 73), MGroup.SPINDLE),
    **dict.fromkeys((6, 61), MGroup.TOOL_CHANGE),
    **dict.fromkeys((7, 8, 9), MGroup.COOLANT),
    **dict.fromkeys((48, 49, 50, 51, 52, 53), MGroup.OVERRIDES),
    **dict.fromkeys((62, 63, 64, 65, 66, 67, 68), MGroup.IO),
    **dict.fromkeys(range(100, 200), MGroup.USER_DEFINED),
}
#: The O-word keywords, in the order LinuxCNC tries them (``elseif`` before ``else``).
O_KEYWORDS = (
    "sub",
    "endsub",
    "call",
    "do",
    "while",
    "repeat",
    "if",
    "elseif",
    "else",
    "endif",
    "break",
    "continue",
    "endwhile",
    "endrepeat",
    "return",
)
#: Letters that read an integer (the rest read a real value).
INTEGER_LETTERS = frozenset("hlt")
#: The unary functions (degrees in and out, as LinuxCNC's).
FUNCTIONS = ("abs", "acos", "asin", "atan", "cos", "exists", "exp", "fix", "fup", "ln", "round", "sin", "sqrt", "tan")
#: Binary operators by precedence (higher binds tighter), LinuxCNC's ``precedence()``.
PRECEDENCE = {
    "**": 5,
    "*": 4,
    "/": 4,
    "mod": 4,
    "+": 3,
    "-": 3,
    "eq": 2,
    "ne": 2,
    "gt": 2,
    "ge": 2,
    "lt": 2,
    "le": 2,
    "and": 1,
    "or": 1,
    "xor": 1,
    "]": 0,
}

_FAST_BLOCK = re.compile(r"(?:n[0-9]+(?:\.[0-9]+)?)?\(?(?:[a-mp-z][-+]?[0-9.]+\(?)*")
_COMMENT = re.compile(r"\([^()]*\)")
_FAST_WORD = re.compile(r"([a-mp-z])([-+]?[0-9.]+)")
_NUMBER = re.compile(r"[-+]*[0-9.]*")
_DIGITS = re.compile(r"[0-9]+")
#: LinuxCNC lowers A-Z alone (str.lower would turn the Kelvin sign into k).
_ASCII_LOWER = str.maketrans("ABCDEFGHIJKLMNOPQRSTUVWXYZ", "abcdefghijklmnopqrstuvwxyz")


class BlockError(ValueError):
    """A line LinuxCNC's reader refuses, with the reason (the reader adds file and line)."""


class ParameterSource(Protocol):
    """What expressions read: numbered and named parameter values."""

    def number(self, index: int) -> float: ...

    def named(self, name: str) -> float: ...

    def exists(self, name: str) -> bool: ...


class OLine(NamedTuple):
    """An O-word line: its label (``100``, ``<name>`` lowercased without the brackets), keyword
    and values (a call's arguments, a condition, a repeat count, a return value)."""

    label: str
    keyword: str
    values: tuple[float, ...]


class Block:
    """One line's words.

    Attributes
    ----------
    g : list of int
        G codes, ten times their number, in the order written.
    m : list of int
        M codes.
    words : dict of str to float
        Every other word by its (lower-case) letter: ``x``, ``f``, ``p``...; ``@`` and ``^``
        for polar coordinates.
    settings : list of tuple
        Parameter settings in order: (number or name, value).
    o : OLine or None
        The O-word of an O line (nothing else is on such a line).
    """

    __slots__ = ("g", "m", "o", "settings", "words")

    def __init__(self) -> None:
        self.g: list[int] = []
        self.m: list[int] = []
        self.words: dict[str, float] = {}
        self.settings: list[tuple[int | str, float]] = []
        self.o: OLine | None = None


def normalize(text: str) -> str:
    """The line as LinuxCNC's ``close_and_downcase`` leaves it, comments taken out: spaces,
    tabs and carriage returns removed, letters lower case, each ``( ... )`` comment a lone
    ``(`` (it ends a number, as LinuxCNC's readers stop at it), nothing from ``;`` on.

    Raises
    ------
    BlockError
        A comment not closed, nested, or a ``)`` with no ``(``.
    """
    if "(" in text or ")" in text:
        body, count = _COMMENT.subn("(", text)
        if body.count("(") != count or ")" in body:
            return _normalize_by_character(text)  # unclosed, nested or stray: LinuxCNC's walk says which
    else:
        body = text
    if ";" in body:
        body = body.split(";", 1)[0]
    body = body.replace(" ", "").replace("\t", "").replace("\r", "")
    return body.lower() if body.isascii() else body.translate(_ASCII_LOWER)


def _normalize_by_character(text: str) -> str:
    """:func:`normalize` character by character, as LinuxCNC's ``close_and_downcase`` walks."""
    out: list[str] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == ";":
            break
        if c == "(":
            close = text.find(")", i + 1)
            if close < 0:
                raise BlockError("unclosed comment found (a comment opened with ( is not closed)")
            if "(" in text[i + 1 : close]:
                raise BlockError("nested comment found")
            out.append("(")
            i = close + 1
            continue
        if c not in " \t\r":
            out.append(c)
        i += 1
    return "".join(out).translate(_ASCII_LOWER)


#: A line of one motion and its words in the usual order (what most CAM output is), read at
#: once: a plane (G17-G19), G0-G3 or none (the modal motion), X Y Z I J K R F, a trailing
#: comment; other lines, and these where a word needs a check, take the reader's general path.
_NUMBER_WORD = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
MOTION_LINE = re.compile(
    r"(?:n[0-9]+(?:\.[0-9]+)?)?(?:g(?P<plane>1[789]))?(?:g0?(?P<g>[0-3]))?"
    + "".join(f"(?:{c}(?P<{c}>{_NUMBER_WORD}))?" for c in "xyzijkrf")
    + r"\(?"
)


def read_block(text: str, params: ParameterSource, skipping: bool = False, body: str | None = None) -> Block | None:
    """The block of one line, or None for a line with nothing on it.

    Parameters
    ----------
    text : str
        The line as written.
    params : ParameterSource
        The parameters expressions read.
    skipping : bool
        Inside a branch or loop not taken: only an O line is read (its label and keyword, no
        value evaluated); any other line is None.

    Raises
    ------
    BlockError
        What LinuxCNC's reader refuses, with its reason.
    """
    if body is None:
        body = normalize(text)
    if not skipping and "(" in body and "abort" in text.lower():
        _abort_comment(text)
    if not body or body == "/":
        return None
    if body[0] == "/":
        body = body[1:]  # block delete: LinuxCNC's switch is off by default, so the block runs
    if not skipping and _FAST_BLOCK.fullmatch(body):  # plain letters and numbers only
        block = _fast_block(body)
        if block is not None:
            return block
    return _LineReader(body, params, skipping).block()


def _abort_comment(text: str) -> None:
    """LinuxCNC's ``(ABORT, message)`` comment ends the program with an error."""
    for part in text.split("(")[1:]:
        comment = part.split(")", 1)[0].strip()
        if comment.lower().startswith("abort,"):
            raise BlockError(f"the program aborts here: {comment[6:].strip()}")


def _fast_block(body: str) -> Block | None:
    """Plain words (letters and numbers, no parameter, expression or O-word); None where a
    number does not convert (the general reader then says why)."""
    block = Block()
    words = block.words
    try:
        for letter, number in _FAST_WORD.findall(body):
            if letter == "g":
                # G1, G01, G17: whole numbers (most codes) without the float arithmetic
                whole = number.isdigit() and len(number) <= 3
                block.g.append(int(number) * 10 if whole else _g_code(float(number), number))
                continue
            if letter == "m":
                block.m.append(
                    int(number) if number.isdigit() and len(number) <= 3 else _integer(float(number), f"m{number}")
                )
                continue
            value = float(number)
            if letter in words:
                raise BlockError(f"multiple {letter} words on one line")
            else:
                if not -MAX_VALUE <= value <= MAX_VALUE:
                    raise BlockError(f"{letter.upper()}{number}: beyond {MAX_VALUE:g}, not a physical value")
                words[letter] = float(_integer(value, f"{letter}{number}")) if letter in INTEGER_LETTERS else value
    except ValueError as exc:
        if isinstance(exc, BlockError):
            raise
        return None
    return block


def _g_code(value: float, text: str) -> int:
    """LinuxCNC's ``read_g``: ten times the value, within 0.001 of a whole number."""
    tenfold = 10.0 * value
    code = math.floor(tenfold)
    if tenfold - code > 0.999:
        code = math.ceil(tenfold)
    elif tenfold - code > 0.001:
        raise BlockError(f"G-code out of range: G{text}")
    if code > 999:
        raise BlockError(f"G-code out of range: G{text}")
    if code < 0:
        raise BlockError(f"negative G-code used: G{text}")
    return int(code)


def _integer(value: float, text: str) -> int:
    """LinuxCNC's ``read_integer_value``: within 0.0001 of a whole number."""
    if not -MAX_VALUE <= value <= MAX_VALUE:
        raise BlockError(f"{text.upper()}: beyond {MAX_VALUE:g}, not a physical value")
    whole = math.floor(value)
    if value - whole > 0.9999:
        whole = math.ceil(value)
    elif value - whole > 0.0001:
        raise BlockError(f"non-integer value for integer: {text.upper()}")
    return int(whole)


def _finite(value: float) -> float:
    """LinuxCNC's check after every value read."""
    if math.isnan(value):
        raise BlockError("calculation resulted in 'not a number'")
    if math.isinf(value):
        raise BlockError("calculation resulted in 'infinity'")
    return value


class _LineReader:
    """LinuxCNC's readers over one normalized line (``read_items`` and what it calls)."""

    def __init__(self, body: str, params: ParameterSource, skipping: bool):
        self.s, self.i, self.params, self.skipping = body, 0, params, skipping

    def peek(self, offset: int = 0) -> str:
        k = self.i + offset
        return self.s[k] if k < len(self.s) else ""

    def block(self) -> Block | None:
        block = Block()
        if self.peek() == "n":
            self.i += 1
            self._unsigned("line number")
            if self.peek() == ".":
                self.i += 1
                self._unsigned("line number")
        if self.peek() == "o":
            block.o = self._o_line()
            self._rest_of_o_line()
            return block
        if self.skipping:
            return None
        while self.i < len(self.s):
            self._item(block)
        return block

    def _unsigned(self, what: str) -> int:
        match = _DIGITS.match(self.s, self.i)
        if match is None:
            raise BlockError(f"bad format unsigned integer ({what})")
        self.i = match.end()
        return int(match.group())

    def _item(self, block: Block) -> None:
        c = self.s[self.i]
        if c == "(":
            self.i += 1
            return
        if c == "#":
            self._setting(block)
            return
        if not ("a" <= c <= "z" or c in "@^$"):
            raise BlockError(f"bad character used: {c!r}")
        if c in "no":
            raise BlockError(f"bad character used: {c!r} ({c.upper()} is only allowed at the start of a line)")
        self.i += 1
        if c == "g":
            start = self.i
            value = self.real_value()
            block.g.append(_g_code(value, self.s[start : self.i]))
            return
        if c == "m":
            start = self.i
            value = self.real_value()
            block.m.append(_integer(value, "m" + self.s[start : self.i]))
            return
        if c in block.words:
            raise BlockError(f"multiple {c} words on one line")
        start = self.i
        value = self.real_value()
        if c in INTEGER_LETTERS:
            value = float(_integer(value, c + self.s[start : self.i]))
        elif abs(value) > MAX_VALUE:
            raise BlockError(
                f"{c.upper()}{self.s[start : self.i][:20]} = {value:g}: beyond {MAX_VALUE:g}, not a physical value"
            )
        block.words[c] = value

    def _setting(self, block: Block) -> None:
        self.i += 1
        if self.peek() == "<":
            key: int | str = self._name()
        else:
            index = _integer(self.real_value(), "parameter number")
            if not 1 <= index <= MAX_PARAMETER:
                raise BlockError(f"parameter number out of range: #{index}")
            key = index
        if self.peek() != "=":
            raise BlockError("equal sign missing in parameter setting")
        self.i += 1
        block.settings.append((key, self.real_value()))

    def _name(self) -> str:
        """A ``<name>`` (the reader is at ``<``): the name without the brackets."""
        close = self.s.find(">", self.i)
        if close < 0:
            raise BlockError("named parameter not terminated (no >)")
        name = self.s[self.i + 1 : close]
        if not name:
            raise BlockError("empty name in < >")
        self.i = close + 1
        return name

    def _o_line(self) -> OLine:
        self.i += 1
        if self.peek() == "<":
            label = self._name()
        elif self.skipping:  # evaluated where it can be: a label that cannot never ends a skip
            try:
                label = str(_integer(self.real_value(), "o-word"))
            except BlockError:
                self.i = len(self.s)
                return OLine("?", "", ())
        else:
            label = str(_integer(self.real_value(), "o-word"))
        for keyword in O_KEYWORDS:
            if self.s.startswith(keyword, self.i):
                self.i += len(keyword)
                break
        else:
            rest = self.s[self.i : self.i + 12]
            if not rest or rest[0] == "(":
                raise BlockError("Fanuc-style numbered programs (a bare O-word) are not supported: use O-word sub")
            raise BlockError(f"unknown command in O line: {rest!r}")
        values: list[float] = []
        if self.skipping:
            self.i = len(self.s)  # nothing on a skipped line is evaluated
            return OLine(label, keyword, ())
        if keyword == "call":
            while self.peek() in ("[", "("):
                if self.peek() == "(":
                    self.i += 1
                    continue
                if len(values) == MAX_CALL_ARGUMENTS:
                    raise BlockError(f"too many subroutine parameters (at most {MAX_CALL_ARGUMENTS})")
                values.append(self.expression())
        elif keyword in ("endsub", "return"):
            if self.peek() == "[":
                values.append(self.expression())
        elif keyword in ("while", "if", "elseif", "repeat"):
            if self.peek() != "[":
                raise BlockError(f"left bracket missing after '{keyword}'")
            values.append(self.expression())
        return OLine(label, keyword, tuple(values))

    def _rest_of_o_line(self) -> None:
        while self.i < len(self.s):
            if self.s[self.i] == "(":
                self.i += 1
            else:
                raise BlockError("unexpected character after O-word")

    # values ---------------------------------------------------------------------------

    def real_value(self) -> float:
        """LinuxCNC's ``read_real_value``: a number, parameter, expression or function."""
        c = self.peek()
        if not c or c == "(":
            raise BlockError("no characters found in reading real value")
        c1 = self.peek(1)
        if c == "[":
            value = self.expression()
        elif c == "#":
            self.i += 1
            value = self.parameter_value()
        elif c in "+-" and c1 and not c1.isdigit() and c1 != ".":
            self.i += 1
            value = self.real_value()
            if c == "-":
                value = -value
        elif "a" <= c <= "z":
            value = self.function()
        else:
            value = self.number()
        return _finite(value)

    def number(self) -> float:
        match = _NUMBER.match(self.s, self.i)
        assert match is not None  # the pattern matches the empty string
        text = match.group()
        self.i = match.end()
        ascii_digits = any("0" <= ch <= "9" for ch in text)
        try:
            value = float(text) if ascii_digits else float("nan")
        except ValueError:
            value = float("nan")
        if math.isnan(value):
            shown = text or self.s[self.i : self.i + 6]
            raise BlockError(f"bad number format: {shown!r}")
        if math.isinf(value):
            raise BlockError(f"{text[:20]}...: beyond any floating-point number")
        return value

    def parameter_value(self) -> float:
        """The value of a parameter (the reader is after ``#``)."""
        if self.peek() == "<":
            return self.params.named(self._name())
        index = _integer(self.real_value(), "parameter number")
        if not 1 <= index <= MAX_PARAMETER:
            raise BlockError(f"parameter number out of range: #{index}")
        return self.params.number(index)

    def function(self) -> float:
        name = next((f for f in FUNCTIONS if self.s.startswith(f, self.i)), None)
        if name is None:
            raise BlockError(f"unknown word where unary operation could be: {self.s[self.i : self.i + 8]!r}")
        self.i += len(name)
        if self.peek() != "[":
            raise BlockError(f"left bracket missing after unary operation name {name.upper()}")
        if name == "exists":
            self.i += 1
            if self.peek() != "#":
                raise BlockError("expected # reading parameter (EXISTS[#<name>] or EXISTS[#number])")
            self.i += 1
            if self.peek() == "<":
                exists = self.params.exists(self._name())
            else:  # a numbered parameter exists when its number is in range
                exists = 1 <= _integer(self.real_value(), "parameter number") <= MAX_PARAMETER
            if self.peek() != "]":
                raise BlockError("expected ] reading bracketed parameter")
            self.i += 1
            return 1.0 if exists else 0.0
        value = self.expression()
        if name == "atan":
            if self.peek() != "/":
                raise BlockError("slash missing after first ATAN argument")
            self.i += 1
            if self.peek() != "[":
                raise BlockError("left bracket missing after slash with ATAN")
            return math.degrees(math.atan2(value, self.expression()))
        return _unary(name, value)

    def expression(self) -> float:
        """LinuxCNC's stack-based ``read_real_expression`` (the reader is at ``[``): operators
        of the same precedence left to right."""
        self.i += 1
        values = [self.real_value()]
        operators = [self.operator()]
        while operators[0] != "]":
            values.append(self.real_value())
            operators.append(self.operator())
            while len(operators) > 1 and PRECEDENCE[operators[-1]] <= PRECEDENCE[operators[-2]]:
                right = values.pop()
                operator = operators.pop()
                values[-1] = _finite(_binary(values[-1], operators[-1], right))
                operators[-1] = operator
        return values[0]

    def operator(self) -> str:
        c = self.peek()
        if not c:
            raise BlockError("unclosed expression (no ])")
        if c == "*" and self.peek(1) == "*":
            self.i += 2
            return "**"
        if c in "+-*/]":
            self.i += 1
            return c
        for name in ("mod", "and", "xor", "or", "eq", "ne", "gt", "ge", "lt", "le"):
            if self.s.startswith(name, self.i):
                self.i += len(name)
                return name
        raise BlockError(f"unknown operation: {self.s[self.i : self.i + 6]!r}")


def _unary(name: str, value: float) -> float:
    """LinuxCNC's ``execute_unary`` (angles in degrees)."""
    if name == "abs":
        return abs(value)
    if name in ("acos", "asin"):
        if not -1.0 <= value <= 1.0:
            raise BlockError(f"argument to {name} out of range: {value:g}")
        return math.degrees(math.acos(value) if name == "acos" else math.asin(value))
    if name == "cos":
        return math.cos(math.radians(value))
    if name == "sin":
        return math.sin(math.radians(value))
    if name == "tan":
        return math.tan(math.radians(value))
    if name == "exp":
        try:
            return math.exp(value)
        except OverflowError:
            raise BlockError("calculation resulted in 'infinity'") from None
    if name == "fix":
        return float(math.floor(value))
    if name == "fup":
        return float(math.ceil(value))
    if name == "ln":
        if value <= 0.0:
            raise BlockError(f"zero or negative argument to ln: {value:g}")
        return math.log(value)
    if name == "round":
        return float(int(value + (-0.5 if value < 0.0 else 0.5)))
    if value < 0.0:  # sqrt
        raise BlockError(f"negative argument to sqrt: {value:g}")
    return math.sqrt(value)


def _binary(left: float, operator: str, right: float) -> float:
    """LinuxCNC's ``execute_binary1`` / ``execute_binary2``."""
    if operator == "+":
        return left + right
    if operator == "-":
        return left - right
    if operator == "*":
        return left * right
    if operator == "/":
        if right == 0.0:
            raise BlockError("attempt to divide by zero")
        return left / right
    if operator == "mod":
        if right == 0.0:
            raise BlockError("attempt to divide by zero (MOD 0)")
        result = math.fmod(left, right)
        return result + abs(right) if result < 0.0 else result
    if operator == "**":
        if left < 0.0 and math.floor(right) != right:
            raise BlockError("attempt to raise negative to non-integer power")
        try:
            return math.pow(left, right)
        except (OverflowError, ValueError):
            raise BlockError("calculation resulted in 'infinity'") from None
    if operator == "and":
        return 0.0 if left == 0.0 or right == 0.0 else 1.0
    if operator == "or":
        return 1.0 if left != 0.0 or right != 0.0 else 0.0
    if operator == "xor":
        return 1.0 if (left == 0.0) != (right == 0.0) else 0.0
    diff = abs(left - right)
    if operator == "eq":
        return 1.0 if diff < TOLERANCE_EQUAL else 0.0
    if operator == "ne":
        return 1.0 if diff >= TOLERANCE_EQUAL else 0.0
    if operator == "lt":
        return 1.0 if left < right else 0.0
    if operator == "gt":
        return 1.0 if left > right else 0.0
    if operator == "le":
        return 1.0 if left <= right else 0.0
    return 1.0 if left >= right else 0.0  # ge
