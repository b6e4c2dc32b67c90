"""The command line: bad input gives one stderr line and exit code 2; runs and fidelity work."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from cli_process import TWIN, interruptible
from cli_process import twin as _twin

from twin.recording import read_back

GOOD = """
machine = "cncmt"
duration_s = 0.5
control_period_s = 1e-3
[controller]
type = "yadav2020_imc"
[reference]
type = "step"
amplitude_m = 0.01
"""


def _twin_process(*args):
    """``twin ARGS`` as a real process: for the exit codes a shell sees."""
    return subprocess.run([*TWIN, *args], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize(
    "text, field",
    [
        (GOOD.replace('"cncmt"', '"lathe"'), "machine = 'lathe'"),
        (GOOD.replace('"yadav2020_imc"', '"lqg"'), "controller.type = 'lqg'"),
        (GOOD + "\nspindle_rpm = 3000\n", "spindle_rpm"),
        (GOOD.replace('machine = "cncmt"', 'machine = "cncmt"\noverrides = { m = -50.0 }'), "overrides.m = -50.0"),
        (GOOD.replace("control_period_s = 1e-3", "control_period_s = 1.5e-4"), "control_period_s = 0.00015"),
        (GOOD.replace("duration_s = 0.5", "duration_s = [0.5"), "malformed TOML"),
        (GOOD.replace("duration_s = 0.5", "duration_s = -1.0"), "duration_s = -1.0"),
    ],
)
def test_bad_scenarios(tmp_path, text, field):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    r = _twin("run", str(path))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: "), r.stderr
    assert field in lines[0], r.stderr
    assert "Traceback" not in r.stderr


def test_run_json_and_recording(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text(GOOD)
    r = _twin("run", str(path), "--json", "--rrd", str(tmp_path / "ok.rrd"))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["machine"] == "cncmt"
    assert out["max_tracking_error_um"]["x"] == pytest.approx(10000.0, rel=1e-6)
    assert read_back(tmp_path / "ok.rrd")["/actual/x"] == 500 + 1  # ticks + the legend entry


def test_divergence_exit_code(tmp_path):
    path = tmp_path / "div.toml"
    path.write_text(
        GOOD.replace('type = "yadav2020_imc"', 'type = "pid"\nparams = { kp = -500.0 }').replace(
            "duration_s = 0.5", "duration_s = 60.0"
        )
    )
    r = _twin_process("run", str(path))
    assert r.returncode == 3
    assert "diverged at t =" in r.stderr
    assert "Traceback" not in r.stderr


def test_demo_writes_recording(tmp_path):
    r = _twin("demo", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["machine"] == "linear_motor_xy"
    assert out["scenario"] == "choi1999_mimo_cutting"
    # Choi 1999's MIMO controller while cutting: tens of um per axis (paper: about 36 and 41 um)
    assert 10.0 < max(out["max_tracking_error_um"].values()) < 100.0
    entities = read_back(tmp_path / "demo.rrd")
    assert entities["/contour/actual"] == 1
    assert any("force" in e for e in entities), sorted(entities)


def test_run_writes_report_plots(tmp_path):
    r = _twin("run", "choi1999_air_cut_circle", "--set", "duration_s=0.2", "--plots", str(tmp_path / "plots"))
    assert r.returncode == 0, r.stderr
    pngs = sorted(p.name for p in (tmp_path / "plots").glob("*.png"))
    assert pngs == [f"choi1999_air_cut_circle_{k}.png" for k in ("contour", "control", "forces", "tracking_error")]
    assert all((tmp_path / "plots" / p).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)
    (tmp_path / "file").write_text("")
    r = _twin("run", "choi1999_air_cut_circle", "--plots", str(tmp_path / "file"))
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [f"error: --plots = {str(tmp_path / 'file')!r}: exists and is not a folder"]


def test_fidelity_json_keys():
    r = _twin("fidelity", "--machine", "cncmt", "--set", "m=60", "--json")
    assert r.returncode == 0, r.stderr
    (res,) = json.loads(r.stdout)
    for key in (
        "machine",
        "tf",
        "time_nrmse",
        "frf_max_mag_err_db",
        "frf_max_phase_err_deg",
        "coupling_slip_um",
        "pass",
    ):
        assert key in res
    assert res["tf"]["x"]["delay_s"] == 0.0
    assert res["pass"] is True


def test_fidelity_bad_set():
    r = _twin("fidelity", "--machine", "cncmt", "--set", "mass=3")
    assert r.returncode == 2
    assert "overrides.mass" in r.stderr


def test_list_and_bench():
    r = _twin("list")
    assert r.returncode == 0
    assert "linear_motor_xy" in r.stdout
    assert "yadav2020_hinf" in r.stdout
    assert "cascade" in r.stdout
    assert "inverse_model" in r.stdout
    assert "reproductions" in r.stdout
    r = _twin(
        "bench", "--json", "--seconds", "0.05", "--repeats", "3", "--gcode-lines", "3000", "--gcode-moves", "500",
        "--part-repeats", "0", "--planning-scale", "0.01",
    )  # fmt: skip
    figures = json.loads(r.stdout)
    assert figures["part"] is None  # the part's figures run whole programs: a slow test of their own
    start = figures["startup"]  # a new process does the in-process work and more; --help much less
    assert start["run_in_process_s"] < start["run_process_s"]
    assert 0 < start["help_process_s"] < start["run_process_s"]
    assert 0 < start["overhead_s"] < start["run_process_s"]
    cases = figures["cases"]
    assert sorted(cases) == [
        "cascade_dob_googol",
        "cutting_circle_linear_motor",
        "gcode_test_piece_linear_motor",
        "hinf_cncmt",
        "npid_googol",
    ]
    gcode = figures["gcode"]
    # the CAM program: 7 header lines (2 moves), 748 groups of 4 moves, M30 and %
    assert gcode["gcode_lines"] == 3000
    assert gcode["moves_read"] == 2 + 4 * 748
    assert gcode["read_lines_per_s"] > 0
    assert gcode["plan_moves"] == 502
    assert gcode["plan_s"] > 0
    assert gcode["plan_cycle_time_s"] > 40
    assert gcode["plan_moves_per_s"] == pytest.approx(502 / gcode["plan_s"])
    assert gcode["engagement_s"] > 0
    once, four_times = gcode["stream_peak_mb"].values()  # the stream's memory does not grow with its length
    assert len(gcode["stream_peak_mb"]) == 2
    assert four_times < 1.5 * once
    assert len(gcode["run_peak_mb"]) == 2
    assert all(mb > 0 for mb in gcode["run_peak_mb"].values())
    planning = figures["planning"]  # motion over planning CPU time, per program and limits
    assert sorted(planning) == ["arc_10_turns", "ball_finishing", "cam_like", "zigzag"]
    for by_limits in planning.values():
        assert sorted(by_limits) == ["linear_motor_xy", "slow"]
        for f in by_limits.values():
            assert f["ratio"] == pytest.approx(f["motion_s"] / f["plan_cpu_s"])
            assert f["violations"] == 0
    assert planning["zigzag"]["slow"]["motion_s"] > 200 * 10e-3 / 0.05  # 200 lines of 10 mm at 50 mm/s
    for figures in cases.values():  # a ratio of medians differs from the median of ratios by noise: not 5x
        assert figures["loop"] == "compiled"
        assert figures["raw_steps_per_s"] > 0
        assert figures["closed_loop_steps_per_s"] * figures["timestep_s"] == pytest.approx(figures["realtime_factor"])
        assert 0.2 < figures["ratio"] / (figures["closed_loop_steps_per_s"] / figures["raw_steps_per_s"]) < 5


@pytest.mark.slow
def test_reproduce_yadav2020_small_counts(tmp_path):
    rrd = tmp_path / "s0.rrd"
    r = _twin(
        "reproduce",
        "yadav2020",
        "--json",
        "--samples",
        "5",
        "--twin-samples",
        "0",
        "--rrd",
        str(rrd),
        "--plots",
        str(tmp_path / "plots"),
    )
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["twin_vs_tf_mismatches"] == []
    assert res["robust_pi"]["eq17_coefficients"]["kp"] == pytest.approx(38.33, rel=0.02)
    assert res["table2"]["hinf"]["tf_monte_carlo"]["overshoot_pct"][0] > 0
    assert len(list((tmp_path / "plots").glob("*.png"))) == 4
    counts = read_back(rrd)
    assert counts["/hinf/actual/x"] == 20_000 + 1  # 12 s at 10 kHz, decimated; + the legend entry
    # the text report (what `twin reproduce yadav2020` prints without --json) of the same results
    from twin.reproductions.registry import reproduction

    report = reproduction("yadav2020").format_report(res)
    assert "Table 2" in report
    assert "38.33" in report  # the paper's Kp beside ours


def test_reproduce_unknown_source_exits_2():
    r = _twin("reproduce", "smith2000")
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [
        "error: source = 'smith2000': no reproduction of that paper yet "
        "(known: yadav2020, sabau2022, anang2017, maharof2021, choi1999)"
    ]


@pytest.mark.slow
def test_reproduce_anang2017_transfer_functions_only(tmp_path):
    r = _twin("reproduce", "anang2017", "--json", "--twin-samples", "0", "--plots", str(tmp_path / "p"))
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert len(res["tables"]) == 16
    assert "twin" not in res["tables"][0]["anang2017_pid"]
    assert res["tables"][0]["anang2017_pid"]["tf_loop"]["max_mm"] == pytest.approx(0.0639, rel=0.01)  # paper's PID
    assert len(list((tmp_path / "p").glob("anang2017_*.png"))) == 3
    cut = [row for row in res["tables"] if row["rpm"] is not None]
    assert len(cut) == 12
    for row in cut:
        # Table 3's metric is the reduction of the maximum error: the paper's own Table 3 is its
        # Table 2 so reduced (to its two decimals), and ours is computed the same way
        key = f"{row['f_hz']} {row['a_mm']} {row['rpm']:.0f}"
        paper_pid, paper_npid = res["paper"]["table2"][key]
        assert row["paper_max_reduction_pct"] == pytest.approx((paper_pid - paper_npid) / paper_pid * 100, abs=0.01)
        pid, npid = row["anang2017_pid"]["tf_loop"], row["anang2017_npid"]["tf_loop"]
        assert row["max_reduction_pct_tf_loop"] == pytest.approx((pid["max_mm"] - npid["max_mm"]) / pid["max_mm"] * 100)
        assert row["rmse_reduction_pct_tf_loop"] == pytest.approx(
            (pid["rmse_mm"] - npid["rmse_mm"]) / pid["rmse_mm"] * 100
        )
    _same_as_committed(
        "anang2017",
        res,
        lambda out: [  # without the twin, the TF loop has no cutting force
            v
            for row in out["tables"]
            if row["rpm"] is None
            for v in (
                *row["anang2017_pid"]["tf_loop"].values(),
                *row["anang2017_npid"]["tf_loop"].values(),
                row["max_reduction_pct_tf_loop"],
            )
        ],
    )


def _same_as_committed(seed: str, res: dict, part) -> None:
    """The transfer-function part of a reproduction equals the committed JSON the docs' tables
    are generated from (``docs/results``): the pages cannot go stale on it."""
    from twin.reproductions.tables import results_path

    committed = json.loads(results_path(seed).read_text())
    assert part(res) == pytest.approx(part(committed), rel=1e-9), (
        f"docs/results/{seed}.json is stale: rerun "
        "`uv run python -m twin.reproductions.tables --rerun docs/results --write`"
    )


@pytest.mark.slow
def test_reproduce_maharof2021_transfer_functions_only():
    r = _twin("reproduce", "maharof2021", "--json", "--twin-samples", "0")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["design"]["velocity"]["gm_db"] == pytest.approx(9.37, abs=0.01)  # the thesis's margins, met
    assert res["design"]["velocity"]["pm_deg"] == pytest.approx(56.4, abs=0.01)
    assert res["design"]["q_cutoff_hz"] == 100.0
    assert len(res["cases"]) == 6
    _same_as_committed(
        "maharof2021",
        res,
        lambda out: (
            [
                row[c]["tf_loop"]["mte_um"]
                for rows in (out["cases"], *out["feedforward_cases"].values())
                for row in rows
                for c in ("cascade", "imbdo", "dfo", "imbdo_dfo")
            ]
            + [row["reduction_pct"]["mte"] for row in out["amplitude_study"]]
        ),
    )


@pytest.mark.slow
def test_reproduce_sabau2022_transfer_functions_only(tmp_path):
    r = _twin(
        "reproduce", "sabau2022", "--json", "--twin-samples", "0", "--samples", "2", "--plots", str(tmp_path / "p")
    )
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["relay"]["used"] == "tf"
    assert "twin" not in res["table1"]["p"]
    # ZN P from the 10 ms relay test: Table 1's 20 % / 8 % overshoot within a few points
    assert [m["overshoot_pct"] for m in res["table1"]["p"]["tf"]] == pytest.approx([20.0, 8.0], abs=2.0)
    assert all(res["lmi"][d]["in_region"] == [True, True] for d in ("lmi", "pi_p_lmi"))
    assert len(list((tmp_path / "p").glob("sabau2022_*.png"))) == 7  # the trajectories need the twin


def test_run_cutting_scenario_with_settings_and_recording(tmp_path):
    rrd = tmp_path / "slot.rrd"
    r = _twin(
        "run",
        "slot_linear_motor",
        "--set",
        "duration_s=0.3",
        "--set",
        "disturbances.0.axial_depth_mm=1.0",
        "--rrd",
        str(rrd),
        "--json",
    )
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    # 1 mm deep slot at 0.1 mm/tooth: the mean feed-normal force is ~56 N, peaks above it
    assert 56.0 < out["max_cutting_force_N"]["y"] < 200.0
    counts = read_back(rrd)
    assert counts["/force/cutting/x"] == counts["/force/cutting/y"] == 600 + 1  # 0.3 s at 2 kHz


@pytest.mark.parametrize(
    "setting, message",
    [
        ("disturbances.3.spindle_rpm=1", "--set disturbances.3.spindle_rpm = '3'"),
        ("disturbances.0.radial_depth_mm=20", "disturbances.0.radial_depth_mm = 20"),
        ("duration_s", "--set = 'duration_s'"),
    ],
)
def test_run_bad_setting(setting, message):
    r = _twin("run", "slot_linear_motor", "--set", setting)
    assert r.returncode == 2
    assert message in r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize(
    "args, field",
    [
        (["--set", "duration_s=nan"], "duration_s = nan"),
        (["--set", "overrides.n_x=1e200"], "overrides = '{...}': n_x = 1e+200 is beyond"),
        (["--set", "duration_s=1e308"], "duration_s = 1e+308"),
        (["--set", "timestep_s=5e-324"], "timestep_s = 5e-324"),
        (["--set", "timestep_s=5e-324", "--set", "control_period_s=5e-324"], "timestep_s = 5e-324"),
        (
            ["--set", 'reference.type="polyline"', "--set", "reference.points_mm=[[0,0],[1e157,0]]"],
            "reference.points_mm.1.0 = 1e+157",
        ),
        (["--set", "seed=-1"], "seed = -1"),
        (["--set", "reference.radius_mm=5e-324"], "reference.radius_mm"),
        (["--set", "duration_s=1e-5"], "shorter than one control period"),
        (["--max-steps", "1000"], "more than the 1,000 allowed"),
        (["--rrd", "/nonexistent-folder/x.rrd"], "--rrd = '/nonexistent-folder/x.rrd'"),
        (["--set", "machine=\x1b[31m" + "a" * 300], "machine = '\\x1b[31maaaa"),
    ],
)
def test_hostile_input_is_one_error_line(args, field):
    """Each is refused before the run, in one line naming the field (values escaped, shortened)."""
    r = _twin("run", "demo_circle_cncmt_xy", *args)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1, r.stderr
    assert field in lines[0], r.stderr
    assert len(lines[0]) < 700
    assert "\x1b" not in lines[0]


def test_scenario_that_is_a_folder_or_not_utf8(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b'machine = "cncmt"\n\xff\xfe\n')
    for target, words in ((tmp_path, "is a folder"), (bad, "not UTF-8")):
        r = _twin("run", str(target))
        assert r.returncode == 2
        assert words in r.stderr
        assert "Traceback" not in r.stderr


def test_divergence_keeps_the_partial_run(tmp_path):
    """Exit 3 after printing how far the run got and writing its recording up to there."""
    path = tmp_path / "div.toml"
    path.write_text(
        GOOD.replace('type = "yadav2020_imc"', 'type = "pid"\nparams = { kp = -500.0 }').replace(
            "duration_s = 0.5", "duration_s = 60.0"
        )
    )
    r = _twin("run", str(path), "--json", "--rrd", str(tmp_path / "div.rrd"))
    assert r.returncode == 3
    assert r.stderr.strip().splitlines()[-1].startswith("error: simulation diverged at t = 0.17")
    out = json.loads(r.stdout)
    assert out["status"] == "diverged"
    assert out["completed_ticks"] == 170
    assert out["sim_time_s"] == pytest.approx(0.17)
    assert read_back(tmp_path / "div.rrd")["/actual/x"] == 170 + 1


def test_interrupt_keeps_the_partial_run(tmp_path):
    """SIGINT in a long run: exit 130, JSON of the ticks done, a valid recording of them (an hour
    simulated: the compiled loop runs 600 s in about 3 s, which a loaded machine's test process
    could sleep through)."""
    import signal
    import threading
    import time

    p = subprocess.Popen(
        [
            *TWIN,
            "run",
            "demo_circle_cncmt_xy",
            "--set",
            "duration_s=1800",
            "--rrd",
            str(tmp_path / "cut.rrd"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )
    err = []
    reader = threading.Thread(target=lambda: err.extend(iter(lambda: p.stderr.read(1), "")), daemon=True)
    reader.start()
    deadline = time.time() + 120
    # the progress bar counting ticks (after numba's compilation, which a cold cache makes slow)
    while not re.search(r"\| [1-9]\d*/1800000", "".join(err)) and time.time() < deadline:
        time.sleep(0.2)
    time.sleep(1.0)
    p.send_signal(signal.SIGINT)
    out = p.stdout.read()
    p.wait(timeout=60)
    reader.join(timeout=10)
    lines = "".join(err).strip().splitlines()
    assert p.returncode == 130, lines[-3:]
    assert lines[-1].startswith("error: interrupted at t = "), lines[-3:]
    summary = dict(line.split(None, 1) for line in out.splitlines()[1:])  # the text summary, key and value
    assert summary["status"] == "interrupted"
    assert 0 < int(summary["completed_ticks"]) < 1_800_000
    assert read_back(tmp_path / "cut.rrd")["/reference/x"] > 0


@pytest.mark.parametrize("scenario", ["cascade_observer_googol", "step_cncmt_hinf", "choi1999_cutting_circle"])
def test_run_imports_only_what_it_needs(scenario):
    """twin run of a bundled scenario (observer, 4th-order H-infinity, milling) loads neither
    python-control nor scipy.signal, matplotlib or rerun (without --rrd): together about 2 s of
    start-up."""
    code = (
        f"import sys; from twin.cli import main; sys.argv = ['twin', 'run', {scenario!r}, '--json', '--set', "
        "'duration_s=0.01']\ntry:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
        "heavy = ('control', 'scipy.signal', 'matplotlib', 'rerun', 'pandas', 'twin.reproductions.registry')\n"
        "print(sorted(m for m in heavy if m in sys.modules))"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().splitlines()[-1] == "[]"


LAUNCHER = [sys.executable, "-m", "twin.launcher"]


def test_launcher_lists_a_program_with_the_reader_alone(tmp_path):
    """``twin gcode FILE --json`` (the console script's fast path): the JSON of every move is
    the reader's ``as_dict()``; a refused program prints nothing on stdout and one error line;
    a pipe closed early ends it quietly; any other command line goes to the full CLI."""
    from twin.gcode.reader import read_program
    from twin.launcher import plain_listing

    program = tmp_path / "part.ngc"
    program.write_text("G21 G90 (cam)\nG0 X1 Y2 Z3\nG1 X4 F600 M8\nG2 X6 Y2 I1 J0\nG4 P0.5\nM30\n")
    r = subprocess.run([*LAUNCHER, "gcode", str(program), "--json"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    assert r.stderr == ""
    assert json.loads(r.stdout)["moves"] == [move.as_dict() for move in read_program(program)]
    assert len(json.loads(r.stdout)["moves"]) == 4
    r = subprocess.run([*LAUNCHER, "gcode", str(program)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    assert r.stdout.splitlines()[3].split()[:2] == ["4", "arc"]

    program.write_text("G21\nG0 X1\nG1 X2 F100\nG41 D3 X3\n")
    r = subprocess.run(
        [*LAUNCHER, "gcode", "part.ngc", "--json"], capture_output=True, text=True, timeout=60, cwd=tmp_path
    )
    assert (r.returncode, r.stdout) == (2, "")
    assert r.stderr.splitlines() == [
        "error: part.ngc:4 = 'G41 D3 X3': Requested tool 3 not found in the tool table (reference.tool_diameters_mm)"
    ]

    program.write_text("G21 G0 X0\n" + "G1 X1 F100\nX0\n" * 20_000)
    r = subprocess.run(
        f"{sys.executable} -m twin.launcher gcode {program} | head -c 100", shell=True, capture_output=True, text=True
    )
    assert len(r.stdout) == 100
    assert r.stderr == ""

    assert plain_listing(["gcode", "a.ngc", "--json"]) == (Path("a.ngc"), True)
    assert plain_listing(["gcode", "--json", "a.ngc"]) == (Path("a.ngc"), True)
    assert plain_listing(["gcode", "a.ngc"]) == (Path("a.ngc"), False)
    for argv in (
        ["gcode", "a.ngc", "--machine", "x"],
        ["gcode", "--help"],
        ["gcode"],
        ["run", "a"],
        ["gcode", "a", "b"],
    ):
        assert plain_listing(argv) is None
    r = subprocess.run([*LAUNCHER, "gcode", "--help"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    assert "--machine" in r.stdout
