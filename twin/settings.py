"""The settings mini-language: ``PATH=VALUE`` strings and dotted paths into a TOML table
(``disturbances.0.spindle_rpm=2500``), as ``twin run --set``, ``twin sweep --vary`` and the API's
keyword settings give them."""

from __future__ import annotations

import copy
import tomllib

from twin.errors import TwinInputError


def parse_settings(settings: list[str]) -> dict:
    """``PATH=VALUE`` strings (``disturbances.0.spindle_rpm=2500``) as ``{path: value}``:
    ``VALUE`` is a TOML value (``2500``, ``[0.02]``, ``"down"``; a bare word counts as a string).

    Raises
    ------
    TwinInputError
        A malformed setting.
    """
    values = {}
    for item in settings:
        path, sep, text = item.partition("=")
        if not sep or not all(path.strip().split(".")):
            raise TwinInputError("--set", item, "use PATH=VALUE, e.g. disturbances.0.spindle_rpm=2500")
        try:
            values[path.strip()] = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            values[path.strip()] = text.strip()
    return values


def set_fields(data: dict, values: dict, label: str = "") -> dict:
    """A deep copy of ``data`` with each dotted ``path`` of ``values`` set to its value (list
    entries by index; missing tables are created).

    Raises
    ------
    TwinInputError
        A path that does not lead into the scenario (named with ``label`` before it).
    """
    out = copy.deepcopy(data)
    for path, value in values.items():
        keys = str(path).split(".")
        if not all(keys):
            raise TwinInputError(f"{label}{path}", value, "not a dotted path, e.g. disturbances.0.spindle_rpm")
        node = out
        for depth, key in enumerate(keys):
            last = depth == len(keys) - 1
            if isinstance(node, list):
                if not (key.isdigit() and int(key) < len(node)):
                    raise TwinInputError(f"{label}{path}", key, f"not an index of a list of {len(node)}")
                key = int(key)
            elif not isinstance(node, dict):
                raise TwinInputError(f"{label}{path}", key, "goes below a value")
            if last:
                node[key] = copy.deepcopy(value)
            else:
                if isinstance(node, dict) and key not in node:
                    node[key] = {}
                node = node[key]
    return out
