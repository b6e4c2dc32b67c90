"""Tests never write into the checkout: numba's compiled-function cache and hypothesis's
storage go to folders in the system's temporary directory (one per checkout, so later runs
reuse them), and subprocesses of the CLI tests inherit them; pytest's own cache is off
(pyproject.toml).

The two test workers (pytest-xdist, ``-n 2``) take a core each: OpenBLAS keeps to one thread in
each (set here, before the workers start and load numpy; their subprocesses inherit it). With
its default of a thread per core, two workers' threads contend for the 2 cores: the tuning,
calibration and FRF tests took 25 % longer."""

import hashlib
import os
import tempfile
from pathlib import Path

_checkout = Path(__file__).resolve().parent.parent
_tag = hashlib.sha1(str(_checkout).encode()).hexdigest()[:12]
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(tempfile.gettempdir(), "cnc-twin-numba-" + _tag))
# hypothesis's example database and caches (its default: .hypothesis/ in the working folder)
os.environ.setdefault(
    "HYPOTHESIS_STORAGE_DIRECTORY", os.path.join(tempfile.gettempdir(), "cnc-twin-hypothesis-" + _tag)
)

from hypothesis import settings  # noqa: E402

# Property-based tests. The default profile (the README's test command and CI) is derandomized:
# the same 150 examples on every run and every machine, with no example database, so the suite
# passes or fails the same way each time. `uv run pytest tests/test_fuzz_cli.py
# --hypothesis-profile thorough` explores 10 000 new examples (random, with the database, so a
# failure it finds is replayed first next time).
settings.register_profile("thorough", max_examples=10_000, derandomize=False)
settings.register_profile("default", max_examples=150, derandomize=True, database=None)
settings.load_profile("default")
