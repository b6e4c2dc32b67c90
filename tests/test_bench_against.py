"""``twin bench --against REV`` (twin/bench_against.py): the commit's temporary worktree, the
alternation of the two trees and the ratio B/A from their timings; no timing is asserted."""

from __future__ import annotations

import json
import statistics
import subprocess
from pathlib import Path

import pytest
from cli_process import twin

from twin.bench_against import CHECKOUT, alternate, resolve_commit, temporary_worktree
from twin.errors import TwinInputError


def _git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(CHECKOUT), *args], capture_output=True, text=True, check=True).stdout


def _worktrees() -> str:
    return _git("worktree", "list", "--porcelain")


def test_alternate_times_a_then_b_and_takes_the_median_of_the_pairs_ratios():
    calls: list[tuple[str, str]] = []
    # closed-loop steps/s by round: A drifts down (a loaded machine), B is A's round times 0.9,
    # except one outlier round where B was preempted
    a_closed = {"x": [100.0, 80.0, 90.0, 70.0, 60.0], "y": [10.0, 20.0, 30.0, 40.0, 50.0]}
    b_closed = {"x": [90.0, 72.0, 81.0, 7.0, 54.0], "y": [12.0, 24.0, 36.0, 48.0, 60.0]}

    def timing(tree: str, closed: dict[str, list[float]]):
        def time(case: str) -> dict:
            k = sum(1 for t, c in calls if t == tree and c == case)
            calls.append((tree, case))
            wall = closed[case][k]  # a CPU second does 3 times a wall second's steps
            return {
                "closed_loop_steps_per_s": wall,
                "bare_steps_per_s": 2 * wall,
                "closed_loop_steps_per_cpu_s": 3 * wall,
                "bare_steps_per_cpu_s": 4 * wall,
                "loop": tree,
            }

        return time

    out = alternate(timing("a", a_closed), timing("b", b_closed), ["x", "y"], 5)
    assert calls == [(tree, case) for _ in range(5) for case in ("x", "y") for tree in ("a", "b")]
    for case in ("x", "y"):
        pairs = [b / a for a, b in zip(a_closed[case], b_closed[case])]
        assert out[case]["b_over_a"] == pytest.approx(statistics.median(pairs))
        assert out[case]["a"]["closed_loop_steps_per_s"] == statistics.median(a_closed[case])
        assert out[case]["b"]["closed_loop_steps_per_s"] == statistics.median(b_closed[case])
        assert out[case]["a"]["bare_steps_per_s"] == 2 * statistics.median(a_closed[case])
        assert out[case]["a"]["ratio"] == pytest.approx(0.5)
        assert out[case]["b"]["ratio_cpu"] == pytest.approx(0.75)
        assert out[case]["b_over_a_cpu"] == pytest.approx(out[case]["b_over_a"])
        assert out[case]["a"]["closed_loop_steps_per_cpu_s"] == 3 * statistics.median(a_closed[case])
        assert out[case]["b"]["loop"] == "b"
    assert out["x"]["b_over_a"] == pytest.approx(0.9)  # the preempted round does not move the median
    assert out["y"]["b_over_a"] == pytest.approx(1.2)


def test_temporary_worktree_holds_the_commit_and_is_removed_even_after_an_error():
    head = resolve_commit("HEAD")
    assert head == _git("rev-parse", "HEAD").strip()
    with pytest.raises(RuntimeError, match="inside"), temporary_worktree(head) as folder:
        tree = folder / "tree"
        assert str(tree) in _worktrees()
        assert subprocess.run(
            ["git", "-C", str(tree), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip() == head  # fmt: skip
        assert (tree / "twin" / "bench.py").read_text() == _git("show", "HEAD:twin/bench.py")
        assert not folder.is_relative_to(CHECKOUT)
        raise RuntimeError("inside")
    assert not folder.exists()
    assert str(tree) not in _worktrees()


def test_a_bad_revision_is_one_error_line_and_exit_2():
    with pytest.raises(TwinInputError, match="--against"):
        resolve_commit("no-such-revision-anywhere")
    r = twin("bench", "--against", "no-such-revision-anywhere")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "--against" in lines[0] and "no-such-revision-anywhere" in lines[0]
    r = twin("bench", "--against", "--json")  # an option where the revision should be
    assert r.returncode == 2
    r = twin("bench", "--case", "hinf_cncmt")
    assert r.returncode == 2 and "--case" in r.stderr


@pytest.mark.slow
def test_against_head_times_one_case_in_both_trees(tmp_path: Path):
    before = _worktrees()
    r = twin("bench", "--against", "HEAD", "--case", "npid_googol", "--repeats", "1", "--seconds", "0.01", "--json")
    assert r.returncode == 0, r.stderr
    f = json.loads(r.stdout)
    assert f["a_commit"] == f["b_commit"] == _git("rev-parse", "HEAD").strip()
    case = f["cases"]["npid_googol"]
    # one pair: the ratio is B's timing over A's
    assert case["b_over_a"] == case["b"]["closed_loop_steps_per_s"] / case["a"]["closed_loop_steps_per_s"]
    cpu = case["b"]["closed_loop_steps_per_cpu_s"] / case["a"]["closed_loop_steps_per_cpu_s"]
    assert case["b_over_a_cpu"] == cpu
    assert case["a"]["loop"] == case["b"]["loop"]
    assert _worktrees() == before
    r = twin("bench", "--against", "HEAD", "--case", "no_such_case", "--repeats", "1")
    assert r.returncode == 2 and "no_such_case" in r.stderr
    assert _worktrees() == before
