"""``twin bench --sweep``: the sweep of the README on this machine, timed.

In one process: two local clusters (one and two worker processes) are started and warmed up
(each worker loads the numba cache and builds the machine once), then the same sweep of
``samples`` samples of ``choi1999_cutting_circle`` (2 s simulated, mechanistic milling force,
``overrides.m_x`` over Table 1's box and the spindle speed uniform in 5000-12000 rpm) runs on
each, alternating, ``repeats`` times; medians are reported.  Parallel efficiency is
``t(1 worker) / (2 t(2 workers))``.  Cluster start-up is not in the times.

Also measured: the client's resident memory before and after a sweep of ``memory_samples``
one-tick samples (what the client holds grows with the sweep, or not), and the same sweep as a
plain Python loop over ``twin run`` processes, timed on ``loop_samples`` and given per sample.
Outputs go to a temporary folder.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SCENARIO = "choi1999_cutting_circle"
SETTINGS = {"duration_s": 2.0}
VARY = ["overrides.m_x=box", "disturbances.0.spindle_rpm=uniform(5000,12000)"]


def _rss_mb() -> float:
    import psutil

    return psutil.Process().memory_info().rss / 2**20


def run_sweep_bench(
    *,
    samples: int = 1000,
    repeats: int = 1,
    memory_samples: int = 10_000,
    loop_samples: int = 10,
    progress: bool = True,
) -> dict:
    """The figures of ``twin bench --sweep`` (see the module docstring)."""
    from twin.sweeps import prepare_sweep
    from twin.sweeps.run import make_client, run_sweep

    sw = prepare_sweep(SCENARIO, settings=SETTINGS, vary=VARY, samples=samples, seed=0, latin_hypercube=False)
    times: dict[int, list[float]] = {1: [], 2: []}
    with tempfile.TemporaryDirectory() as tmp:
        clients = {n: make_client(n) for n in (1, 2)}
        try:
            warm = prepare_sweep(SCENARIO, settings=SETTINGS, vary=VARY, samples=4, seed=1, latin_hypercube=False)
            for n, client in clients.items():
                run_sweep(
                    warm.scenario,
                    warm.plan,
                    axes=warm.axes,
                    out=Path(tmp) / f"warm{n}",
                    client=client,
                    batch_size=1,
                    progress=False,
                )
            for r in range(repeats):
                for n, client in clients.items():
                    done = run_sweep(
                        sw.scenario,
                        sw.plan,
                        axes=sw.axes,
                        out=Path(tmp) / f"s{n}_{r}",
                        client=client,
                        batch_size=10,
                        progress=progress,
                    )
                    times[n].append(done.wall_s)
            tiny = prepare_sweep(
                SCENARIO,
                settings={"duration_s": 0.0005},
                vary=VARY,
                samples=memory_samples,
                seed=0,
                latin_hypercube=False,
            )
            before = _rss_mb()
            run_sweep(
                tiny.scenario,
                tiny.plan,
                axes=tiny.axes,
                out=Path(tmp) / "memory",
                client=clients[2],
                batch_size=50,
                progress=progress,
            )
            growth = _rss_mb() - before
        finally:
            for client in clients.values():
                client.close()
    loop = []
    for i in range(loop_samples):
        values = sw.plan.values(i)
        cmd = [sys.executable, "-m", "twin.cli", "run", SCENARIO, "--json"]
        for s in [f"{p}={v!r}" for p, v in {**SETTINGS, **values}.items()]:
            cmd += ["--set", s]
        start = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        loop.append(time.perf_counter() - start)
    t1, t2 = statistics.median(times[1]), statistics.median(times[2])
    per_sample = statistics.mean(loop)
    return {
        "scenario": SCENARIO,
        "settings": SETTINGS,
        "vary": VARY,
        "samples": samples,
        "repeats": repeats,
        "wall_s_1_worker": t1,
        "wall_s_2_workers": t2,
        "samples_per_s_2_workers": samples / t2,
        "parallel_efficiency": t1 / (2 * t2),
        "target_wall_s": 60.0,
        "target_efficiency": 0.85,
        "memory_samples": memory_samples,
        "client_memory_growth_MB": growth,
        "twin_run_loop_s_per_sample": per_sample,
        "twin_run_loop_samples": loop_samples,
        "twin_run_loop_extrapolated_s": per_sample * samples,
    }
