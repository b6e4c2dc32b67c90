"""O-word program flow as LinuxCNC's interpreter runs it (``interp_o_word.cc``): subroutines
(``sub`` / ``endsub`` / ``call`` / ``return``), loops (``while`` / ``endwhile``, ``do`` /
``while``, ``repeat`` / ``endrepeat``, ``break``, ``continue``) and conditions (``if`` /
``elseif`` / ``else`` / ``endif``), over a program text that can go back to a line.

Like LinuxCNC, the flow is line by line: a branch or loop not taken is skipped by reading on
(nothing evaluated) to the O line that ends it; a loop or call goes back by seeking to a line
read before. A subroutine called before its definition is found by reading ahead to it, as
LinuxCNC 2.9 does (which then refuses the definition where the program reaches it again).

Bounded: at most :data:`MAX_CALL_DEPTH` nested calls (LinuxCNC's limit), :data:`MAX_ITERATIONS`
jumps back of all loops together and :data:`MAX_SUBROUTINES` definitions; a program over a
limit is refused at it, with its line.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from enum import Enum, StrEnum
from pathlib import Path
from typing import NamedTuple

from twin.gcode.parameters import Parameters
from twin.gcode.words import MAX_LINE_CHARS, BlockError, OLine

#: Nested subroutine calls at most (LinuxCNC's INTERP_SUB_ROUTINE_LEVELS).
MAX_CALL_DEPTH = 10
#: Jumps back (loop iterations) in one program at most (ours: a loop that never ends is refused).
MAX_ITERATIONS = 1_000_000
#: Subroutine definitions in one program at most (ours).
MAX_SUBROUTINES = 10_000


class Position(NamedTuple):
    """Where a line starts: its byte (or list) offset and its 1-based number."""

    offset: int
    number: int


class ProgramText:
    """A program's lines, read one at a time, that can go back to a line read before.

    Parameters
    ----------
    lines : sequence or iterable of str, or None
        The program's lines (a sequence is indexed; another iterable is kept from the first
        position :meth:`keep` asks for on, so memory stays bounded for a program without O-words).
    path : str or Path, optional
        A file read instead (binary, by byte offsets: memory stays bounded for any program).
    """

    def __init__(self, lines: Iterable[str] | None = None, path: str | Path | None = None):
        self.handle = None
        self.sequence: Sequence[str] | None = None
        self.iterator: Iterator[str] | None = None
        self.kept: list[str] = []
        self.kept_from: int | None = None
        self.pulled = 0
        self.offset, self.number = 0, 0
        self.line_offset = 0  # where the line last read starts
        if path is not None:
            self.handle = Path(path).open("rb")  # noqa: SIM115 - held for the program's reading, closed by close()
        elif isinstance(lines, Sequence) and not isinstance(lines, str):
            self.sequence = lines
        else:
            assert lines is not None
            self.iterator = iter(lines)

    def close(self) -> None:
        if self.handle is not None:
            self.handle.close()

    def tell(self) -> Position:
        """The position of the next line."""
        return Position(self.offset, self.number + 1)

    def keep(self, position: Position) -> None:
        """A position the flow may go back to (an iterable's lines from there on are kept)."""
        if self.iterator is not None and self.kept_from is None:
            self.kept_from = position.offset

    def seek(self, position: Position) -> None:
        """Go back (or on) to a line read before."""
        if self.handle is not None:
            self.handle.seek(position.offset)
        self.offset, self.number = position.offset, position.number - 1

    def next_line(self) -> str | None:
        """The next line without its end-of-line characters (None at the end).

        Raises
        ------
        BlockError
            A line longer than :data:`MAX_LINE_CHARS` (at most that much of it is read) or
            with a NUL byte.
        """
        self.line_offset = self.offset
        if self.handle is not None:
            raw = self.handle.readline(MAX_LINE_CHARS + 3)
            if not raw:
                return None
            self.offset += len(raw)
            self.number += 1
            if len(raw) - raw.endswith(b"\n") > MAX_LINE_CHARS:
                start = raw[:40].decode("utf-8", errors="replace")
                raise BlockError(f"command too long: a line of more than {MAX_LINE_CHARS} characters ({start!r}...)")
            text = raw.decode("utf-8", errors="replace").rstrip("\r\n")
        else:
            line = self._line_of_sequence() if self.sequence is not None else self._line_of_iterator()
            if line is None:
                return None
            text = line
            self.offset += 1
            self.number += 1
        if len(text) > MAX_LINE_CHARS:
            raise BlockError(f"command too long: a line of more than {MAX_LINE_CHARS} characters ({text[:40]!r}...)")
        if "\x00" in text:
            raise BlockError("not text (a NUL byte)")
        return text

    def _line_of_sequence(self) -> str | None:
        assert self.sequence is not None
        return self.sequence[self.offset] if self.offset < len(self.sequence) else None

    def _line_of_iterator(self) -> str | None:
        assert self.iterator is not None
        if self.kept_from is not None and self.offset < self.pulled:
            return self.kept[self.offset - self.kept_from]
        text = next(self.iterator, None)
        if text is None:
            return None
        self.pulled += 1
        if self.kept_from is not None:
            self.kept.append(text[: MAX_LINE_CHARS + 2])
        return text


class LoopKind(StrEnum):
    """The three loops, by the keyword that opens them."""

    WHILE = "while"
    DO = "do"
    REPEAT = "repeat"


#: The keyword that ends each loop (``do`` ... ``while``).
LOOP_END = {LoopKind.WHILE: "endwhile", LoopKind.DO: "while", LoopKind.REPEAT: "endrepeat"}


class SkipEnd(Enum):
    """What the O line that ends a skip does: runs (it is evaluated and its keyword's handler
    called) or is passed (the flow goes on after it)."""

    RUN = "run"
    PASS = "pass"


@dataclass
class _Loop:
    kind: LoopKind
    start: Position  # while: the while line; do / repeat: the line after
    remaining: int = 0


@dataclass
class _Frame:
    """One subroutine call (the main program is the first)."""

    name: str
    back: Position | None
    loops: dict[str, _Loop] = field(default_factory=dict)
    ifs: set[str] = field(default_factory=set)
    #: Each label an if, while, do or repeat of this call has run: its keyword and line (LinuxCNC's
    #: offset map: a label is defined once, and an elseif, else or endif needs its if).
    labels: dict[str, tuple[str, int]] = field(default_factory=dict)


@dataclass
class _Skip:
    """Reading on without evaluating, to an O line of ``label`` with one of ``keywords``;
    ``then`` says what to do there (run it, or pass on after it)."""

    label: str
    keywords: frozenset[str]
    then: SkipEnd
    started: int


class Flow:
    """The program flow of one program: which line runs next.

    Parameters
    ----------
    text : ProgramText
    params : Parameters
        Saved and restored around calls; ``_value`` / ``_value_returned`` set by returns.
    """

    def __init__(self, text: ProgramText, params: Parameters):
        self.text, self.params = text, params
        self.frames = [_Frame("", None)]
        self.subs: dict[str, Position] = {}
        self.skip: _Skip | None = None
        self.defining: str | None = None
        self.searching: tuple[str, tuple[float, ...], Position] | None = None
        self.iterations = 0
        self.return_value = 0.0
        self.value_returned = 0.0
        #: What each O-word keyword does (LinuxCNC's ``control_*`` of ``interp_o_word.cc``).
        self.handlers: dict[str, Callable[[OLine], None]] = {
            "sub": self._sub,
            "endsub": self._return,
            "call": self._call,
            "do": self._do,
            "while": self._while,
            "repeat": self._repeat,
            "if": self._if,
            "elseif": self._elseif,
            "else": self._else,
            "endif": self._endif,
            "break": self._break,
            "continue": self._continue,
            "endwhile": self._endwhile,
            "endrepeat": self._endrepeat,
            "return": self._return,
        }

    @property
    def skipping(self) -> bool:
        """Whether the next line is read without being evaluated."""
        return self.skip is not None

    @property
    def line_start(self) -> Position:
        """Where the line last read starts."""
        return Position(self.text.line_offset, self.text.number)

    @property
    def depth(self) -> int:
        """Subroutine calls in progress (LinuxCNC's ``_call_level``)."""
        return len(self.frames) - 1

    def next_line(self) -> str | None:
        """The text of the next line to read (None at the end of the file)."""
        text = self.text.next_line()
        if text is None:
            if self.searching is not None:
                raise BlockError(f"o{self.searching[0]} call: no such subroutine (read to the end of the file)")
            if self.skip is not None:
                raise BlockError(
                    f"the file ends inside o{self.skip.label} (started on line {self.skip.started}), "
                    f"looking for its {' or '.join(sorted(self.skip.keywords))}"
                )
            if self.depth:
                raise BlockError(f"the file ends inside subroutine o{self.frames[-1].name}")
        return text

    def end_needs_values(self) -> bool:
        """Whether the O line that ends the skip runs with its values (a condition to test)."""
        return self.skip is not None and self.skip.then is SkipEnd.RUN and self.searching is None

    def is_end(self, o: OLine) -> bool:
        """Whether the O line ``o`` read while skipping ends the skip (and then runs).

        Raises
        ------
        BlockError
            A subroutine defined inside the one being defined (LinuxCNC refuses nesting); an
            elseif, else or endif of a loop's label, an endwhile or endrepeat of an if's.
        """
        skip = self.skip
        assert skip is not None
        if self.defining is not None and o.keyword == "sub":
            raise BlockError(f"nested subroutine definition: o{o.label} sub inside o{self.defining}")
        if self.searching is not None and o.keyword == "sub" and o.label == self.searching[0]:
            return True
        if o.label != skip.label:
            return False
        if o.keyword in skip.keywords:
            return True
        if self.searching is None and self.defining is None:  # a block of this label, skipped
            if o.keyword in ("elseif", "else", "endif"):
                self._of_if(o)
            elif o.keyword in ("endwhile", "endrepeat") and self.frames[-1].labels.get(o.label, ("",))[0] == "if":
                raise BlockError(f"o{o.label} {o.keyword}: o{o.label} is an if, not a loop")
        return False

    def o_line(self, o: OLine) -> None:
        """Run an O line (read with its values evaluated)."""
        if self.skip is not None:
            self._end_skip(o)
            return
        self.handlers[o.keyword](o)

    # --- skipping -------------------------------------------------------------------------

    def _skip_to(self, label: str, keywords: tuple[str, ...], then: SkipEnd) -> None:
        self.skip = _Skip(label, frozenset(keywords), then, self.line_start.number)

    def _end_skip(self, o: OLine) -> None:
        skip = self.skip
        assert skip is not None
        self.skip = None
        if self.searching is not None:
            name, arguments, back = self.searching
            self.searching = None
            self._define(name, skipping=False)
            self._enter(name, arguments, back)
            return
        if self.defining is not None:  # the endsub of a definition
            self.defining = None
            return
        if skip.then is SkipEnd.RUN:
            self.handlers[o.keyword](o)

    # --- subroutines ----------------------------------------------------------------------

    def _define(self, name: str, skipping: bool = True) -> None:
        if name in self.subs:
            raise BlockError(
                f"o{name} sub: a subroutine of that name is already defined (line {self.subs[name].number - 1}); "
                "LinuxCNC refuses a definition reached again, also after a call found it further on"
            )
        if len(self.subs) >= MAX_SUBROUTINES:
            raise BlockError(f"more than {MAX_SUBROUTINES} subroutine definitions")
        body = self.text.tell()
        self.text.keep(body)
        self.subs[name] = body
        if skipping:
            self.defining = name
            self._skip_to(name, ("endsub",), SkipEnd.PASS)

    def _sub(self, o: OLine) -> None:
        if self.depth:
            raise BlockError(f"o{o.label} sub: a subroutine defined inside subroutine o{self.frames[-1].name}")
        self._define(o.label)

    def _call(self, o: OLine) -> None:
        back = self.text.tell()
        if o.label not in self.subs:  # read on to find it, as LinuxCNC 2.9 does
            self.searching = (o.label, o.values, back)
            self.text.keep(back)
            self._skip_to(o.label, ("sub",), SkipEnd.PASS)
            return
        self._enter(o.label, o.values, back)

    def _enter(self, name: str, arguments: tuple[float, ...], back: Position) -> None:
        if self.depth >= MAX_CALL_DEPTH:
            raise BlockError(f"o{name} call: more than {MAX_CALL_DEPTH} nested subroutine calls")
        self.text.keep(back)
        self.params.enter(arguments)
        self.return_value = self.value_returned = 0.0
        self.frames.append(_Frame(name, back))
        self.text.seek(self.subs[name])

    def _return(self, o: OLine) -> None:
        if not self.depth:
            raise BlockError(f"o{o.label} {o.keyword}: not inside a subroutine")
        frame = self.frames[-1]  # any label returns from the subroutine being run, as in LinuxCNC
        self.return_value, self.value_returned = (o.values[0], 1.0) if o.values else (0.0, 0.0)
        self.frames.pop()
        self.params.leave()
        assert frame.back is not None
        self.text.seek(frame.back)

    # --- labels ---------------------------------------------------------------------------

    def _label(self, o: OLine) -> None:
        """An if, while, do or repeat: its label is this one's (LinuxCNC refuses a label defined
        twice in a call, also after its block ended; the same line run again is no second one)."""
        labels = self.frames[-1].labels
        line = self.line_start.number
        known = labels.get(o.label)
        if known is None:
            labels[o.label] = (o.keyword, line)
        elif known[1] != line:
            raise BlockError(
                f"o{o.label} {o.keyword}: the label o{o.label} is already defined on line {known[1]} "
                f"(o{o.label} {known[0]}); LinuxCNC refuses a label defined twice"
            )

    def _of_if(self, o: OLine) -> None:
        """An elseif, else or endif: its label is an if's, run before it in this call."""
        known = self.frames[-1].labels.get(o.label)
        if known is None:
            raise BlockError(f"o{o.label} {o.keyword} without its if: no o{o.label} if ran before it")
        if known[0] != "if":
            raise BlockError(f"o{o.label} {o.keyword}: o{o.label} is a {known[0]} (line {known[1]}), not an if")

    # --- loops ----------------------------------------------------------------------------

    def _jump_back(self, position: Position) -> None:
        self.iterations += 1
        if self.iterations > MAX_ITERATIONS:
            raise BlockError(f"more than {MAX_ITERATIONS:,} loop iterations: a loop that does not end?")
        self.text.seek(position)

    def _do(self, o: OLine) -> None:
        self._label(o)
        start = self.text.tell()
        self.text.keep(start)
        self.frames[-1].loops[o.label] = _Loop(LoopKind.DO, start)

    def _while(self, o: OLine) -> None:
        loops = self.frames[-1].loops
        loop = loops.get(o.label)
        if loop is not None and loop.kind is LoopKind.DO:  # the end of a do loop
            if o.values[0] != 0.0:
                self._jump_back(loop.start)
            else:
                del loops[o.label]
            return
        self._label(o)
        if o.values[0] != 0.0:
            if loop is None:
                self.text.keep(self.line_start)
                loops[o.label] = _Loop(LoopKind.WHILE, self.line_start)
            return
        loops.pop(o.label, None)
        self._skip_to(o.label, ("endwhile",), SkipEnd.PASS)

    def _endwhile(self, o: OLine) -> None:
        loop = self.frames[-1].loops.get(o.label)
        if loop is None or loop.kind is not LoopKind.WHILE:
            raise BlockError(f"o{o.label} endwhile: no while loop of that label")
        self._jump_back(loop.start)

    def _repeat(self, o: OLine) -> None:
        self._label(o)
        count = int(o.values[0])
        if count <= 0:
            self._skip_to(o.label, ("endrepeat",), SkipEnd.PASS)
            return
        start = self.text.tell()
        self.text.keep(start)
        self.frames[-1].loops[o.label] = _Loop(LoopKind.REPEAT, start, count)

    def _endrepeat(self, o: OLine) -> None:
        loops = self.frames[-1].loops
        loop = loops.get(o.label)
        if loop is None or loop.kind is not LoopKind.REPEAT:
            raise BlockError(f"o{o.label} endrepeat: no repeat loop of that label")
        loop.remaining -= 1
        if loop.remaining > 0:
            self._jump_back(loop.start)
        else:
            del loops[o.label]

    def _loop(self, o: OLine) -> _Loop:
        loop = self.frames[-1].loops.get(o.label)
        if loop is None:
            raise BlockError(f"o{o.label} {o.keyword}: not inside a loop of that label")
        return loop

    def _break(self, o: OLine) -> None:
        loop = self._loop(o)
        del self.frames[-1].loops[o.label]
        self._skip_to(o.label, (LOOP_END[loop.kind],), SkipEnd.PASS)

    def _continue(self, o: OLine) -> None:
        loop = self._loop(o)
        if loop.kind is LoopKind.WHILE:
            self._jump_back(loop.start)
        else:  # do: on to its while (run: its condition); repeat: to its endrepeat (run: it counts)
            self._skip_to(o.label, (LOOP_END[loop.kind],), SkipEnd.RUN)

    # --- conditions -----------------------------------------------------------------------

    def _if(self, o: OLine) -> None:
        self._label(o)
        if o.values[0] != 0.0:
            self.frames[-1].ifs.add(o.label)
        else:
            self.frames[-1].ifs.discard(o.label)
            self._skip_to(o.label, ("elseif", "else", "endif"), SkipEnd.RUN)

    def _elseif(self, o: OLine) -> None:
        self._of_if(o)
        ifs = self.frames[-1].ifs
        if o.label in ifs:  # a branch before was taken
            self._skip_to(o.label, ("endif",), SkipEnd.RUN)
        elif o.values[0] != 0.0:
            ifs.add(o.label)
        else:
            self._skip_to(o.label, ("elseif", "else", "endif"), SkipEnd.RUN)

    def _else(self, o: OLine) -> None:
        self._of_if(o)
        ifs = self.frames[-1].ifs
        if o.label in ifs:
            self._skip_to(o.label, ("endif",), SkipEnd.RUN)
        else:
            ifs.add(o.label)

    def _endif(self, o: OLine) -> None:
        """The if is done: an else or elseif of its label after it is a branch not taken (rs274
        skips it to the next endif of the label, its ``executed_if`` set by every endif)."""
        self._of_if(o)
        self.frames[-1].ifs.add(o.label)
