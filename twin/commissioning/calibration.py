"""Calibration: fit named machine parameters to a measured time trace or FRF.

A time trace (CSV or Parquet) has ``time_s`` (uniform, increasing) and per axis ``u_<axis>_V``
(the drive input) and ``pos_<axis>_m`` (the encoder position); an axis without columns gets zero
input and is not compared. The fit is output-error least squares (``scipy.optimize.least_squares``,
trust-region reflective, finite-difference Jacobian) through the twin itself: each evaluation
replays the measured input open loop on the MuJoCo model built with the trial values, so
nonlinear terms (Coulomb friction) are fitted as well as the linear ones.  It runs in two
stages.  The first fits the velocity (the position's difference per sample): an open loop
integrates, so one sticking of Coulomb friction shifts the position for the rest of the record
and the position's cost is rugged (on a hidden variant of ``mid_size_xy`` its solve stopped at
-7.9 % mass, +3.4 % stiffness, in one of several local minima between the nominal and the
truth), while the velocity's error stays where it arose and its cost is smooth.  The second
fits the position from there: the measurement's own noise (the encoder's) is white on the
position, where least squares is efficient and its standard errors hold.  The residual at the
end is compared with the trace's noise (:func:`noise_floor`): a fit far above it says so.

A measured FRF (``frequency_hz``, ``magnitude_db``, ``phase_deg``, one axis: ``--axis``) is fitted
through the machine's transfer function to the sensor it was measured at (``--sensor``: the
table's or the motor's), with its delay, the residual the complex logarithm of model over
measurement (log-magnitude and phase in radians).

Standard errors come from the Jacobian at the solution: cov = s^2 (J^T J)^-1 with s^2 the
residual variance (``statistical_errors``), and, for a time trace, the model's own error beside
it in quadrature (``model_errors``): MuJoCo's Euler integrator is first order in the physics
step h, so the estimate at h lies about twice its shift with the step halved from the step's
limit (the shift is one Gauss-Newton step from the residual's change at h / 2).  Against an
independent exact-ZOH model the noise's errors alone were 20-150 times too small (heavy_xy X's
mass +0.16 % with 0.001 %).  A parameter whose error exceeds :data:`POORLY_DETERMINED` of its
value is named in ``poorly_determined``; a parameter the data cannot identify (a Jacobian column near zero or
nearly dependent on the others: relative standard error above 50 %) is named, and the fit
keeps its nominal value: every such parameter (a combination's partners together) is held at
nominal and the others are fitted again without them.  ``solver`` reports whether the solve
converged (scipy's termination, the evaluations out of :data:`MAX_EVALUATIONS`, the final
first-order optimality); standard errors are given only for a converged fit.  A trial the
twin diverges on is a rejected step (a huge residual), counted in ``rejected_diverged``.
The fit index is Sabau 2022's NRMSE fit, 100 (1 - ||y - y_model|| /
||y - mean(y)||), before (nominal values) and after.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from scipy import optimize, signal
from tqdm import tqdm

from controllers.blocks import open_loop
from twin.commissioning.frf import (
    SENSORS,
    FrfSettings,
    excitation_signal,
    model_modes,
    sample_period,
    sensor_plant,
)
from twin.errors import SimulationDiverged, TwinInputError, input_file
from twin.machines import BuiltMachine, build, get_machine
from twin.metrics import fit_index
from twin.references import Step
from twin.sim.runner import simulate
from twin.spec import axes_indices

#: Fewest samples and seconds a time trace must hold.
MIN_SAMPLES = 200
MIN_DURATION_S = 0.05
#: Most samples a trace may hold (memory and time stay bounded: each evaluation is a run).
MAX_SAMPLES = 2_000_000
#: Relative standard error above which a parameter counts as not identifiable.
MAX_RELATIVE_ERROR = 0.5
#: Correlation of two estimates over which a parameter not determined is named with the other.
MAX_CORRELATION = 0.95
#: Most model evaluations of one least-squares solve (finite differences included).
MAX_EVALUATIONS = 200
#: Multiples of a fitted stiffness's nominal value the solve also starts from.
STIFFNESS_STARTS = (0.5, 0.7, 1.4, 2.0)
#: Multiples of the trace's noise (:func:`noise_floor`) a fit's residual may reach: a white
#: residual's RMS over a few thousand samples is known within about 1 %, the noise's estimate
#: within a few; a fit 10 % above it has not reached its minimum (or the model misses something).
NOISE_FLOOR_FACTOR = 1.2
#: The model's own error on an estimate, in multiples of its shift when the physics step is
#: halved: MuJoCo's Euler integrator is first order in the step (its explicit tendon dampers
#: shift a mode by about 0.7 zeta omega h, its position leads by half a step), so the estimate
#: at h lies twice that shift from the step's limit.
INTEGRATOR_ORDER_FACTOR = 2.0
#: A fitted parameter whose standard error (the model's own error included) exceeds this
#: fraction of its value is named as poorly determined (the torsion of mid_size_xy, its mode
#: at 650 Hz on a 500 Hz PRBS, came back 12 % low, +-9 %).
POORLY_DETERMINED = 0.05
#: Input lines within this many dB of the input's strongest count as excited.
EXCITED_WITHIN_DB = 20.0
#: A stiffness is seen through its mode: the input must reach this multiple of the mode.
EXCITE_BEYOND_MODE = 1.5
#: The residual of a trial the twin diverges on (each entry; measured ones are about 1).
DIVERGED_RESIDUAL = 1e6


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """A CSV or Parquet file's columns as float arrays.

    Raises
    ------
    TwinInputError
        A missing file, another suffix, or a file that cannot be parsed.
    """
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    path = input_file(path, "--trace")
    try:
        if path.suffix == ".parquet":
            table = pq.read_table(path)
        elif path.suffix == ".csv":
            table = pacsv.read_csv(path)
        else:
            raise TwinInputError("--trace", str(path), "must be a .csv or .parquet file")
    except (OSError, ValueError) as exc:
        if isinstance(exc, TwinInputError):
            raise
        raise TwinInputError("--trace", str(path), f"cannot be read: {str(exc).splitlines()[0]}") from None
    out = {}
    for name in table.column_names:
        try:
            out[name] = np.asarray(table.column(name).to_numpy(zero_copy_only=False), float)
        except (TypeError, ValueError):
            raise TwinInputError(f"--trace column {name}", str(table.column(name).type), "must be numbers") from None
    return out


#: The largest magnitude a trace's column may hold, by the column's unit (the name's end): a
#: drive's input (V), a position within any machine's travel (m), a record's time (s), a
#: frequency (Hz), a gain (dB), a phase (deg) and a coherence.
TRACE_RANGES = {"_V": 1e3, "_m": 10.0, "_s": 1e6, "_hz": 1e6, "_db": 400.0, "_deg": 1e6, "coherence": 1.0}


def _all_finite(columns: dict[str, np.ndarray], names: list[str]) -> None:
    """Refuse the first NaN or inf of the columns ``names``, or a value beyond the column's
    range (:data:`TRACE_RANGES`), naming its column, row and value."""
    for name in names:
        bad = np.flatnonzero(~np.isfinite(columns[name]))
        if bad.size:
            raise TwinInputError(f"--trace column {name}", f"row {bad[0]}", "is not a finite number (NaN or inf)")
        limit = next((v for end, v in TRACE_RANGES.items() if name.endswith(end)), math.inf)
        beyond = np.flatnonzero(np.abs(columns[name]) > limit)
        if beyond.size:
            row = int(beyond[0])
            raise TwinInputError(
                f"--trace column {name}", f"{columns[name][row]:g} at row {row}", f"beyond +-{limit:g}, out of range"
            )


def time_trace(columns: dict[str, np.ndarray], axes: list[str]) -> tuple[float, np.ndarray, np.ndarray, list[int]]:
    """Check a time trace: its sample period (s), inputs (n, axes) in V, positions (n, axes) in m
    and the indices of the axes it measures.

    Raises
    ------
    TwinInputError
        One line per defect: missing ``time_s``, an unknown or unpaired column, too short,
        NaN, time not increasing or not uniform, an axis that never moves.
    """
    if "time_s" not in columns:
        raise TwinInputError("--trace", sorted(columns), "needs a time_s column (or an FRF: frequency_hz, ...)")
    expected = {"time_s"} | {f"u_{a}_V" for a in axes} | {f"pos_{a}_m" for a in axes}
    unknown = sorted(set(columns) - expected)
    if unknown:
        raise TwinInputError(
            "--trace column", unknown[0], f"unknown (columns: time_s, u_<axis>_V, pos_<axis>_m; axes {axes})"
        )
    t = columns["time_s"]
    if len(t) < MIN_SAMPLES or (len(t) > 1 and t[-1] - t[0] < MIN_DURATION_S):
        raise TwinInputError(
            "--trace", f"{len(t)} samples", f"too short: needs {MIN_SAMPLES} samples and {MIN_DURATION_S} s"
        )
    if len(t) > MAX_SAMPLES:
        raise TwinInputError("--trace", f"{len(t)} samples", f"too long: at most {MAX_SAMPLES}")
    _all_finite(columns, list(columns))
    steps = np.diff(t)
    if (steps <= 0).any():
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise TwinInputError("--trace column time_s", f"row {row}", "time must increase from row to row")
    dt = float(np.median(steps))
    if np.abs(steps - dt).max() > 1e-3 * dt:
        raise TwinInputError(
            "--trace column time_s", f"step {np.abs(steps - dt).max() + dt:g} s", "sampling must be uniform"
        )
    measured = [i for i, a in enumerate(axes) if f"pos_{a}_m" in columns]
    if not measured:
        raise TwinInputError("--trace", sorted(columns), f"needs a pos_<axis>_m column for one of the axes {axes}")
    u = np.zeros((len(t), len(axes)))
    y = np.zeros((len(t), len(axes)))
    for i, a in enumerate(axes):
        if f"u_{a}_V" in columns:
            u[:, i] = columns[f"u_{a}_V"]
        if f"pos_{a}_m" in columns:
            y[:, i] = columns[f"pos_{a}_m"]
            if np.ptp(y[:, i]) < 1e-7:
                raise TwinInputError(
                    f"--trace column pos_{a}_m", f"range {np.ptp(y[:, i]):g} m", "the axis never moves"
                )
    inputs = [f"u_{a}_V" for a in axes if f"u_{a}_V" in columns]
    if not any(np.ptp(columns[name]) > 0 for name in inputs):
        raise TwinInputError("--trace", inputs, "the input never changes (or is missing): nothing excites the axes")
    return dt, u, y, measured


def replay(bm: BuiltMachine, dt: float, u: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """The twin's positions (m) under the measured input ``u`` (V), played open loop at ``dt``
    from rest at the trace's first positions ``y0``."""
    names = [a.name for a in bm.axes]
    run = simulate(
        bm, open_loop(u, dt, names), Step(0.0, n_axes=len(names)), len(u) * dt, dt, progress=False, record_every=1
    )
    return run.table_position_m() - run.table_position_m()[0] + y0


def _fit_parameters(machine, fit: list[str]) -> list[str]:
    if not fit:
        raise TwinInputError("--fit", "", "name one parameter or more: SYM,SYM")
    for name in fit:
        if name not in machine.parameters:
            raise TwinInputError(
                "--fit", name, f"not a parameter of {machine.name} (its: {', '.join(machine.parameters)})"
            )
        if math.isinf(machine.parameters[name].value):
            raise TwinInputError("--fit", name, "is infinite (rigid): give it a finite value with --set first")
    if len(set(fit)) != len(fit):
        raise TwinInputError("--fit", ",".join(fit), "names a parameter twice")
    return fit


@dataclass(frozen=True)
class TimeTrace:
    """A measured time trace, checked (:func:`time_trace`), and how a fit compares the twin with it.

    Attributes
    ----------
    sample_period_s : float
    inputs_V : numpy.ndarray
        (samples, axes): the drive inputs (V), zero on an axis without a column.
    positions_m : numpy.ndarray
        (samples, axes): the encoder positions (m).
    measured : list of int
        The axes the trace measures.
    noise_floor_m : float
        The positions' white noise (m RMS, :func:`noise_floor`).
    """

    sample_period_s: float
    inputs_V: np.ndarray
    positions_m: np.ndarray
    measured: list[int]
    noise_floor_m: float

    @property
    def target(self) -> np.ndarray:
        """The measured positions (m): (samples, measured axes)."""
        return self.positions_m[:, self.measured]

    def model(self, bm: BuiltMachine) -> np.ndarray:
        """The twin's positions (m) on the measured axes under the trace's input (:func:`replay`)."""
        return replay(bm, self.sample_period_s, self.inputs_V, self.positions_m[0])[:, self.measured]

    def residual(self, model: np.ndarray) -> np.ndarray:
        """The position's error, in units of the measured positions' standard deviation."""
        return (model - self.target).ravel() / np.std(self.target)

    def basin_residual(self, model: np.ndarray) -> np.ndarray:
        """The velocity's error (the positions' difference per sample), in units of the measured
        velocity's standard deviation: the first stage's (see the module docstring)."""
        measured_velocity = np.diff(self.target, axis=0) / self.sample_period_s
        velocity = np.diff(model, axis=0) / self.sample_period_s
        return (velocity - measured_velocity).ravel() / np.std(measured_velocity)

    def at_noise_floor(self, solution: optimize.OptimizeResult) -> bool:
        """Whether a velocity fit's residual lies within :data:`NOISE_FLOOR_FACTOR` of the
        velocity's noise (the position's, differenced)."""
        measured_velocity = np.diff(self.target, axis=0) / self.sample_period_s
        velocity_floor = math.sqrt(2.0) * self.noise_floor_m / self.sample_period_s
        rms = float(np.sqrt(np.mean(solution.fun**2))) * np.std(measured_velocity)
        return bool(rms <= NOISE_FLOOR_FACTOR * velocity_floor)


@dataclass(frozen=True)
class MeasuredFrf:
    """A measured FRF, checked (:func:`measured_frf`), and how a fit compares the model with it.

    Attributes
    ----------
    frequency_hz : numpy.ndarray
    response : numpy.ndarray
        The complex response (m/V) on those lines.
    axis : int
        The index of the axis it was measured on.
    sensor : {"motor", "table"}
        The sensor it was measured at.
    """

    frequency_hz: np.ndarray
    response: np.ndarray
    axis: int
    sensor: str

    @property
    def target(self) -> np.ndarray:
        """The measured response (m/V)."""
        return self.response

    def model(self, bm: BuiltMachine) -> np.ndarray:
        """The machine's transfer function to the sensor on the measured lines, with its delay."""
        import control

        g = sensor_plant(bm, self.axis, self.sensor)
        s = 2j * math.pi * self.frequency_hz
        return control.tf(list(g.num), list(g.den))(s) * np.exp(-s * bm.delay_s)

    def residual(self, model: np.ndarray) -> np.ndarray:
        """The complex logarithm of model over measurement: log-magnitude and phase (rad, wrapped
        to +-pi) side by side."""
        r = np.log(model / self.response)
        r = r.real + 1j * np.angle(np.exp(1j * r.imag))
        return np.concatenate([r.real, r.imag])

    def basin_residual(self, model: np.ndarray) -> np.ndarray:
        """An FRF's fit has one stage: its :meth:`residual`."""
        return self.residual(model)

    def at_noise_floor(self, solution: optimize.OptimizeResult) -> bool:
        """Never: an FRF's noise is not known, so every start is tried."""
        return False


@dataclass(frozen=True)
class CalibrationProblem:
    """A fit, checked and ready to :func:`solve` (build it with :meth:`from_inputs`).

    Attributes
    ----------
    machine : str
    trace : str
        The measured trace's path.
    fit : list of str
        The parameters fitted (symbols).
    parameters : dict
        Every parameter's value before the fit (symbol: value; the overrides in).
    nominal : numpy.ndarray
        The fitted parameters' values before the fit.
    scale : numpy.ndarray
        Each fitted parameter's unit in the solve (its nominal magnitude, 1 for zero).
    lower, upper : numpy.ndarray
        The bounds of the solve (in units of the scale): physical signs and the machine's ranges.
    stiffnesses : numpy.ndarray
        Which fitted parameters are stiffnesses (bool): the solve starts from more values of them.
    axes : list of str
        The machine's axes.
    timestep_s : float or None
        The physics step of the fit's twin runs (None: the machine's).
    physics_step_s : float
        That step's value (s).
    data : TimeTrace or MeasuredFrf
    """

    machine: str
    trace: str
    fit: list[str]
    parameters: dict[str, float]
    nominal: np.ndarray
    scale: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    stiffnesses: np.ndarray
    axes: list[str]
    timestep_s: float | None
    physics_step_s: float
    data: TimeTrace | MeasuredFrf

    @classmethod
    def from_inputs(
        cls,
        machine: str,
        trace: str | Path,
        fit: list[str],
        *,
        overrides: dict[str, float] | None = None,
        axis: str = "x",
        sensor: str = "table",
        timestep_s: float | None = None,
    ) -> CalibrationProblem:
        """The fit of ``fit`` (parameter symbols) on ``machine`` (with ``overrides``) to the
        ``trace`` (a time trace, or an FRF measured on ``axis`` at ``sensor``), its twin at the
        physics step ``timestep_s`` (default the machine's), checked.

        Raises
        ------
        TwinInputError
            A bad machine, parameter, file or column (one line).
        """
        if sensor not in SENSORS:
            raise TwinInputError("--sensor", sensor, f"must be one of {', '.join(SENSORS)}")
        spec = get_machine(machine)
        fit = _fit_parameters(spec, fit)
        base = spec.resolve(overrides)
        bm0 = build(machine, overrides, timestep_s)
        names = [a.name for a in bm0.axes]
        axes_indices([axis], names, "--axis")  # an FRF's axis; a time trace's axes are its columns
        columns = read_table(trace)
        nominal = np.array([base[s] for s in fit])
        scale = np.where(nominal != 0, np.abs(nominal), 1.0)
        lower = np.array(
            [1e-6 if spec.parameters[s].positive else 0.0 if spec.parameters[s].nonnegative else -np.inf for s in fit]
        )
        # within each parameter's physical range too (a machine file's): a trial beyond it is refused
        ranges = [spec.parameters[s].bounds for s in fit]
        lower = np.maximum(lower, [-np.inf if r is None else r.low for r in ranges] / scale)
        upper = np.array([np.inf if r is None else r.high for r in ranges]) / scale
        data: TimeTrace | MeasuredFrf
        if "frequency_hz" in columns:
            data = measured_frf(columns, names, axis, sensor)
        else:
            dt, u, y, measured = time_trace(columns, names)
            substeps = dt / bm0.model.opt.timestep
            if abs(substeps - round(substeps)) > 1e-6 or round(substeps) < 1:
                raise TwinInputError(
                    "--trace column time_s",
                    f"step {dt:g} s",
                    f"must be a multiple of the timestep {bm0.model.opt.timestep:g} s",
                )
            floor = noise_floor(y[:, measured], np.array(bm0.encoder_resolution_m)[measured])
            data = TimeTrace(dt, u, y, measured, floor)
        return cls(
            machine=machine,
            trace=str(trace),
            fit=fit,
            parameters=base,
            nominal=nominal,
            scale=scale,
            lower=lower,
            upper=upper,
            stiffnesses=np.array([spec.parameters[s].infinite for s in fit]),
            axes=names,
            timestep_s=timestep_s,
            physics_step_s=bm0.model.opt.timestep,
            data=data,
        )

    @property
    def kind(self) -> Literal["time", "frf"]:
        """``time`` for a time trace, ``frf`` for a measured FRF."""
        return "time" if isinstance(self.data, TimeTrace) else "frf"

    @property
    def start(self) -> np.ndarray:
        """Where the solve starts (units of the scale): the nominal values, one on its low bound
        moved inside."""
        return np.minimum(np.maximum(self.nominal / self.scale, self.lower + 0.01), self.upper)

    def values(self, x: np.ndarray) -> dict[str, float]:
        """All parameter values with the fitted ones at ``x`` (in units of their scale)."""
        return {**self.parameters, **dict(zip(self.fit, (x * self.scale).tolist()))}

    def model(self, x: np.ndarray, *, halved: bool = False) -> np.ndarray:
        """The twin's (or the model's) response to the data with the fitted parameters at ``x``,
        at the fit's physics step, or half of it (``halved``: the model's own error)."""
        step = self.physics_step_s / 2 if halved else self.timestep_s
        return self.data.model(build(self.machine, self.values(x), step))

    def residual(self, x: np.ndarray, *, halved: bool = False) -> np.ndarray:
        """The fit's residual at ``x`` (the position's for a time trace)."""
        return self.data.residual(self.model(x, halved=halved))

    def basin_residual(self, x: np.ndarray) -> np.ndarray:
        """The first stage's residual at ``x`` (the velocity's for a time trace)."""
        return self.data.basin_residual(self.model(x))


@dataclass(frozen=True)
class NoiseComparison:
    """A time trace fit's residual beside the trace's noise (:func:`_against_noise`).

    Attributes
    ----------
    residual_rms_m : float
        The residual of a twin run with the fitted values (m RMS).
    noise_floor_m : float
        The trace's noise (m RMS, :func:`noise_floor`).
    at_noise_floor : bool
        Whether the residual is within :data:`NOISE_FLOOR_FACTOR` of the noise.
    note : str
        What that says.
    """

    residual_rms_m: float
    noise_floor_m: float
    at_noise_floor: bool
    note: str

    def to_json(self) -> dict[str, Any]:
        """The comparison as ``solver``'s entries."""
        return {
            "residual_rms_m": self.residual_rms_m,
            "noise_floor_m": self.noise_floor_m,
            "at_noise_floor": self.at_noise_floor,
            "note": self.note,
        }


@dataclass(frozen=True)
class SolverReport:
    """How the last least-squares solve ended.

    Attributes
    ----------
    converged : bool
        scipy's termination was a convergence.
    termination : str
        scipy's message.
    evaluations : int
        The solve's evaluations, out of :data:`MAX_EVALUATIONS`.
    optimality : float
        The final gradient's largest component, scaled.
    rejected_diverged : int
        The trials the twin diverged on (rejected steps), over the whole fit.
    against_noise : NoiseComparison or None
        A time trace's residual beside its noise; None for an FRF.
    """

    converged: bool
    termination: str
    evaluations: int
    optimality: float
    rejected_diverged: int
    against_noise: NoiseComparison | None

    def to_json(self) -> dict[str, Any]:
        """The report as ``twin calibrate --json``'s ``solver``."""
        return {
            "converged": self.converged,
            "termination": self.termination,
            "evaluations": self.evaluations,
            "max_evaluations": MAX_EVALUATIONS,
            "optimality": self.optimality,
            "rejected_diverged": self.rejected_diverged,
            **(self.against_noise.to_json() if self.against_noise is not None else {}),
        }


@dataclass(frozen=True)
class FitIndex:
    """Sabau 2022's NRMSE fit index (%), 100 (1 - ||y - y_model|| / ||y - mean(y)||).

    Attributes
    ----------
    before, after : float
        With the nominal values and the fitted ones.
    twin : float or None
        A time trace's twin run with the fitted values, in full; None for an FRF.
    """

    before: float
    after: float
    twin: float | None

    def to_json(self) -> dict[str, float]:
        """``before``, ``after`` and a time trace's ``twin``."""
        return {"before": self.before, "after": self.after, **({"twin": self.twin} if self.twin is not None else {})}


@dataclass(frozen=True)
class CalibrationReport:
    """A calibration's result (:func:`solve`); every value by parameter symbol, in the machine's units.

    Attributes
    ----------
    machine, trace : str
    kind : {"time", "frf"}
    excited_band_hz : float
        The band the input excites (an FRF: its highest line).
    not_excited : dict
        The fitted stiffnesses whose mode the input does not reach, with the excitation that would.
    fitted, nominal : dict
        The fitted values (the identifiable ones) and the values before the fit.
    standard_errors, statistical_errors, model_errors : dict
        The noise's and the model's own errors together, the noise's (from the Jacobian) and a
        time trace's model's own (twice the estimate's shift with the physics step halved); empty
        for a fit that did not converge.
    unidentifiable, poorly_determined : dict
        The parameters the data do not determine (kept at nominal) or pin only loosely, with the reason.
    solver : SolverReport
    fit_index_pct : FitIndex
    evaluations : int
        The model's evaluations over the whole fit, finite differences included.
    parameters : dict
        All values in effect after the fit.
    """

    machine: str
    trace: str
    kind: Literal["time", "frf"]
    excited_band_hz: float
    not_excited: dict[str, str]
    fitted: dict[str, float]
    nominal: dict[str, float]
    standard_errors: dict[str, float]
    statistical_errors: dict[str, float]
    model_errors: dict[str, float]
    unidentifiable: dict[str, str]
    poorly_determined: dict[str, str]
    solver: SolverReport
    fit_index_pct: FitIndex
    evaluations: int
    parameters: dict[str, float]

    def to_json(self) -> dict[str, Any]:
        """What ``twin calibrate --json`` prints."""
        return {
            "machine": self.machine,
            "trace": self.trace,
            "kind": self.kind,
            "excited_band_hz": self.excited_band_hz,
            "not_excited": self.not_excited,
            "fitted": self.fitted,
            "nominal": self.nominal,
            "standard_errors": self.standard_errors,
            "statistical_errors": self.statistical_errors,
            "model_errors": self.model_errors,
            "unidentifiable": self.unidentifiable,
            "poorly_determined": self.poorly_determined,
            "solver": self.solver.to_json(),
            "fit_index_pct": self.fit_index_pct.to_json(),
            "evaluations": self.evaluations,
            "parameters": self.parameters,
        }


@dataclass
class _Tally:
    """The model's evaluations over a fit (a twin run each for a time trace), on a progress bar,
    and the trials rejected."""

    bar: tqdm
    evaluations: int = 0
    rejected: int = 0


class _CountedResidual:
    """A residual whose evaluations are counted in a :class:`_Tally`.  A trial that makes the
    twin diverge, or needs a shorter physics step than the machine's, is a step the solver
    rejects (a residual far larger than any it has seen), not the end of the fit; the first
    evaluation (where the solve starts) raises."""

    def __init__(self, residual: Callable[[np.ndarray], np.ndarray], tally: _Tally) -> None:
        self.residual = residual
        self.tally = tally
        self.size: int | None = None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        self.tally.evaluations += 1
        self.tally.bar.update(1)
        if self.size is None:
            r = self.residual(x)
            self.size = len(r)
            return r
        try:
            return self.residual(x)
        except SimulationDiverged:
            self.tally.rejected += 1
        except TwinInputError as exc:
            if exc.field != "timestep_s":  # a trial stiffness too high for the physics step: rejected too
                raise
            self.tally.rejected += 1
        return np.full(self.size, DIVERGED_RESIDUAL)


def calibrate(
    machine: str,
    trace: str | Path,
    fit: list[str],
    *,
    overrides: dict[str, float] | None = None,
    axis: str = "x",
    progress: bool = False,
    sensor: str = "table",
    timestep_s: float | None = None,
) -> CalibrationReport:
    """Fit ``fit`` (parameter symbols) to a measured trace or FRF (see the module docstring):
    the problem built (:meth:`CalibrationProblem.from_inputs`) and solved (:func:`solve`);
    ``timestep_s`` replaces the machine's physics step (a finer one: the model's own error),
    ``progress`` shows a bar of the evaluations.

    Returns
    -------
    CalibrationReport
        Its :meth:`CalibrationReport.to_json` is what ``twin calibrate --json`` prints.

    Raises
    ------
    TwinInputError
        A bad machine, parameter, file or column (one line).
    """
    problem = CalibrationProblem.from_inputs(
        machine, trace, fit, overrides=overrides, axis=axis, sensor=sensor, timestep_s=timestep_s
    )
    return solve(problem, progress=progress)


def solve(problem: CalibrationProblem, *, progress: bool = False) -> CalibrationReport:
    """Solve a calibration (see the module docstring): the first stage (a time trace's
    velocity) from the nominal values and, off the noise, from each stiffness's other starts
    (:func:`_starts`), the least cost kept; a time trace's position from there; the
    unidentifiable parameters held at nominal and the others fitted again.  ``progress`` shows
    a bar of the evaluations.

    Raises
    ------
    TwinInputError
        A trial's bad value (one line, "during the fit").
    """
    x0, bounds = problem.start, (problem.lower, problem.upper)
    tally = _Tally(tqdm(desc=f"calibrating {', '.join(problem.fit)}", unit="run", disable=not progress, leave=False))
    try:
        before = problem.model(x0)
        every = np.ones(len(problem.fit), bool)
        sol = _solve(_CountedResidual(problem.basin_residual, tally), x0, bounds, every)
        if not problem.data.at_noise_floor(sol):  # from each stiffness's other starts too, the least cost kept
            others = (
                _solve(_CountedResidual(problem.basin_residual, tally), np.clip(start, *bounds), bounds, every)
                for start in _starts(x0, problem.stiffnesses)
            )
            sol = min([sol, *others], key=lambda solution: solution.cost)
        if problem.kind == "time":  # the position's own fit, from the velocity's basin
            sol = _solve(_CountedResidual(problem.residual, tally), sol.x, bounds, every)
        unidentifiable = _unidentifiable(sol.jac, sol.x, problem.scale, problem.fit, sol.cost)
        fitted_x, free = sol.x.copy(), np.array([s not in unidentifiable for s in problem.fit])
        fitted_x[~free] = (problem.nominal / problem.scale)[~free]  # held at nominal, all together
        if unidentifiable and free.any():  # the others fitted again with them held
            sol = _solve(_CountedResidual(problem.residual, tally), fitted_x, bounds, free)
            fitted_x = sol.x
    except TwinInputError as exc:
        raise TwinInputError(exc.field, exc.value, f"{exc.reason} (during the fit)") from None
    finally:
        tally.bar.close()
    return _report(
        problem, sol, fitted_x=fitted_x, free=free, unidentifiable=unidentifiable, before=before, tally=tally
    )


def _report(
    problem: CalibrationProblem,
    sol: optimize.OptimizeResult,
    *,
    fitted_x: np.ndarray,
    free: np.ndarray,
    unidentifiable: dict[str, str],
    before: np.ndarray,
    tally: _Tally,
) -> CalibrationReport:
    """The report of a solved calibration: the last solve ``sol``, the fitted values
    ``fitted_x`` (units of the scale; the ``free`` ones fitted, the ``unidentifiable`` ones at
    nominal), the model at the start ``before`` and the evaluations' ``tally``; the standard
    errors (for a time trace with the model's own error, one more evaluation), the fit index,
    a time trace's twin run with the fitted values against its noise, the stiffnesses not
    excited."""
    fit, scale, data = problem.fit, problem.scale, problem.data
    converged = bool(sol.status > 0)
    std = np.full(len(fit), np.nan)
    model_error = np.zeros(len(fit))
    if free.any():
        std[free] = _standard_errors(sol.jac, sol.cost) * scale[free]
        if isinstance(data, TimeTrace):  # the model's own error: the estimate's shift with the step halved
            shift = _estimate_shift(sol.jac, problem.residual(fitted_x, halved=True) - problem.residual(fitted_x))
            model_error[free] = INTEGRATOR_ORDER_FACTOR * np.abs(shift) * scale[free]
            tally.evaluations += 1
    statistical = std.copy()
    std = np.hypot(std, model_error)
    poorly_determined = {
        s: f"the data pin it only to +-{100 * std[i] / abs(fitted_x[i] * scale[i]):.2g} % (the model's own "
        f"error {100 * model_error[i] / abs(fitted_x[i] * scale[i]):.2g} %, the noise's "
        f"{100 * statistical[i] / abs(fitted_x[i] * scale[i]):.2g} %)"
        for i, s in enumerate(fit)
        if free[i] and converged and fitted_x[i] != 0 and std[i] > POORLY_DETERMINED * abs(fitted_x[i] * scale[i])
    }
    after = problem.model(fitted_x)
    target = data.target
    fitted = {s: float(fitted_x[i] * scale[i]) for i, s in enumerate(fit) if s not in unidentifiable}
    twin_index, against_noise = None, None
    if isinstance(data, TimeTrace):  # confirmed by a twin run with the fitted values, in full
        confirm = replay(
            build(problem.machine, problem.values(fitted_x), problem.timestep_s),
            data.sample_period_s,
            data.inputs_V,
            data.positions_m[0],
        )[:, data.measured]
        twin_index = float(np.mean(fit_index(target, confirm)))
        against_noise = _against_noise(float(np.sqrt(np.mean((confirm - target) ** 2))), data.noise_floor_m)
        band_hz = excited_band_hz(data.inputs_V, data.sample_period_s)
    else:
        band_hz = float(data.frequency_hz.max())
    stiffnesses = [s for s, stiffness in zip(fit, problem.stiffnesses) if stiffness]
    return CalibrationReport(
        machine=problem.machine,
        trace=problem.trace,
        kind=problem.kind,
        excited_band_hz=band_hz,
        not_excited=_not_excited(problem, problem.values(fitted_x), stiffnesses, band_hz),
        fitted=fitted,
        nominal={s: float(problem.parameters[s]) for s in fit},
        standard_errors=_identified(fit, std, unidentifiable) if converged else {},
        statistical_errors=_identified(fit, statistical, unidentifiable) if converged else {},
        model_errors=_identified(fit, model_error, unidentifiable) if converged and problem.kind == "time" else {},
        unidentifiable=unidentifiable,
        poorly_determined=poorly_determined,
        solver=SolverReport(
            converged=converged,
            termination=sol.message,
            evaluations=int(sol.nfev),
            optimality=float(sol.optimality),
            rejected_diverged=tally.rejected,
            against_noise=against_noise,
        ),
        fit_index_pct=FitIndex(
            before=float(np.mean(fit_index(_real(target), _real(before)))),
            after=float(np.mean(fit_index(_real(target), _real(after)))),
            twin=twin_index,
        ),
        evaluations=tally.evaluations,
        parameters={k: float(v) for k, v in problem.values(fitted_x).items()},
    )


def _identified(fit: list[str], values: np.ndarray, unidentifiable: dict[str, str]) -> dict[str, float]:
    """``values`` (one per fitted parameter) by symbol, the unidentifiable ones left out."""
    return {s: float(values[i]) for i, s in enumerate(fit) if s not in unidentifiable}


def noise_floor(positions: np.ndarray, resolution_m: np.ndarray) -> float:
    """The white noise (m, RMS over the columns) of sampled positions ``positions`` (samples,
    axes), from their second differences: a smooth motion's are tiny at the sampling rate,
    white noise of variance s^2 gives 6 s^2 (a robust estimate: the median absolute
    deviation); never under the encoder's quantization, ``resolution_m`` / sqrt(12) per axis."""
    second = np.diff(positions, 2, axis=0)
    deviation = np.median(np.abs(second - np.median(second, axis=0)), axis=0)
    noise = np.maximum(1.4826 * deviation / math.sqrt(6.0), resolution_m / math.sqrt(12.0))
    return float(np.sqrt(np.mean(noise**2)))


def _against_noise(residual_rms_m: float, floor: float) -> NoiseComparison:
    """The fit's residual (m RMS) beside the trace's noise ``floor`` (:func:`noise_floor`, m),
    and a note where it is over :data:`NOISE_FLOOR_FACTOR` times it: a solve that stopped away
    from the minimum, a parameter that should be fitted too, or a model that cannot explain the
    data."""
    if residual_rms_m > NOISE_FLOOR_FACTOR * floor:
        return NoiseComparison(
            residual_rms_m,
            floor,
            at_noise_floor=False,
            note=f"the fit leaves {residual_rms_m:.3g} m RMS, {residual_rms_m / floor:.2g} x the trace's noise "
            f"({floor:.3g} m): a local minimum, a parameter not fitted, or a model that cannot explain the data",
        )
    return NoiseComparison(
        residual_rms_m,
        floor,
        at_noise_floor=True,
        note=f"the fit leaves {residual_rms_m:.3g} m RMS, {residual_rms_m / floor:.2g} x the trace's noise "
        f"({floor:.3g} m): the model explains the data to their noise, which does not make it exact "
        "(the standard errors include the model's own error, model_errors)",
    )


def excited_band_hz(u: np.ndarray, dt: float) -> float:
    """The frequency (Hz) up to which the input ``u`` (samples, axes; V at ``dt`` s) excites:
    the end of the band, from the lowest line, where its power spectral density (Welch, the
    axes summed) stays within :data:`EXCITED_WITHIN_DB` of its strongest line (a PRBS's main
    lobe, not its side lobes)."""
    freqs, density = signal.welch(u, fs=1.0 / dt, nperseg=min(len(u), 1024), axis=0)
    density = density.sum(axis=1)
    weak = np.flatnonzero(density[1:] < density.max() * 10 ** (-EXCITED_WITHIN_DB / 10))
    return float(freqs[weak[0] + 1] if weak.size else freqs[-1])


def _not_excited(
    problem: CalibrationProblem, values: dict[str, float], stiffnesses: list[str], band_hz: float
) -> dict[str, str]:
    """The fitted ``stiffnesses`` whose mode the input does not reach (with the parameter
    ``values``), each with the excitation that would.  A stiffness's mode is the model's (table
    sensor, any axis) that moves most when it changes by 1 %; it is excited where the input
    reaches :data:`EXCITE_BEYOND_MODE` times ``band_hz`` (the models built at the fit's physics
    step)."""
    nominal = _table_modes(problem, values)
    out = {}
    for s in stiffnesses:
        shift = np.abs(_table_modes(problem, {**values, s: 1.01 * values[s]}) / nominal - 1)
        mode = float(nominal[np.argmax(shift)])
        if mode * EXCITE_BEYOND_MODE > band_hz:
            needed = 10 * math.ceil(EXCITE_BEYOND_MODE * mode / 10)
            out[s] = (
                f"its mode at {mode:.0f} Hz lies beyond what the input excites (to {band_hz:.0f} Hz, within "
                f"{EXCITED_WITHIN_DB:g} dB of its strongest line): excite to {needed} Hz, e.g. the PRBS of "
                f"twin excite {problem.machine} --f-max {needed}"
            )
    return out


def _table_modes(problem: CalibrationProblem, values: dict[str, float]) -> np.ndarray:
    """The resonances (Hz) of every axis to the table's sensor with the parameter ``values``, at
    the fit's physics step."""
    bm = build(problem.machine, values, problem.timestep_s)
    return np.concatenate([model_modes(bm, k, "table")[0] for k in range(len(problem.axes))])


def excitation_trace(
    machine: str,
    axis: str = "x",
    f_max_hz: float = 500.0,
    amplitude_V: float = 2.0,
    duration_s: float = 0.6,
    seed: int = 1,
    overrides: dict[str, float] | None = None,
    simulate_twin: bool = False,
) -> dict[str, np.ndarray]:
    """An open-loop excitation for calibration: a PRBS (:func:`excitation_signal`) on ``axis``'s
    drive input, flat to about ``f_max_hz``, at the FRF's sample period, as trace columns
    (``time_s``, ``u_<axis>_V``) to play on a machine and record its ``pos_<axis>_m``; with
    ``simulate_twin``, the twin's own open-loop response (the machine with ``overrides``)."""
    bm = build(machine, overrides)
    names = [a.name for a in bm.axes]
    (k,) = axes_indices([axis], names, "--axis")
    if not (MIN_DURATION_S <= duration_s <= 60.0):
        raise TwinInputError("--duration", duration_s, f"must be in [{MIN_DURATION_S:g}, 60] s")
    FrfSettings(axis=axis, amplitude_V=amplitude_V, f_max_hz=f_max_hz, seed=seed).check()
    dt = sample_period(bm)
    n = max(MIN_SAMPLES, round(duration_s / dt))
    u = np.zeros((n, len(names)))
    u[:, k] = excitation_signal("prbs", n, dt, amplitude_V, f_max_hz, seed)
    columns = {"time_s": np.arange(n) * dt, f"u_{axis}_V": u[:, k]}
    if simulate_twin:
        columns[f"pos_{axis}_m"] = replay(bm, dt, u, np.zeros(len(names)))[:, k]
    return columns


def write_table(columns: dict[str, np.ndarray], path: str | Path) -> None:
    """Columns as a CSV or Parquet file (by its suffix), readable by :func:`read_table`."""
    import pyarrow as pa
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    table = pa.table(columns)
    if Path(path).suffix == ".parquet":
        pq.write_table(table, path)
    else:
        pacsv.write_csv(table, path)


def _starts(x0: np.ndarray, stiff: np.ndarray) -> list[np.ndarray]:
    """Where the solve starts again when the start from ``x0`` ends above the trace's noise (an
    FRF: always): each fitted stiffness, one at a time, at :data:`STIFFNESS_STARTS` times its
    nominal value (the solution of least cost is kept).  A drive train's response is not convex
    in its stiffness (a mode moved past the excitation's lines rings out of phase): fitting the
    position from the nominal alone, a stiffness 31 % low came back 62 % high."""
    starts = []
    for i in np.flatnonzero(stiff):
        for factor in STIFFNESS_STARTS:
            x = x0.copy()
            x[i] *= factor
            starts.append(x)
    return starts


def _solve(residual, x0: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], free: np.ndarray):
    """Least squares over the ``free`` entries of ``x`` (in units of their scale), the others held
    at ``x0``: trust-region reflective, a finite-difference Jacobian, at most
    :data:`MAX_EVALUATIONS` evaluations.  The solution's ``x`` is the whole vector."""

    def partial(z):
        x = x0.copy()
        x[free] = z
        return residual(x)

    sol = optimize.least_squares(
        partial,
        x0[free],
        bounds=(bounds[0][free], bounds[1][free]),
        diff_step=1e-4,
        x_scale="jac",
        max_nfev=MAX_EVALUATIONS,
    )
    x = x0.copy()
    x[free] = sol.x
    sol.x = x
    return sol


def _estimate_shift(jac: np.ndarray, change: np.ndarray) -> np.ndarray:
    """The least-squares estimate's shift (in units of the scale, the Jacobian's columns) when
    the residual at the solution changes by ``change`` (one Gauss-Newton step:
    -(J^T J)^-1 J^T change, through :func:`_resolved_svd`, the unresolved directions left out)."""
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    _, _, tiny = _resolved_svd(jac)
    u = jac @ vt.T
    coefficients = np.where(tiny, 0.0, (u.T @ change) / np.where(tiny, 1.0, sv) ** 2)
    return -(vt.T @ coefficients)


def _resolved_svd(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Jacobian's singular values and right singular vectors, and which singular values
    finite differences of a simulation cannot resolve (under 1e-5 of the largest)."""
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    tiny = sv < 1e-5 * sv.max() if sv.max() > 0 else np.ones_like(sv, bool)
    return sv, vt, tiny


def _covariance(jac: np.ndarray, cost: float) -> np.ndarray:
    """The parameters' covariance (in units of their scale) from the Jacobian at the solution:
    s^2 (J^T J)^-1, s^2 the residual variance, through the SVD with the directions finite
    differences cannot resolve left out (:func:`_resolved_svd`)."""
    s2 = 2 * cost / max(1, jac.shape[0] - jac.shape[1])
    sv, vt, tiny = _resolved_svd(jac)
    inv_sv2 = np.where(tiny, 0.0, 1.0 / np.where(tiny, 1.0, sv) ** 2)
    return (vt.T * inv_sv2) @ vt * s2


def _standard_errors(jac: np.ndarray, cost: float) -> np.ndarray:
    """Standard errors (in units of the scale): the square roots of :func:`_covariance`'s diagonal."""
    return np.sqrt(np.maximum(np.diag(_covariance(jac, cost)), 0.0))


def _unidentifiable(jac: np.ndarray, x: np.ndarray, scale: np.ndarray, fit: list[str], cost: float) -> dict:
    """The parameters the data do not determine, with the reason (see the module docstring): a
    Jacobian column of zeros, a direction of the Jacobian's null space it takes part in, or a
    relative standard error over :data:`MAX_RELATIVE_ERROR`, a combination where its estimate
    correlates over :data:`MAX_CORRELATION` with others'; a combination's partners are flagged
    with it."""
    _, vt, tiny = _resolved_svd(jac)
    null_space = vt[tiny]  # directions the data do not see
    cov = _covariance(jac, cost)
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.nan_to_num(cov / np.outer(std, std))
    combination = "the data determine only its combination with "
    out = {}
    for i, s in enumerate(fit):
        rel = std[i] / abs(x[i]) if x[i] else np.inf
        partners = []
        if not np.abs(jac[:, i]).max() > 0:
            out[s] = "the data do not depend on it"
            continue
        if null_space.size and np.abs(null_space[:, i]).max() > 0.1:
            partners = [fit[j] for j in range(len(fit)) if j != i and np.abs(null_space[:, j]).max() > 0.1]
        elif rel > MAX_RELATIVE_ERROR:
            partners = [fit[j] for j in range(len(fit)) if j != i and abs(corr[i, j]) > MAX_CORRELATION]
            if not partners:
                out[s] = f"the data do not determine it (relative standard error {100 * rel:.0f} %)"
                continue
        else:
            continue
        out[s] = combination + (", ".join(partners) or "itself")
    for s, why in list(out.items()):  # a combination's partners are held with it
        if why.startswith(combination):
            for partner in why.removeprefix(combination).split(", "):
                if partner in fit and partner not in out:
                    out[partner] = combination + s
    return out


def _real(values: np.ndarray) -> np.ndarray:
    """A complex series as real and imaginary columns side by side (real series unchanged)."""
    values = np.asarray(values)
    if np.iscomplexobj(values):
        return np.column_stack([values.real, values.imag])
    return values


def measured_frf(columns: dict[str, np.ndarray], axes: list[str], axis: str, sensor: str) -> MeasuredFrf:
    """Check a measured FRF's columns (see the module docstring): measured on ``axis`` (one of
    the machine's ``axes``) at ``sensor`` (the table's or the motor's).

    Raises
    ------
    TwinInputError
        One line per defect: a missing or unknown column, an unknown axis, under 10 lines, NaN,
        frequencies not positive and increasing.
    """
    needed = ("frequency_hz", "magnitude_db", "phase_deg")
    missing = [c for c in needed if c not in columns]
    if missing:
        raise TwinInputError(
            "--trace column", missing[0], "missing: an FRF needs frequency_hz, magnitude_db, phase_deg"
        )
    unknown = sorted(set(columns) - set(needed) - {"coherence"})
    if unknown:
        raise TwinInputError(
            "--trace column", unknown[0], f"unknown in an FRF (columns: {', '.join(needed)}, coherence)"
        )
    (k,) = axes_indices([axis], axes, "--axis")
    f = columns["frequency_hz"]
    if len(f) < 10:
        raise TwinInputError("--trace", f"{len(f)} lines", "too short: an FRF needs 10 frequency lines")
    _all_finite(columns, list(needed))
    if (f <= 0).any() or (np.diff(f) <= 0).any():
        raise TwinInputError("--trace column frequency_hz", f"{f.min():g} Hz", "frequencies must be > 0 and increase")
    response = 10 ** (columns["magnitude_db"] / 20) * np.exp(1j * np.radians(columns["phase_deg"]))
    return MeasuredFrf(f, response, k, sensor)
