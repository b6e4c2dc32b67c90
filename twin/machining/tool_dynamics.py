"""The structure at the tool: its vibration modes, or its measured tool-tip FRF.

``[tool.dynamics]`` (also on an entry of ``[[tools]]`` and on an ``end_milling`` disturbance)
gives one of

``modes``
    A list of modes, each ``{ direction = "x" | "y", frequency_hz, damping_ratio,
    stiffness_N_per_m }`` (or ``modal_mass_kg`` in place of the stiffness; one of the two),
    several per direction allowed.  Directions are the machine's X and Y; a mode's receptance at
    the tool tip is ``1 / (k (1 - r^2 + 2 i zeta r))`` with ``r = f / f_n`` and ``k = m (2 pi
    f_n)^2``, the direct receptance of the direction the sum over its modes (m/N), the cross
    terms zero (Altintas, *Manufacturing Automation*, 2nd ed., ch. 3.2).
``frf_file``
    A measured tool-tip FRF (an impact test): a CSV with a header row naming the columns
    ``frequency_hz, xx_real, xx_imag, yy_real, yy_imag`` and optionally ``xy_real, xy_imag,
    yx_real, yx_imag`` (receptance, m/N; the first index the response, the second the force), in
    any order, frequencies increasing, at most :data:`MAX_FRF_ROWS` rows; a relative path is
    relative to the scenario file.  Between its frequencies the receptance is interpolated
    linearly (real and imaginary parts); outside them it is unknown (an error).

Either gives :meth:`ToolDynamicsSpec.receptance`: the 2 x 2 receptance matrix in X/Y at any
frequency, or in a feed frame (x along the feed, y = z x feed) rotated by the feed's angle.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, PrivateAttr, model_validator

from twin.errors import TwinInputError, input_file
from twin.spec import StrictSpec

#: Rows of a measured FRF file at most (a tap test has a few thousand lines).
MAX_FRF_ROWS = 200_000
#: Modes of one tool at most.
MAX_MODES = 50
#: Highest natural frequency of a mode (Hz): far above any tool's (a few kHz to 20 kHz).
MAX_FREQUENCY_HZ = 1e6
#: Lowest natural frequency of a mode (Hz): under any machine structure's.
MIN_FREQUENCY_HZ = 1.0
#: Lightest damping of a mode: under any measured structure's (0.1 %), over which the chatter
#: frequencies' grid (a fraction of the half-power band) stays bounded.
MIN_DAMPING_RATIO = 1e-4
#: The columns a measured FRF file must have, and those it may have besides.
FRF_COLUMNS = ("frequency_hz", "xx_real", "xx_imag", "yy_real", "yy_imag")
FRF_CROSS_COLUMNS = ("xy_real", "xy_imag", "yx_real", "yx_imag")
#: Directions of a mode, and their index in the receptance matrix.
DIRECTIONS = ("x", "y")


class ModeSpec(StrictSpec):
    """One vibration mode of the tool in X or Y."""

    direction: Literal["x", "y"] = Field(description="the machine axis it vibrates along")
    frequency_hz: float = Field(ge=MIN_FREQUENCY_HZ, le=MAX_FREQUENCY_HZ, description="natural frequency (Hz)")
    damping_ratio: float = Field(ge=MIN_DAMPING_RATIO, lt=1.0, description="viscous damping ratio (1)")
    stiffness_N_per_m: float | None = Field(None, ge=1.0, description="modal stiffness (N/m); or modal_mass_kg")
    modal_mass_kg: float | None = Field(None, ge=1e-9, le=1e6, description="modal mass (kg); or stiffness_N_per_m")

    @model_validator(mode="after")
    def _stiffness_or_mass(self):
        if (self.stiffness_N_per_m is None) == (self.modal_mass_kg is None):
            given = "both" if self.stiffness_N_per_m is not None else "neither"
            raise ValueError(f"give stiffness_N_per_m or modal_mass_kg, one of the two ({given} given)")
        return self

    @property
    def omega_rad_s(self) -> float:
        """Natural frequency (rad/s)."""
        return 2.0 * math.pi * self.frequency_hz

    @property
    def stiffness(self) -> float:
        """Modal stiffness (N/m), given or ``m omega_n^2``."""
        if self.stiffness_N_per_m is not None:
            return self.stiffness_N_per_m
        assert self.modal_mass_kg is not None  # the validator's
        return self.modal_mass_kg * self.omega_rad_s**2

    @property
    def mass(self) -> float:
        """Modal mass (kg), given or ``k / omega_n^2``."""
        return self.stiffness / self.omega_rad_s**2


@dataclass(frozen=True)
class MeasuredFrf:
    """A measured receptance table: frequencies (n,) Hz and the matrix (n, 2, 2) m/N."""

    frequency_hz: np.ndarray
    receptance: np.ndarray


def read_frf_csv(path: str | Path, field: str) -> MeasuredFrf:
    """The measured FRF in the CSV ``path`` (the module's format).

    Raises
    ------
    TwinInputError
        Under ``field``: no such file, a missing or unknown column, a value that is not a finite
        number, frequencies not positive and increasing, fewer than 2 or over
        :data:`MAX_FRF_ROWS` rows.
    """
    path = input_file(path, field)
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            reader = csv.DictReader(stream)
            header = [name.strip() for name in reader.fieldnames or []]
            missing = [c for c in FRF_COLUMNS if c not in header]
            if missing:
                raise TwinInputError(field, str(path), f"column(s) {', '.join(missing)} missing (header: {header})")
            unknown = [c for c in header if c not in FRF_COLUMNS + FRF_CROSS_COLUMNS]
            if unknown:
                raise TwinInputError(field, str(path), f"unknown column(s) {', '.join(unknown)}")
            cross = [c for c in FRF_CROSS_COLUMNS if c in header]
            if cross and len(cross) != len(FRF_CROSS_COLUMNS):
                raise TwinInputError(field, str(path), f"give all of {', '.join(FRF_CROSS_COLUMNS)} or none")
            rows: list[list[float]] = []
            for number, row in enumerate(reader, start=2):
                if len(rows) >= MAX_FRF_ROWS:
                    raise TwinInputError(field, str(path), f"over {MAX_FRF_ROWS} rows")
                values = {k.strip(): v for k, v in row.items() if k is not None}
                try:
                    rows.append([float(values[c]) for c in FRF_COLUMNS + tuple(cross)])
                except (TypeError, ValueError):
                    raise TwinInputError(field, str(path), f"line {number}: not a number in {row}") from None
    except UnicodeDecodeError as exc:
        raise TwinInputError(field, str(path), f"not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise TwinInputError(field, str(path), f"cannot be read ({exc.strerror})") from None
    table = np.array(rows, dtype=float).reshape(-1, len(FRF_COLUMNS) + len(cross))
    if len(table) < 2:
        raise TwinInputError(field, str(path), f"{len(table)} row(s): at least 2 frequencies")
    if not np.all(np.isfinite(table)):
        raise TwinInputError(field, str(path), "a value is not finite (nan or inf)")
    freq = table[:, 0]
    if freq[0] <= 0 or np.any(np.diff(freq) <= 0):
        raise TwinInputError(field, str(path), "frequency_hz must be positive and increasing")
    g = np.zeros((len(table), 2, 2), dtype=complex)
    g[:, 0, 0] = table[:, 1] + 1j * table[:, 2]
    g[:, 1, 1] = table[:, 3] + 1j * table[:, 4]
    if cross:
        g[:, 0, 1] = table[:, 5] + 1j * table[:, 6]
        g[:, 1, 0] = table[:, 7] + 1j * table[:, 8]
    return MeasuredFrf(freq, g)


def feed_frame_rotation(feed_angle_rad: float) -> np.ndarray:
    """The matrix (2, 2) taking a vector from the feed frame (x along the feed at
    ``feed_angle_rad`` from the machine's X, y = z x feed) to the machine's X/Y."""
    c, s = math.cos(feed_angle_rad), math.sin(feed_angle_rad)
    return np.array([[c, -s], [s, c]])


class ToolDynamicsSpec(StrictSpec):
    """``[tool.dynamics]``: the tool's modes in X and Y, or its measured tool-tip FRF."""

    modes: list[ModeSpec] = Field(
        default_factory=list, max_length=MAX_MODES, description="modes in X and Y (several per direction allowed)"
    )
    frf_file: str | None = Field(
        None,
        description="measured tool-tip receptance CSV (frequency_hz, xx_real, xx_imag, yy_real, yy_imag"
        "[, xy_real, xy_imag, yx_real, yx_imag], m/N), relative to the scenario file",
    )
    modes_in_run: bool = Field(
        False,
        description="the modes vibrate in the run too: the tool's deflection enters the chip "
        "(twin.machining.cutting; the physics step must resolve the highest mode)",
    )
    _measured: MeasuredFrf | None = PrivateAttr(None)

    @model_validator(mode="after")
    def _modes_or_file(self):
        if bool(self.modes) == (self.frf_file is not None):
            raise ValueError("give modes = [...] or frf_file = '...', one of the two")
        if self.modes_in_run and not self.modes:
            raise ValueError("modes_in_run needs modes = [...]: a measured FRF has no modes to integrate")
        if self.frf_file is not None:
            try:
                self._measured = read_frf_csv(self.frf_file, "frf_file")
            except TwinInputError as exc:  # pydantic names the table; the message the file
                raise ValueError(str(exc)) from None
        return self

    @property
    def measured(self) -> MeasuredFrf | None:
        """The measured FRF table (None for modes)."""
        return self._measured

    def modes_along(self, direction: str) -> list[ModeSpec]:
        """The modes along ``direction`` ("x" or "y")."""
        return [m for m in self.modes if m.direction == direction]

    def is_isotropic(self) -> bool:
        """Whether the receptance is the same along every direction of the XY plane (X and Y
        alike, no cross terms): then it is the same in any feed frame."""
        if self._measured is not None:
            g = self._measured.receptance
            return bool(np.array_equal(g[:, 0, 0], g[:, 1, 1]) and not np.any(g[:, 0, 1]) and not np.any(g[:, 1, 0]))

        def along(direction):
            return sorted((m.frequency_hz, m.damping_ratio, m.stiffness) for m in self.modes_along(direction))

        return along("x") == along("y")

    def frequency_range_hz(self) -> tuple[float, float]:
        """Where the receptance is known (Hz): the measured table's span, or for modes from
        zero to four times the highest natural frequency."""
        if self._measured is not None:
            return float(self._measured.frequency_hz[0]), float(self._measured.frequency_hz[-1])
        return 0.0, 4.0 * max(m.frequency_hz for m in self.modes)

    def receptance(self, frequency_hz: np.ndarray | float, feed_angle_rad: float | None = None) -> np.ndarray:
        """The tool tip's receptance matrix (m/N), shape ``frequency_hz.shape + (2, 2)``.

        Parameters
        ----------
        frequency_hz : array_like
            Frequencies (Hz); for a measured FRF within its range.
        feed_angle_rad : float, optional
            None: in the machine's X/Y.  Else in the feed frame of a feed at this angle from X
            (rad): ``R^T G R`` with ``R`` :func:`feed_frame_rotation`.

        Raises
        ------
        TwinInputError
            A frequency outside a measured FRF's range.
        """
        f = np.asarray(frequency_hz, dtype=float)
        if self._measured is not None:
            table = self._measured
            low, high = table.frequency_hz[0], table.frequency_hz[-1]
            if f.size and (f.min() < low or f.max() > high):
                outside = float(f.min() if f.min() < low else f.max())
                raise TwinInputError("frf_file", self.frf_file, f"{outside:g} Hz is outside its {low:g}-{high:g} Hz")
            g = np.empty((*f.shape, 2, 2), dtype=complex)
            for i in range(2):
                for j in range(2):
                    column = table.receptance[:, i, j]
                    g[..., i, j] = np.interp(f, table.frequency_hz, column.real) + 1j * np.interp(
                        f, table.frequency_hz, column.imag
                    )
        else:
            g = np.zeros((*f.shape, 2, 2), dtype=complex)
            for mode in self.modes:
                r = f / mode.frequency_hz
                i = DIRECTIONS.index(mode.direction)
                g[..., i, i] += 1.0 / (mode.stiffness * (1.0 - r**2 + 2j * mode.damping_ratio * r))
        if feed_angle_rad is None:
            return g
        rot = feed_frame_rotation(feed_angle_rad)
        return rot.T @ g @ rot
