"""Running a sweep on Dask: batches of samples as tasks, each finished batch one Parquet part.

The output is a Parquet dataset (a folder, ``sweep.parquet/part-<first index>.parquet``) with
one row per sample: its index, scenario seed, the varied values (one column per path), status
(``ok``, ``diverged`` with the simulated time, or ``error`` with the message), the metrics of
``twin run`` over every tick (max and RMS tracking error per axis, the largest cutting force
per axis; runs record metrics only) and the wall time.  A part is written to a hidden
temporary file and renamed, so an interrupted or killed sweep leaves only whole parts, and
``resume`` runs the samples no part holds.  The client keeps the indices done and the batches
in flight, nothing more, so its memory does not grow with the sweep.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twin.errors import SimulationDiverged, TwinInputError
from twin.sampling import SamplePlan

STATUSES = ("ok", "diverged", "error")


#: The contour columns of a two-axis machine: filled for a G-code reference (the samples record
#: their ticks for it; ``_feed``: on the feed moves alone), empty otherwise.
CONTOUR_COLUMNS = (
    "max_contour_error_um",
    "rms_contour_error_um",
    "max_contour_error_feed_um",
    "rms_contour_error_feed_um",
)


def metric_columns(axes, program: bool = False) -> list[str]:
    """The metric columns for machine axes ``axes`` (a G-code ``program`` on two axes: and the
    contour columns)."""
    per_axis = [f"{m}_{a}" for m in ("max_tracking_error_um", "rmse_um", "max_cutting_force_N") for a in axes]
    return per_axis + (list(CONTOUR_COLUMNS) if program and len(axes) == 2 else [])


def is_program(base: dict) -> bool:
    """Whether the scenario ``base`` (a dict) runs a G-code program."""
    reference = base.get("reference")
    return isinstance(reference, dict) and reference.get("type") == "gcode"


def scenario_value(value):
    """A sampled value as the scenario takes it: a number as a float, anything else as text."""
    return float(value) if isinstance(value, (int, float, np.floating)) else str(value)


def run_sample(base: dict, *, index: int, values: dict, seed: int, axes) -> dict:
    """Run one sample of the scenario ``base`` (a scenario dict) and return its row.

    The scenario gets the sample's ``values`` (as ``twin run --set`` would set them), its
    ``seed`` and ``record_every_ticks = 0`` (a G-code program: recorded, for its contour
    error).  Never raises for the sample's own failures: a diverging run is a ``diverged`` row
    with the simulated time, an invalid or failing one an ``error`` row with the message.
    """
    from twin.scenario import run_scenario, scenario_from_dict
    from twin.settings import set_fields

    row = {
        "index": index,
        "seed": seed,
        **values,
        "status": "ok",
        "error": "",
        "sim_time_s": math.nan,
        "completed_ticks": 0,
        **{c: math.nan for c in metric_columns(axes, is_program(base))},
    }
    start = time.perf_counter()
    result = None
    try:
        data = set_fields(base, {p: scenario_value(v) for p, v in values.items()})
        program = is_program(data)
        # a program's samples record (every tick up to 100 000, the runner's default) for the
        # contour error; others keep metrics only
        data["seed"], data["record_every_ticks"] = seed, None if program else 0
        outcome = run_scenario(scenario_from_dict(data), progress=False)
        result = outcome.run
        row["sim_time_s"] = result.info["completed_ticks"] * result.control_period_s
    except SimulationDiverged as exc:
        row.update(status="diverged", error=str(exc), sim_time_s=exc.sim_time_s)
        result = exc.result
    except TwinInputError as exc:
        row.update(status="error", error=str(exc))
    except Exception as exc:
        row.update(status="error", error=f"{type(exc).__name__}: {exc}")
    if result is not None and row["status"] == "ok":
        row["completed_ticks"] = int(result.info["completed_ticks"])
        for i, a in enumerate(axes):
            row[f"max_tracking_error_um_{a}"] = float(result.error_max_m[i] * 1e6)
            row[f"rmse_um_{a}"] = float(result.error_rms_m[i] * 1e6)
            row[f"max_cutting_force_N_{a}"] = float(result.force_max_N[i])
        if is_program(base) and len(result.t_s) > 1 and len(axes) == 2:
            from twin.metrics import tracking_summary

            summary = tracking_summary(outcome)
            for column in CONTOUR_COLUMNS:
                row[column] = float(summary.get(column, math.nan))
    elif result is not None:
        row["completed_ticks"] = int(result.info["completed_ticks"])
    row["wall_s"] = time.perf_counter() - start
    return row


def run_batch(base: dict, items: list, axes) -> list[dict]:
    """:func:`run_sample` for each ``(index, values, seed)`` of ``items`` (one Dask task)."""
    return [run_sample(base, index=i, values=values, seed=seed, axes=axes) for i, values, seed in items]


def _schema(plan: SamplePlan, axes, program: bool):
    import pyarrow as pa

    fields = [pa.field("index", pa.int64()), pa.field("seed", pa.int64())]
    for v in plan.variations:
        text = v.kind == "choice" and any(isinstance(a, str) for a in v.args)
        fields.append(pa.field(v.path, pa.string() if text else pa.float64()))
    fields += [
        pa.field("status", pa.string()),
        pa.field("error", pa.string()),
        pa.field("sim_time_s", pa.float64()),
        pa.field("completed_ticks", pa.int64()),
    ]
    metrics = metric_columns(axes, program)
    fields += [pa.field(c, pa.float64()) for c in metrics] + [pa.field("wall_s", pa.float64())]
    return pa.schema(fields)


def done_indices(out: Path) -> set[int]:
    """The sample indices the parts in ``out`` already hold."""
    import pyarrow.parquet as pq

    if not out.exists():
        return set()
    parts = sorted(out.glob("part-*.parquet"))
    return {int(i) for p in parts for i in pq.read_table(p, columns=["index"]).column("index").to_pylist()}


def _write_part(out: Path, rows: list[dict], schema) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    text = [f.name for f in schema if f.type == pa.string()]  # a choice of mixed values is stored as text
    rows = [r | {k: str(r[k]) for k in text} for r in sorted(rows, key=lambda r: r["index"])]
    name = f"part-{rows[0]['index']:07d}.parquet"
    tmp = out / f".{name}.tmp"
    pq.write_table(pa.Table.from_pylist(rows, schema=schema), tmp)
    os.replace(tmp, out / name)


@dataclass
class SweepRun:
    """What a call of :func:`run_sweep` did: ``ran`` samples, ``skipped`` (already in the
    output), ``wall_s`` and whether it was ``interrupted``."""

    ran: int
    skipped: int
    wall_s: float
    interrupted: bool = False


def check_batch_size(batch_size) -> None:
    """Refuse a batch size (samples per Dask task) that is not a whole number from 1 to 10 000.

    Raises
    ------
    TwinInputError
        Under ``--batch``.
    """
    if not (isinstance(batch_size, int) and not isinstance(batch_size, bool) and 1 <= batch_size <= 10_000):
        raise TwinInputError("--batch", batch_size, "must be a whole number from 1 to 10000")


def make_client(workers: int | None = None, scheduler: str | None = None):
    """A Dask client: on the scheduler at ``scheduler`` (``tcp://host:8786``), else on a new
    local cluster of ``workers`` processes (default one per core), one thread each.

    Raises
    ------
    TwinInputError
        No scheduler answers at ``scheduler`` within 10 s (or the address is malformed).
    """
    import logging

    from distributed import Client

    if scheduler:
        try:
            return Client(scheduler, timeout="10s")
        except (OSError, ValueError, TypeError) as exc:
            raise TwinInputError("--scheduler", scheduler, f"no Dask scheduler answers there ({exc})") from None
    n = workers or os.cpu_count() or 1
    # Dask's own lines (INFO, and at shutdown a worker's heartbeat meeting a closed scheduler,
    # logged with its traceback) would bury the progress bar and the twin's one error line: a
    # sample's failure is its row, a lost worker an exception the CLI reports
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    # the client starts the cluster itself, so that closing the client closes the cluster before
    # the interpreter's exit (a cluster handed in is left to a finalizer, whose shutdown races)
    return Client(
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.CRITICAL
    )


def run_sweep(
    base: dict,
    plan: SamplePlan,
    *,
    axes,
    out: Path,
    client,
    batch_size: int = 10,
    resume: bool = False,
    progress: bool = True,
    in_flight_per_worker: int = 2,
) -> SweepRun:
    """Run every sample of ``plan`` not yet in ``out`` on ``client``; parts stream to ``out``.

    Parameters
    ----------
    base : dict
        The scenario, as a dict (validated by the caller).
    axes : sequence of str
        The machine's axis names (the metric columns).
    out : Path
        The Parquet dataset folder; must not exist unless ``resume``.
    batch_size : int
        Samples per Dask task.
    in_flight_per_worker : int
        Batches submitted ahead per worker (bounds the client's memory).

    Raises
    ------
    TwinInputError
        ``out`` exists without ``resume``, or is not a folder of parts.
    """
    from distributed import as_completed
    from tqdm import tqdm

    if out.exists() and not resume:
        raise TwinInputError("--out", str(out), "exists: add --resume to complete it, or choose another path")
    if out.exists() and not out.is_dir():
        raise TwinInputError("--out", str(out), "is not a sweep's Parquet folder")
    check_batch_size(batch_size)
    out.mkdir(parents=True, exist_ok=True)
    schema = _schema(plan, axes, is_program(base))
    done = done_indices(out)
    todo = (i for i in range(len(plan)) if i not in done)
    remaining = len(plan) - len(done)
    workers = max(1, len(client.scheduler_info().get("workers", {})))
    limit = workers * in_flight_per_worker
    start, ran, interrupted = time.perf_counter(), 0, False

    queue, pending = as_completed(), set()

    def submit_next():
        items = []
        for i in todo:
            items.append((i, plan.values(i), plan.sample_seed(i)))
            if len(items) == batch_size:
                break
        if items:
            future = client.submit(run_batch, base, items, list(axes), retries=3, pure=False)
            pending.add(future)
            queue.add(future)

    for _ in range(limit):
        submit_next()
    with tqdm(total=remaining, desc="sweep", unit="sample", disable=not progress) as bar:
        try:
            for future in queue:
                rows = future.result()
                _write_part(out, rows, schema)
                ran += len(rows)
                bar.update(len(rows))
                pending.discard(future)
                future.release()
                submit_next()
        except KeyboardInterrupt:
            interrupted = True
            client.cancel(list(pending))
    return SweepRun(ran, len(done), time.perf_counter() - start, interrupted)


def read_sweep(out: Path):
    """The whole sweep as a pyarrow Table, sorted by index."""
    import pyarrow.parquet as pq

    if not out.is_dir() or not any(out.glob("part-*.parquet")):
        raise TwinInputError("--out", str(out), "holds no sweep parts")
    return pq.read_table(out).sort_by("index")
