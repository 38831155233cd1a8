"""An expensive session fixture built once per test run, not once per pytest-xdist worker."""

import json
import os
from collections.abc import Callable
from typing import Any

try:
    import fcntl
except ImportError:  # not on Windows: each worker builds its own
    fcntl = None  # type: ignore[assignment]


def once_per_run(tmp_path_factory, name: str, build: Callable[[], Any]) -> Any:
    """``build()``'s JSON value, built by the first worker that asks and read back by the
    others from a file beside their temporary folders (which one run's workers share); a
    lock makes the others wait for the first. Without xdist, ``build()`` as JSON."""
    if fcntl is None or "PYTEST_XDIST_WORKER" not in os.environ:
        return json.loads(json.dumps(build()))
    root = tmp_path_factory.getbasetemp().parent
    path = root / f"{name}.json"
    with open(root / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.is_file():
            text = json.dumps(build())
            (root / f"{name}.tmp").write_text(text)
            (root / f"{name}.tmp").replace(path)
        return json.loads(path.read_text())
