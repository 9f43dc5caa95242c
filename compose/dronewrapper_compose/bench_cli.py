"""``dronewrapper bench``: the repository's benchmarks, run from the repository.

``bench --quick [...]`` is the self-benchmark (``bench/quick.py``: this computer's speed and
the settings to use); ``bench [NAME...]`` the full benchmarks. They are scripts in ``bench/``,
beside ``compose/``, so this command exists where the repository is installed from source.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence

from dronewrapper_compose.graph import REPO


def main(argv: Sequence[str]) -> int:
    """Run ``python -m bench.quick`` (with ``--quick``) or ``python -m bench`` in the
    repository; 2 when there is no ``bench/`` beside ``compose/``."""
    if not (REPO / "bench" / "quick.py").is_file():
        print(f"dronewrapper bench: no bench/ beside {REPO / 'compose'}", file=sys.stderr)
        return 2
    quick = "--quick" in argv
    module = "bench.quick" if quick else "bench"
    rest = [a for a in argv if a != "--quick"] if quick else list(argv)
    return subprocess.call([sys.executable, "-m", module, *rest], cwd=REPO)
