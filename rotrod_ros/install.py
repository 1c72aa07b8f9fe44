"""Where the installed package's executables and shared files are (no ROS import).

Works for a colcon install (``<prefix>/lib/rotrod``, ``<prefix>/share/rotrod``, found
through ament_index as ``ros2 run`` does), a pip or venv install (scripts beside the
interpreter, data in ``<sys.prefix>/share/rotrod``) and an editable source checkout.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
from pathlib import Path

PACKAGE = 'rotrod'
SOURCE_ROOT = Path(__file__).resolve().parent.parent


def _ament_prefix() -> Path | None:
    if not os.environ.get('AMENT_PREFIX_PATH'):
        return None
    with contextlib.suppress(Exception):
        from ament_index_python.packages import get_package_prefix
        return Path(get_package_prefix(PACKAGE))
    return None


def executable(name: str) -> list[str]:
    """The command (argv list) for one of the package's executables, e.g. ``simulator``.

    Looked up beside ``sys.executable`` (venv or pip install), then in
    ``<prefix>/lib/rotrod`` of a colcon install on AMENT_PREFIX_PATH, then on PATH.
    """
    candidates = [Path(sys.executable).parent / name]
    prefix = _ament_prefix()
    if prefix is not None:
        candidates.append(prefix / 'lib' / PACKAGE / name)
    for cand in candidates:
        if cand.is_file() and os.access(cand, os.X_OK):
            return [str(cand)]
    found = shutil.which(name)
    if found:
        return [found]
    raise FileNotFoundError(f'executable {name!r} not found (looked in '
                            f'{", ".join(map(str, candidates))} and on PATH); '
                            'is the package installed (pip install -e . / colcon build)?')


def share_file(relative: str) -> Path:
    """A file installed under ``share/rotrod`` (e.g. ``config/table1.yaml``)."""
    roots = []
    prefix = _ament_prefix()
    if prefix is not None:
        roots.append(prefix / 'share' / PACKAGE)
    roots += [Path(sys.prefix) / 'share' / PACKAGE, SOURCE_ROOT]
    for root in roots:
        if (root / relative).is_file():
            return root / relative
    raise FileNotFoundError(f'{relative} not found under {", ".join(map(str, roots))}')
