"""Parameters as LinuxCNC's interpreter keeps them: numbered ``#1`` .. ``#5601``, named local
``#<name>`` (one scope per subroutine call) and global ``#<_name>``, and the read-only system
parameters computed from the interpreter's state (``#5220``, ``#<_x>``, ...).

The numbered ones #1 .. #30 are a call's arguments: saved at a call and restored at its return
(:meth:`Parameters.enter` / :meth:`Parameters.leave`); #31 and up are global. Reading a named
parameter never set is an error, as in LinuxCNC; a numbered one reads 0.
"""

from __future__ import annotations

from collections.abc import Callable

from twin.gcode.words import MAX_CALL_ARGUMENTS, BlockError

#: Most named parameters a program may create (ours: bounded memory for any program).
MAX_NAMED = 100_000


class Parameters:
    """The parameter table of one program.

    Parameters
    ----------
    system : callable
        ``system(number_or_name)`` gives a read-only system parameter's value, or None where
        the number or name is not one.
    """

    def __init__(self, system: Callable[[int | str], float | None]):
        self.system = system
        self.numbered: dict[int, float] = {}
        self.globals: dict[str, float] = {}
        self.scopes: list[dict[str, float]] = [{}]
        self.saved: list[dict[int, float]] = []

    def number(self, index: int) -> float:
        """The value of ``#index`` (0 where never set)."""
        value = self.system(index)
        if value is not None:
            return value
        return self.numbered.get(index, 0.0)

    def named(self, name: str) -> float:
        """The value of ``#<name>``."""
        if name.startswith("_"):
            value = self.system(name)
            if value is not None:
                return value
            if name in self.globals:
                return self.globals[name]
        elif name in self.scopes[-1]:
            return self.scopes[-1][name]
        if name.startswith(("_ini[", "_hal[")):
            raise BlockError(f"#<{name}>: INI and HAL parameters are not available in the twin")
        raise BlockError(f"named parameter #<{name}> not defined")

    def exists(self, name: str) -> bool:
        """Whether ``#<name>`` has a value (EXISTS)."""
        if name.startswith("_"):
            return self.system(name) is not None or name in self.globals
        return name in self.scopes[-1]

    def set(self, key: int | str, value: float) -> None:
        """Set a numbered or named parameter (read-only system ones refuse)."""
        if isinstance(key, int):
            if self.system(key) is not None:
                raise BlockError(f"parameter #{key} is read-only")
            self.numbered[key] = value
            return
        if key.startswith("_"):
            if self.system(key) is not None:
                raise BlockError(f"parameter #<{key}> is read-only")
            table = self.globals
        else:
            table = self.scopes[-1]
        if key not in table and len(self.globals) + sum(len(s) for s in self.scopes) >= MAX_NAMED:
            raise BlockError(f"more than {MAX_NAMED} named parameters")
        table[key] = value

    def enter(self, arguments: tuple[float, ...]) -> None:
        """A subroutine call: #1 .. #30 saved and set to the arguments (the rest to 0, as
        LinuxCNC 2.9 does), a new scope of local named parameters."""
        self.saved.append({i: self.numbered.get(i, 0.0) for i in range(1, MAX_CALL_ARGUMENTS + 1)})
        for i in range(1, MAX_CALL_ARGUMENTS + 1):
            self.numbered[i] = arguments[i - 1] if i <= len(arguments) else 0.0
        self.scopes.append({})

    def leave(self) -> None:
        """A subroutine's return: #1 .. #30 and the caller's local names back."""
        self.numbered.update(self.saved.pop())
        self.scopes.pop()
