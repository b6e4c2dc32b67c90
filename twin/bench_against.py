"""``twin bench --against REV``: the closed-loop cases of two trees timed alternately.

Tree A is the commit ``REV``, checked out into a temporary git worktree (in the system's
temporary folder, removed afterwards with its numba cache); tree B is this checkout as it is on
disk (uncommitted edits included).  One worker process per tree (:mod:`twin.bench_worker`, run
with the tree first on ``PYTHONPATH`` and this checkout's Python environment) builds that tree's
bench cases and warms them up; then, ``repeats`` times, every case is timed in A and at once in
B (A, B, A, B, ...): bare ``mj_step`` and the closed loop back to back in each.  Reported per
case: each tree's medians (closed-loop and bare steps/s, closed/bare) and ``b_over_a``, the
median of the per-pair ratios of closed-loop steps/s B/A, each from two timings taken one after
the other, so a busy machine slows both and the ratio less; ``b_over_a_cpu`` the same per second
of the worker thread's CPU time (``time.thread_time``), which leaves out the waits for a core
that a machine shared with other work adds to wall time.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

from twin import bench_worker
from twin.errors import TwinInputError

#: The checkout this twin is imported from (tree B).
CHECKOUT = Path(__file__).resolve().parent.parent


def _git(*args: str, root: Path = CHECKOUT) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, check=False)


def resolve_commit(rev: str, root: Path = CHECKOUT) -> str:
    """The full hash of ``rev`` in the git repository at ``root``.

    Raises
    ------
    TwinInputError
        Under ``--against`` where ``root`` is no git checkout or ``rev`` names no commit in it.
    """
    if rev.startswith("-") or not rev.strip():
        raise TwinInputError("--against", rev, "is not a commit of this checkout")
    try:
        found = _git("rev-parse", "--verify", "--quiet", f"{rev}^{{commit}}", root=root)
    except OSError as exc:
        raise TwinInputError("--against", rev, f"git cannot be run: {exc.strerror or exc}") from None
    if found.returncode != 0:
        where = "this checkout" if _git("rev-parse", "--git-dir", root=root).returncode == 0 else "a git checkout"
        raise TwinInputError("--against", rev, f"is not a commit of {where} ({root})")
    return found.stdout.strip()


@contextmanager
def temporary_worktree(commit: str, root: Path = CHECKOUT) -> Iterator[Path]:
    """A detached git worktree of ``commit`` in a new temporary folder, removed (with the folder
    and git's record of it) on leaving, whatever happened inside.

    Yields
    ------
    Path
        The folder: the tree at ``tree/``; the rest of it is free for the caller's files.
    """
    folder = Path(tempfile.mkdtemp(prefix="twin-bench-against-"))
    tree = folder / "tree"
    try:
        added = _git("worktree", "add", "--detach", "--quiet", str(tree), commit, root=root)
        if added.returncode != 0:
            raise TwinInputError("--against", commit, f"git worktree add failed: {added.stderr.strip()}")
        yield folder
    finally:
        if tree.exists():
            _git("worktree", "remove", "--force", str(tree), root=root)
        shutil.rmtree(folder, ignore_errors=True)
        _git("worktree", "prune", root=root)


class Worker:
    """A :mod:`twin.bench_worker` process on one tree: its cases built and warmed up.

    Parameters
    ----------
    tree
        The tree's root (first on the worker's ``PYTHONPATH``).
    label
        The tree's name in error lines.
    names
        Cases to warm up and time; empty: all of the tree's.
    log
        File that takes the worker's standard error.
    numba_cache
        ``NUMBA_CACHE_DIR`` of the worker; None keeps the environment's.
    """

    def __init__(self, tree: Path, label: str, names: list[str], log: IO[str], *, numba_cache: Path | None = None):
        env = {**os.environ, "PYTHONPATH": str(tree)}
        if numba_cache is not None:
            env["NUMBA_CACHE_DIR"] = str(numba_cache)
        self.label = label
        self._log = log
        self._process = subprocess.Popen(
            [sys.executable, "-P", bench_worker.__file__, *names],
            cwd=tree,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=log,
            text=True,
        )
        ready = self._answer()
        if "unknown" in ready:
            self.close()
            raise TwinInputError("--case", ", ".join(ready["unknown"]), f"not a case of {label}: {ready['cases']}")
        self.names: list[str] = ready["ready"]

    def _answer(self) -> dict:
        assert self._process.stdout is not None
        line = self._process.stdout.readline()
        if not line:
            self.close()
            self._log.seek(0)
            lines = [text for text in self._log.read().splitlines() if text.strip()]
            raise TwinInputError("--against", self.label, f"its bench worker stopped: {lines[-1] if lines else ''}")
        return json.loads(line)

    def time(self, case: str, seconds: float) -> dict:
        """One timing of ``case`` (``seconds`` simulated): steps per wall and per CPU second,
        bare and closed-loop, and ``loop`` (:mod:`twin.bench_worker`)."""
        assert self._process.stdin is not None
        self._process.stdin.write(json.dumps({"case": case, "seconds": seconds}) + "\n")
        self._process.stdin.flush()
        return self._answer()

    def __enter__(self) -> Worker:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        """End the worker (its input closed; killed if it has not ended in 60 s)."""
        if self._process.stdin is not None and not self._process.stdin.closed:
            self._process.stdin.close()
        try:
            self._process.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        if self._process.stdout is not None:
            self._process.stdout.close()


def alternate(
    time_a: Callable[[str], dict], time_b: Callable[[str], dict], cases: list[str], repeats: int
) -> dict[str, dict]:
    """Time every case in A and then in B, ``repeats`` rounds over all cases (A, B, A, B, ...).

    Parameters
    ----------
    time_a, time_b
        One timing of a case by name in tree A, B: ``bare_steps_per_s``,
        ``closed_loop_steps_per_s`` (steps per wall second), ``bare_steps_per_cpu_s``,
        ``closed_loop_steps_per_cpu_s`` (per second of the worker thread's CPU time) and ``loop``.
    cases
        Case names, in the order timed within a round.
    repeats
        Rounds.

    Returns
    -------
    dict
        ``<case>.{a, b}.{closed_loop_steps_per_s, bare_steps_per_s, ratio,
        closed_loop_steps_per_cpu_s, ratio_cpu, loop}`` (medians; ``ratio``: the median of
        closed/bare of each timing) and ``<case>.b_over_a``, the median of the per-round ratios
        of closed-loop steps/s B over A (``b_over_a_cpu``: per CPU second).
    """
    timings: dict[str, list[tuple[dict, dict]]] = {case: [] for case in cases}
    for _ in range(repeats):
        for case in cases:
            a = time_a(case)
            timings[case].append((a, time_b(case)))
    out = {}
    for case, pairs in timings.items():
        out[case] = {
            "a": _medians([a for a, _b in pairs]),
            "b": _medians([b for _a, b in pairs]),
            "b_over_a": statistics.median(
                b["closed_loop_steps_per_s"] / a["closed_loop_steps_per_s"] for a, b in pairs
            ),
            "b_over_a_cpu": statistics.median(
                b["closed_loop_steps_per_cpu_s"] / a["closed_loop_steps_per_cpu_s"] for a, b in pairs
            ),
        }
    return out


def _medians(timings: list[dict]) -> dict:
    return {
        "closed_loop_steps_per_s": statistics.median(t["closed_loop_steps_per_s"] for t in timings),
        "bare_steps_per_s": statistics.median(t["bare_steps_per_s"] for t in timings),
        "ratio": statistics.median(t["closed_loop_steps_per_s"] / t["bare_steps_per_s"] for t in timings),
        "closed_loop_steps_per_cpu_s": statistics.median(t["closed_loop_steps_per_cpu_s"] for t in timings),
        "ratio_cpu": statistics.median(t["closed_loop_steps_per_cpu_s"] / t["bare_steps_per_cpu_s"] for t in timings),
        "loop": timings[-1]["loop"],
    }


def compare(rev: str, cases: list[str], seconds: float, repeats: int) -> dict:
    """``twin bench --against rev``: see the module docstring.

    Parameters
    ----------
    rev
        Tree A: a commit (hash, branch, tag, ``HEAD~3``...) of this checkout's repository.
    cases
        Case names; empty: the cases both trees have (in this checkout's order).
    seconds
        Simulated time of each timing (s).
    repeats
        Alternating rounds.

    Returns
    -------
    dict
        ``against``, ``a_commit``, ``b_commit`` (this checkout's HEAD), ``b_modified`` (uncommitted
        edits in the tracked files), ``simulated_s``, ``repeats``, ``only_in_a``, ``only_in_b``
        (cases one tree lacks) and ``cases`` (:func:`alternate`).
    """
    commit = resolve_commit(rev)
    with (
        temporary_worktree(commit) as folder,
        (folder / "a.log").open("w+") as log_a,
        (folder / "b.log").open("w+") as log_b,
        Worker(folder / "tree", f"tree A ({rev})", cases, log_a, numba_cache=folder / "numba") as a,
        Worker(CHECKOUT, "tree B (this checkout)", cases, log_b) as b,
    ):
        common = [name for name in b.names if name in a.names]
        figures = alternate(lambda case: a.time(case, seconds), lambda case: b.time(case, seconds), common, repeats)
    return {
        "against": rev,
        "a_commit": commit,
        "b_commit": resolve_commit("HEAD"),
        "b_modified": _git("diff", "--quiet", "HEAD").returncode != 0,
        "simulated_s": seconds,
        "repeats": repeats,
        "only_in_a": [name for name in a.names if name not in b.names],
        "only_in_b": [name for name in b.names if name not in a.names],
        "cases": figures,
    }
