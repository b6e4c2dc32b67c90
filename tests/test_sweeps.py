"""Sweeps: sampling, a real Dask LocalCluster, Parquet read back, seeded determinism across
worker counts, a killed worker, divergence and error rows, resume, certificates, the CLI."""

from __future__ import annotations

import os
import shutil
import signal
import threading
import time

import numpy as np
import pytest
from cli_process import TWIN, interruptible
from cli_process import twin as twin_cli

from twin.errors import TwinInputError
from twin.machines import get_machine
from twin.sampling import SamplePlan, parse_variation
from twin.sweeps import prepare_sweep
from twin.sweeps.run import make_client, read_sweep, run_sweep
from twin.sweeps.summary import certificates, summarize

LM = get_machine("linear_motor_xy").parameters


def _plan(*specs, samples=10, seed=0, lhs=False, params=LM):
    return SamplePlan([parse_variation(s, params) for s in specs], samples, seed, lhs)


def test_box_draws_stay_in_the_documented_range():
    plan = _plan("overrides.m_x=box", "overrides.b_y=box", samples=2000, seed=3)
    for key in ("m_x", "b_y"):
        lo, hi = LM[key].box
        v = np.array([plan.values(i)[f"overrides.{key}"] for i in range(len(plan))])
        assert lo <= v.min()
        assert v.max() <= hi
        assert v.min() < lo + 0.01 * (hi - lo)
        assert v.max() > hi - 0.01 * (hi - lo)  # the whole box is used


def test_sample_values_depend_on_seed_and_index_only():
    a = _plan("overrides.m_x=box", "disturbances.0.spindle_rpm=uniform(5000,12000)", samples=50, seed=7)
    b = _plan("overrides.m_x=box", "disturbances.0.spindle_rpm=uniform(5000,12000)", samples=50, seed=7)
    assert [a.values(i) for i in range(50)] == [b.values(i) for i in reversed(range(50))][::-1]
    assert a.values(3) != _plan(
        "overrides.m_x=box", "disturbances.0.spindle_rpm=uniform(5000,12000)", samples=50, seed=8
    ).values(3)
    assert len({a.sample_seed(i) for i in range(50)}) == 50


def test_structured_specs_combine_as_a_product_and_line_moves_together():
    plan = _plan("overrides.m_x=corners", "overrides.b_x=grid(100, 300, 3)", "overrides.m_y=box", samples=4)
    assert len(plan) == 2 * 3 * 4
    pairs = {(plan.values(i)["overrides.m_x"], plan.values(i)["overrides.b_x"]) for i in range(len(plan))}
    assert pairs == {(m, b) for m in LM["m_x"].box for b in (100.0, 200.0, 300.0)}
    cn = get_machine("cncmt").parameters
    line = _plan("overrides.K1=line(10)", "overrides.m=line(10)", samples=1, params=cn)
    assert len(line) == 10
    for i in range(10):
        v = line.values(i)
        t = i / 9
        assert v["overrides.K1"] == pytest.approx(cn["K1"].box[0] + t * (cn["K1"].box[1] - cn["K1"].box[0]))
        assert v["overrides.m"] == pytest.approx(cn["m"].box[0] + t * (cn["m"].box[1] - cn["m"].box[0]))


def test_latin_hypercube_puts_one_sample_in_every_stratum():
    plan = _plan("overrides.m_x=uniform(0, 1)", "overrides.m_y=normal(10, 2)", samples=64, lhs=True)
    u = np.array([plan.values(i)["overrides.m_x"] for i in range(64)])
    assert sorted(np.floor(u * 64).astype(int)) == list(range(64))
    normal = np.array([plan.values(i)["overrides.m_y"] for i in range(64)])
    assert normal.mean() == pytest.approx(10.0, abs=0.2)
    assert normal.std() == pytest.approx(2.0, rel=0.15)


@pytest.mark.parametrize(
    "spec, match",
    [
        ("overrides.m_x=uniform(2, 1)", "a < b"),
        ("overrides.nope=box", "machine"),
        ("overrides.m_x=normal(1, 0)", "sigma"),
        ("m_x", "PATH=SPEC"),
        ("overrides.m_x=grid(0, 1, 1.5)", "whole n"),
        ("overrides.m_x=uniform(a, 1)", "not a number"),
    ],
)
def test_bad_variations_name_the_field(spec, match):
    with pytest.raises(TwinInputError, match=match):
        parse_variation(spec, LM)


SHORT = {"duration_s": 0.05}


@pytest.fixture(scope="module")
def one_worker():
    """A client on a local cluster of one worker process, shared by this module's tests (each
    cluster takes a second or two to start, and its worker to load the twin)."""
    client = make_client(1)
    yield client
    client.close()


def _sweep(
    tmp_path,
    name,
    workers,
    vary=("overrides.m_x=box", "disturbances.0.spindle_rpm=uniform(5000,12000)"),
    samples=12,
    batch=3,
    scenario="choi1999_cutting_circle",
    settings=SHORT,
    client=None,
):
    sw = prepare_sweep(
        scenario, settings=dict(settings), vary=list(vary), samples=samples, seed=5, latin_hypercube=False
    )
    out = tmp_path / name
    own = client is None
    client = client or make_client(workers)
    try:
        run_sweep(sw.scenario, sw.plan, axes=sw.axes, out=out, client=client, batch_size=batch, progress=False)
    finally:
        if own:
            client.close()
    return sw, read_sweep(out)


def test_results_are_bit_identical_for_one_and_two_workers(tmp_path, one_worker):
    sw, one = _sweep(tmp_path, "one.parquet", None, client=one_worker)
    _, two = _sweep(tmp_path, "two.parquet", 2)
    assert one.num_rows == two.num_rows == 12
    assert one.drop(["wall_s"]).equals(two.drop(["wall_s"]))
    assert set(one.column("status").to_pylist()) == {"ok"}
    # the rows hold the plan's values and seeds
    assert one.column("overrides.m_x").to_pylist() == [sw.plan.values(i)["overrides.m_x"] for i in range(12)]
    assert one.column("seed").to_pylist() == [sw.plan.sample_seed(i) for i in range(12)]
    assert min(one.column("max_cutting_force_N_x").to_pylist()) > 0


@pytest.mark.slow  # a worker killed and its batch run again
def test_a_killed_worker_loses_no_sample(tmp_path):
    _, reference = _sweep(tmp_path, "ref.parquet", 2, samples=40, batch=2)
    client = make_client(2)
    out = tmp_path / "killed.parquet"
    killed = []

    def kill_one_worker():
        while not any(out.glob("part-*.parquet")):
            time.sleep(0.005)
        pid = next(iter(client.run(os.getpid).values()))
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    try:
        sw = prepare_sweep(
            "choi1999_cutting_circle",
            settings=SHORT,
            vary=["overrides.m_x=box", "disturbances.0.spindle_rpm=uniform(5000,12000)"],
            samples=40,
            seed=5,
            latin_hypercube=False,
        )
        killer = threading.Thread(target=kill_one_worker)
        killer.start()
        run_sweep(sw.scenario, sw.plan, axes=sw.axes, out=out, client=client, batch_size=2, progress=False)
        killer.join()
    finally:
        client.close()
    assert killed
    table = read_sweep(out)
    assert table.column("index").to_pylist() == list(range(40))
    assert table.drop(["wall_s"]).equals(reference.drop(["wall_s"]))


def test_divergence_and_errors_are_rows_with_their_status(tmp_path, one_worker):
    _, table = _sweep(
        tmp_path,
        "bad.parquet",
        None,
        vary=["controller.params.kp=choice(4000, 1e12, 'abc')"],
        samples=24,
        batch=4,
        scenario="square_sabau_pid",
        settings={"duration_s": 0.2},
        client=one_worker,
    )
    rows = table.to_pylist()
    by_kp = {r["controller.params.kp"]: r for r in rows}
    assert table.num_rows == 24
    assert set(by_kp) == {"4000.0", "1000000000000.0", "abc"}
    assert by_kp["4000.0"]["status"] == "ok"
    assert np.isfinite(by_kp["4000.0"]["max_tracking_error_um_x"])
    diverged = by_kp["1000000000000.0"]
    assert diverged["status"] == "diverged"
    assert 0 < diverged["sim_time_s"] < 0.2
    assert "diverged" in diverged["error"]
    assert np.isnan(diverged["max_tracking_error_um_x"])
    assert by_kp["abc"]["status"] == "error"
    assert by_kp["abc"]["error"]


def test_resume_completes_an_interrupted_sweep(tmp_path, one_worker):
    sw, full = _sweep(tmp_path, "full.parquet", None, client=one_worker)
    out = tmp_path / "part.parquet"
    shutil.copytree(tmp_path / "full.parquet", out)
    removed = sorted(out.glob("part-*.parquet"))[1:3]
    for p in removed:
        p.unlink()
    with pytest.raises(TwinInputError, match="--resume"):
        run_sweep(sw.scenario, sw.plan, axes=sw.axes, out=out, client=one_worker, batch_size=3, progress=False)
    done = run_sweep(
        sw.scenario, sw.plan, axes=sw.axes, out=out, client=one_worker, batch_size=3, resume=True, progress=False
    )
    assert (done.ran, done.skipped) == (6, 6)
    assert read_sweep(out).drop(["wall_s"]).equals(full.drop(["wall_s"]))


def test_summary_bands_and_worst_case(tmp_path, one_worker):
    sw, table = _sweep(tmp_path, "s.parquet", None, client=one_worker)
    s = summarize(table, sw.plan, sw.axes)
    worst = max(max(r["max_tracking_error_um_x"], r["max_tracking_error_um_y"]) for r in table.to_pylist())
    assert s["worst"]["value"] == pytest.approx(worst)
    assert s["bands"]["rmse_um_x"]["max"] == pytest.approx(max(table.column("rmse_um_x").to_pylist()))
    assert s["status"] == {"ok": 12}


@pytest.mark.slow
def test_yadav2020_certificate_is_the_reproductions():
    from twin.reproductions.yadav2020.procedure import interval_table

    plan = _plan("overrides.K1=box", "overrides.m=box", params=get_machine("cncmt").parameters)
    (cert,) = certificates("cncmt", "yadav2020_robust_pi", plan)
    row = next(r for r in interval_table() if r["controller"] == "robust_pi")
    assert cert["stability_margin"] == pytest.approx(row["sm"])
    assert cert["kharitonov_robustly_stable"] is False
    assert certificates("cncmt", "pid", plan) == []
    assert certificates("linear_motor_xy", "pid", _plan("overrides.m_x=box")) == []


def _cli(*args):
    return twin_cli("sweep", *args)


def test_cli_sweep_file_writes_parquet_summary_and_plots(tmp_path):
    import json
    from pathlib import Path

    import twin

    example = Path(twin.__file__).parent / "sweeps" / "examples" / "choi1999_cutting_circle.toml"
    out = tmp_path / "s.parquet"
    r = _cli(
        str(example),
        "--samples",
        "4",
        "--workers",
        "1",
        "--set",
        "duration_s=0.05",
        "--out",
        str(out),
        "--plots",
        str(tmp_path / "p"),
        "--json",
    )
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary["status"] == {"ok": 4}
    assert summary["ran"] == 4
    assert summary["certificates"] == []
    assert read_sweep(out).num_rows == 4
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == [
        "sweep_histograms.png",
        "sweep_metric_vs_parameters.png",
    ]
    bad = _cli(str(example), "--vary", "overrides.m_x=uniform(1)", "--out", str(tmp_path / "b.parquet"))
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == [
        "error: --vary overrides.m_x = 'uniform(1)': uniform takes 2 argument(s)"
    ]


@pytest.mark.slow  # 300 samples in a process interrupted, then resumed
def test_cli_interrupted_sweep_keeps_its_parts_and_resume_completes_it(tmp_path):
    import subprocess
    import sys

    out = tmp_path / "i.parquet"
    args = [
        "choi1999_cutting_circle",
        "--vary",
        "overrides.m_x=box",
        "--samples",
        "300",
        "--batch",
        "5",
        "--workers",
        "1",
        "--set",
        "duration_s=0.2",  # 300 samples take 20 s: a loaded machine's test process sees a part before the end
        "--out",
        str(out),
    ]
    proc = subprocess.Popen(
        [sys.executable, "-m", "twin.cli", "sweep", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )
    deadline = time.time() + 120
    while not any(out.glob("part-*.parquet")) and time.time() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    kept = read_sweep(out).num_rows
    assert 0 < kept < 300
    assert "--resume completes it" in stderr.strip().splitlines()[-1]
    r = _cli(*args, "--resume", "--json")
    assert r.returncode == 0, r.stderr
    table = read_sweep(out)
    assert table.column("index").to_pylist() == list(range(300))


def test_a_sweep_runs_on_a_scheduler_by_address(tmp_path):
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        client = make_client(scheduler=cluster.scheduler_address)
        try:
            _, table = _sweep(tmp_path, "addr.parquet", None, samples=4, client=client)
        finally:
            client.close()
    assert table.num_rows == 4
    assert set(table.column("status").to_pylist()) == {"ok"}
    with pytest.raises(TwinInputError, match="no Dask scheduler"):
        make_client(scheduler="not-an-address")


def test_a_sweep_of_failed_samples_exits_2_with_the_first_error_and_nothing_else_on_stderr(tmp_path):
    # a real process: the local cluster's workers write on the process's own stderr, where Dask's
    # shutdown chatter (a heartbeat's CommClosedError traceback) came out
    import subprocess

    out = tmp_path / "f.parquet"
    vary = "controller.params.kp=choice('abc', 'x')"
    args = ["sweep", "square_sabau_pid", "--vary", vary, "--samples", "2", "--workers", "1"]
    args += ["--set", "duration_s=0.02", "--out", str(out), "--json"]
    r = subprocess.run([*TWIN, *args], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr
    assert r.stdout == ""
    first = read_sweep(out).slice(0, 1).to_pylist()[0]
    assert first["controller.params.kp"] in ("abc", "x")
    assert first["error"] == f"controller.params.kp = {first['controller.params.kp']!r}: Input should be a valid number"
    assert r.stderr.splitlines() == [
        f"error: sweep = '2 samples': every sample failed; the first (sample 0): {first['error']}"
    ]


@pytest.mark.parametrize("batch", [0, 10_001, True])
def test_a_bad_batch_size_is_refused_before_a_cluster_starts(tmp_path, monkeypatch, batch):
    from twin import api
    from twin.sweeps import run

    def no_cluster(*args, **kwargs):
        raise AssertionError("a cluster was started")

    monkeypatch.setattr(run, "make_client", no_cluster)
    with pytest.raises(TwinInputError) as err:
        api.sweep("choi1999_cutting_circle", ["overrides.m_x=box"], samples=2, batch=batch, out=tmp_path / "b.parquet")
    assert (err.value.field, err.value.value) == ("--batch", batch)
    assert not (tmp_path / "b.parquet").exists()
