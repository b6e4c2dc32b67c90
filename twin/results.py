"""What the API returns for each command, typed: the command line prints their ``summary``
(``--json``) or formats it, and writes their files (``--plots``, ``--rrd``, ``--out``) through them.

:class:`Run` and :class:`Sweep` (``twin run``, ``twin sweep``), :class:`Program` (``twin gcode``),
:class:`Frf` (``twin frf``), :class:`Calibration` (``twin calibrate``), :class:`Tuning` (``twin
tune``) and :class:`Fidelity` (``twin fidelity``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from twin.errors import RunInterrupted, SimulationDiverged, TwinInputError

if TYPE_CHECKING:  # the heavy modules load on first use, not with `import twin`
    import pandas as pd
    import pyarrow as pa

    from twin.commissioning.boundary import MarginCheck
    from twin.commissioning.calibration import CalibrationReport
    from twin.commissioning.frf import FrfMeasurement, FrfSettings
    from twin.gcode.moves import Move
    from twin.gcode.report import PlannedSummary
    from twin.outcome import RunOutcome
    from twin.records import LineStability, RunRecords
    from twin.sampling import SamplePlan
    from twin.scenario import Scenario
    from twin.sim.runner import RunResult


@dataclass
class Run:
    """One closed-loop run.

    Attributes
    ----------
    scenario : twin.scenario.Scenario
    outcome : twin.outcome.RunOutcome
        The run and what was computed from its motion: with a part program its warnings, with
        a stock the part it cut and its inspection.
    """

    scenario: Scenario
    outcome: RunOutcome

    @property
    def result(self) -> RunResult:
        """The raw arrays (SI units) at the recorded ticks, and metrics over every tick."""
        return self.outcome.run

    @property
    def stopped(self) -> SimulationDiverged | RunInterrupted | None:
        """What stopped a run early (see :func:`twin.api.run`'s ``keep_partial``); None for a
        run that went to its end."""
        return self.outcome.stopped

    @property
    def status(self) -> str:
        """``ok``, or ``diverged`` / ``interrupted`` for a run that stopped early."""
        if self.stopped is None:
            return "ok"
        return "diverged" if isinstance(self.stopped, SimulationDiverged) else "interrupted"

    @property
    def summary(self) -> dict:
        """What ``twin run --json`` prints: scenario, machine, status, completed ticks, max and
        RMS tracking error per axis (µm), the largest cutting force (N), the contour error for
        2-D paths (µm) and the loop that ran."""
        from twin.metrics import tracking_summary

        done = self.result.info["completed_ticks"]
        return {
            "scenario": self.scenario.name,
            "machine": self.scenario.machine,
            "status": self.status,
            **({} if self.stopped is None else {"sim_time_s": self.stopped.sim_time_s}),
            "completed_ticks": done,
            **(tracking_summary(self.outcome, self.records) if done else {}),
            "loop": self.result.info["loop"],
        }

    @cached_property
    def records(self) -> RunRecords:
        """The run's per-line rows, warnings, inspected features and chatter, typed
        (:func:`twin.metrics.run_records`; :attr:`summary` gives them as JSON); none for a run
        that completed no tick."""
        from twin.metrics import run_contour_error, run_records
        from twin.records import RunRecords

        if not self.result.info["completed_ticks"]:
            return RunRecords()
        return run_records(self.outcome, run_contour_error(self.result))

    def lines_to_parquet(self, path: str | Path) -> Path:
        """Write the per-line table of a G-code run (:attr:`records`' ``lines``, each row's
        columns :meth:`twin.records.LineRow.to_columns`: the per-axis tracking errors as
        ``max_tracking_error_um_<axis>``, a cutting line's chatter check as ``stability_<key>``
        with ``stability_stable_rpm_low`` and ``_high``, its chatter in the run as ``chatter``,
        ``chatter_hz``, ``chatter_indicator``, ``chatter_threshold`` and ``chatter_windows``) to
        a Parquet file.

        Raises
        ------
        TwinInputError
            The run has no G-code reference.
        """
        import pyarrow as pa
        import pyarrow.parquet as pq

        rows = self.records.lines
        if not rows:
            raise TwinInputError("lines", str(path), "the run has no G-code reference: no per-line table")
        flat = [row.to_columns() for row in rows]
        columns = list(dict.fromkeys(key for row in flat for key in row))  # every row's, in order
        pq.write_table(pa.Table.from_pylist([{c: row.get(c) for c in columns} for row in flat]), Path(path))
        return Path(path)

    def to_pandas(self) -> pd.DataFrame:
        """The run's named series as a ``pandas.DataFrame`` indexed by simulated time (s), one
        column per series of the recording, named ``<path> (<unit>)``: ``reference/x (mm)``,
        ``actual/x (mm)``, ``error/x (µm)``, ``control/x (V)``, ``force/drive/x (N)`` or
        ``torque/drive/x (N m)``, ``force/cutting/x (N)``, ``joints/x/motor/angle (rad)``..."""
        import pandas as pd

        from twin.series import named_series

        columns = {f"{s.path} ({s.unit})": s.values for s in named_series(self.result)}
        return pd.DataFrame(columns, index=pd.Index(self.result.t_s, name="time (s)"))

    def record(self, path: str | Path) -> Path:
        """Write the Rerun recording (``.rrd``) of the run and return its path."""
        from twin.recording import record

        path = Path(path)
        record(self.outcome, path)
        return path

    def write_part(self, folder: str | Path) -> list[Path]:
        """Write the virtual part of a run with a stock into ``folder`` (created if missing):
        ``<scenario>_part.stl``, the actual part's closed mesh (mm), and
        ``<scenario>_part_map.parquet``, the nominal and actual height maps and their
        difference by cell (:mod:`twin.machining.part_map`); their paths.

        Raises
        ------
        TwinInputError
            The run has no virtual part (no stock, or it stopped early).
        """
        part = self.outcome.part
        if part is None or part.maps is None:
            raise TwinInputError("part", str(folder), "the run has no virtual part: give [stock] and run to the end")
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        name = self.scenario.name
        return [
            part.maps.to_stl(folder / f"{name}_part.stl"),
            part.maps.to_parquet(folder / f"{name}_part_map.parquet"),
        ]

    def plots(self, folder: str | Path) -> list[Path]:
        """Write the PNG plots of ``twin run --plots`` into ``folder``; their paths."""
        from twin.plots import write_plots

        return write_plots(self.outcome, Path(folder), self.scenario.name)


@dataclass
class Sweep:
    """A finished (or interrupted) sweep.

    Attributes
    ----------
    summary : dict
        What ``twin sweep --json`` prints: bands, the worst case, certificates, counts.
    out : Path
        The Parquet dataset folder, one row per sample.
    table : pyarrow.Table
        Its rows, as read back.
    plan : twin.sampling.SamplePlan
        The samples' plan.
    axes : tuple of str
        The machine's axes.
    interrupted : bool
        Whether Ctrl-C stopped it (``resume=True`` with the same ``out`` completes it).
    """

    summary: dict
    out: Path
    table: pa.Table
    plan: SamplePlan
    axes: tuple[str, ...]
    interrupted: bool = False

    def to_pandas(self) -> pd.DataFrame:
        """Every sample's row (its parameters, status and metrics) as a ``pandas.DataFrame``."""
        return self.table.to_pandas()

    def plots(self, folder: str | Path) -> list[Path]:
        """Write the PNGs of ``twin sweep --plots`` into ``folder``; their paths."""
        from twin.sweeps.summary import write_sweep_plots

        return write_sweep_plots(self.table, self.plan, self.axes, Path(folder))


@dataclass
class Program:
    """A part program as read, and planned for a machine (``twin gcode FILE [--machine M]``).

    Attributes
    ----------
    file : str
    moves : list of twin.gcode.reader.Move
        The moves as LinuxCNC reads them.
    planned : twin.gcode.report.PlannedSummary or None
        With a machine: the plan's cycle time (s), feed-only time, limits and largest values per
        axis, path deviation and warnings against the machine
        (:func:`twin.gcode.report.planned_summary`).
    """

    file: str
    moves: list[Move]
    planned: PlannedSummary | None = None

    @property
    def summary(self) -> dict:
        """What ``twin gcode --json`` prints: ``file``, ``moves`` (line, kind, end_mm, arcs' plane,
        center_mm and turns, feed, spindle) and, with a machine, ``planned``."""
        out: dict[str, Any] = {"file": self.file, "moves": [m.as_dict() for m in self.moves]}
        if self.planned is not None:
            out["planned"] = self.planned.to_json()
        return out


@dataclass
class Frf:
    """An axis's frequency response measured on the twin (``twin frf``).

    Attributes
    ----------
    measurement : twin.commissioning.frf.FrfMeasurement
        The lines (Hz), magnitude (dB), phase (deg) and coherence, the model's, the resonances
        and anti-resonances found, the settings and the simulated experiment (``run``).
    nut_stiffness : dict or None
        On a machine file whose stiffness depends on the nut's position: the position (m) and
        the axial (N/m) and torsional (N m/rad) stiffness there.
    """

    measurement: FrfMeasurement
    nut_stiffness: dict | None = None

    @property
    def machine(self) -> str:
        """The machine or machine file measured."""
        return self.measurement.machine

    @property
    def settings(self) -> FrfSettings:
        """What the measurement did."""
        return self.measurement.settings

    @property
    def run(self) -> RunResult:
        """The simulated experiment."""
        return self.measurement.run

    @cached_property
    def summary(self) -> dict:
        """What ``twin frf --json`` prints (:meth:`twin.commissioning.frf.FrfMeasurement.to_json`)."""
        return self.measurement.to_json()

    def to_pandas(self) -> pd.DataFrame:
        """The measured and the model's response by frequency (Hz): ``magnitude_db``,
        ``phase_deg``, ``coherence``, ``model_magnitude_db``, ``model_phase_deg``."""
        import pandas as pd

        m = self.measurement
        index = pd.Index(m.frequency_hz, name="frequency_hz")
        columns = {
            "magnitude_db": m.magnitude_db,
            "phase_deg": m.phase_deg,
            "coherence": m.coherence,
            "model_magnitude_db": m.model_magnitude_db,
            "model_phase_deg": m.model_phase_deg,
        }
        return pd.DataFrame(columns, index=index)

    def write_bode(self, path: str | Path) -> Path:
        """The Bode plot (PNG) of the measured response beside the model's, with the coherence."""
        from twin.commissioning.frf import write_bode

        write_bode(self.measurement, path)
        return Path(path)

    def record(self, path: str | Path) -> Path:
        """The experiment as a Rerun recording (``.rrd``)."""
        from twin.recording import record

        record(self.run, Path(path))
        return Path(path)


@dataclass
class StabilityLobes:
    """The stability lobes of a scenario's tool and its program's lines on them (``twin lobes``).

    Attributes
    ----------
    scenario : str
    summary : dict
        What ``twin lobes --json`` prints: ``lobes`` per method (a list of ``spindle_rpm``,
        ``critical_depth_mm``, ``chatter_hz``), their ``lowest``, the ``seconds`` each took, the
        cut, and with a program ``lines`` with each line's ``stability``.
    """

    scenario: str
    summary: dict

    def to_pandas(self) -> pd.DataFrame:
        """The lobes by spindle speed (rpm): ``<method>_critical_depth_mm`` and
        ``<method>_chatter_hz`` for each method computed."""
        import pandas as pd

        frames = []
        for method, rows in self.summary["lobes"].items():
            frame = pd.DataFrame(rows).set_index("spindle_rpm")
            frames.append(frame.add_prefix(f"{method}_"))
        return pd.concat(frames, axis=1)

    @property
    def stability_checks(self) -> list[LineStability]:
        """With a program: each cutting line's chatter check, in program order (empty without)."""
        from twin.records import LineStability

        return [LineStability.from_json(row["stability"]) for row in self.summary.get("lines", [])]

    def write_png(self, path: str | Path) -> Path:
        """The lobes, the program's lines on them and the chatter frequency beneath (PNG)."""
        from twin.commissioning.lobes import write_lobes_png

        return write_lobes_png(self.summary, path)


@dataclass
class Calibration:
    """Machine parameters fitted to a measured trace or FRF (``twin calibrate``).

    Attributes
    ----------
    report : twin.commissioning.calibration.CalibrationReport
        The machine and trace, the ``fitted`` values, their standard errors, the ``nominal``
        ones, the fit index before and after, the solver's report.
    """

    report: CalibrationReport

    @property
    def machine(self) -> str:
        """The machine or machine file calibrated."""
        return self.report.machine

    @property
    def trace(self) -> str:
        """The measured trace."""
        return self.report.trace

    @property
    def summary(self) -> dict:
        """What ``twin calibrate --json`` prints
        (:meth:`twin.commissioning.calibration.CalibrationReport.to_json`)."""
        return self.report.to_json()

    @property
    def fitted(self) -> dict[str, float]:
        """The fitted parameters by symbol, in the machine's units."""
        return self.report.fitted

    def write_machine_file(self, path: str | Path) -> Path:
        """The calibrated machine file (TOML): the machine file with the fitted values, a comment
        naming the trace they come from.

        Raises
        ------
        TwinInputError
            The machine is a bundled one, not a machine file.
        """
        from twin.machines import get_machine
        from twin.machines.datasheet import DatasheetMachine
        from twin.machines.machine_file import machine_file_text

        check_calibrated_output(self.machine, "path", path)
        machine = get_machine(self.machine)
        assert isinstance(machine, DatasheetMachine)  # a machine file, checked above
        note = f"calibrated by twin calibrate against {self.trace}: " + ", ".join(
            f"{s} = {v:.6g}" for s, v in self.fitted.items()
        )
        Path(path).write_text(machine_file_text(machine.spec, self.fitted, note), encoding="utf-8")
        return Path(path)


def check_calibrated_output(machine: str, field: str, path: str | Path) -> None:
    """Refuse to write a calibrated machine file for ``machine`` unless it is a machine file.

    Raises
    ------
    TwinInputError
        ``field`` = ``path``: ``machine`` is a bundled machine.
    """
    from twin.machines import is_machine_file

    if not is_machine_file(machine):
        raise TwinInputError(field, str(path), "writes a machine file: calibrate a machine file (FILE.toml)")


@dataclass
class Tuning:
    """Each axis's tuned position P / velocity PI cascade (``twin tune``).

    Attributes
    ----------
    machine : str
        The machine, or a machine file's absolute path (what the scenario it writes names).
    summary : dict
        What ``twin tune --json`` prints: the control period, the feedback, per axis the gains,
        the margins and bandwidths; ``verification`` once :meth:`verify` has run.
    margin_check : list of MarginCheck
        Each gain's cascade margin beside the twin's boundaries once :meth:`verify_margins` has
        run (empty before).
    """

    machine: str
    summary: dict
    margin_check: list[MarginCheck] = field(default_factory=list)

    def verify(self) -> dict:
        """Run the tuned cascade on the twin (a 1 mm step, a circle) and add what it measured to
        :attr:`summary` as ``verification``; returns it."""
        import tempfile

        from twin.commissioning.tuning import verify

        with tempfile.TemporaryDirectory() as folder:
            self.summary["verification"] = verify(self.summary, self.machine, Path(folder))
        return self.summary["verification"]

    def verify_margins(
        self,
        gains: tuple[str, ...] = ("kp_pos", "kp_vel", "ki_vel"),
        conditions: tuple[str, ...] | None = None,
    ) -> list[MarginCheck]:
        """Each axis's cascade margins beside the twin's own stability boundaries, bisected for
        each of ``gains`` (:func:`twin.commissioning.boundary.verify_margins`) under the named
        conditions (default all of :data:`twin.commissioning.boundary.CONDITIONS`: ``twin`` as
        run, ``without_coulomb``, ``like_for_like``, the linear model's assumptions); keeps them
        as :attr:`margin_check`, adds them to :attr:`summary` as ``margin_check`` and returns them."""
        from twin.commissioning.boundary import CONDITIONS, verify_margins

        chosen = {name: CONDITIONS[name] for name in (conditions or CONDITIONS)}
        self.margin_check = verify_margins(self.summary, self.machine, gains, chosen)
        self.summary["margin_check"] = [row.to_json() for row in self.margin_check]
        return self.margin_check

    def scenario_text(self, reference: str = "circle") -> str:
        """The tuned cascade as a scenario (TOML) on a 10 mm circle (or a 1 mm ``step``)."""
        from twin.commissioning.tuning import scenario_text

        return scenario_text(self.summary, self.machine, reference)


@dataclass
class Fidelity:
    """Each machine's twin against its transfer function (``twin fidelity``).

    Attributes
    ----------
    cases : list of dict
        Per case: time NRMSE, FRF errors (dB, deg), gear slip (µm) and ``pass``.
    """

    cases: list[dict]

    @property
    def summary(self) -> list[dict]:
        """What ``twin fidelity --json`` prints: the cases."""
        return self.cases

    @property
    def failed(self) -> list[str]:
        """The cases that miss a target."""
        return [c["case"] for c in self.cases if not c["pass"]]

    def to_pandas(self) -> pd.DataFrame:
        """One row per case, by its name."""
        import pandas as pd

        return pd.DataFrame(self.cases).set_index("case")
