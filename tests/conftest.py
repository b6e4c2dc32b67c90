"""Tests never write into the checkout: numba's compiled-function cache goes to a folder in the
system's temporary directory (one per checkout, so later runs reuse it), and subprocesses of
the CLI tests inherit it; pytest's own cache is off (pyproject.toml)."""

import hashlib
import os
import tempfile
from pathlib import Path

_checkout = Path(__file__).resolve().parent.parent
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(
    tempfile.gettempdir(), "cnc-twin-numba-" + hashlib.sha1(str(_checkout).encode()).hexdigest()[:12]))

from hypothesis import settings  # noqa: E402

# property-based tests: `uv run pytest --hypothesis-profile thorough` for the long run
settings.register_profile("default", max_examples=150)
settings.register_profile("thorough", max_examples=10_000)
