"""A disk cache of planned spin-ups: the same request is planned once per code version.

Planning a spin-up takes seconds to minutes (a robust plan, about half a minute on
this project's machine), and its answer depends only on the request and the code: it
is the same on every CPU and BLAS kernel (``test_planner``'s cross-kernel test). So
a node or a command that plans at its start (``profile_publisher``, ``rotrod demo
--profile planned``) plans once and starts at once the next time.

An entry is keyed by the SHA-256 of the request (the rod's parameters and the plan's
settings, floats exactly), of every source file of ``rotrod_core``, and of the numpy,
scipy and Python versions: any change of the code or of those libraries plans anew. It
holds the plan as JSON (the :class:`SpinUpProfile`'s arguments, floats exactly), or
the reason no plan exists. Unreadable or malformed entries are planned again and
overwritten; a cache that cannot be written is skipped. At most :data:`MAX_ENTRIES`
are kept (the least recently written go).

Where: ``ROTROD_PLAN_CACHE`` names the directory; ``off`` turns the cache off;
unset, ``$XDG_CACHE_HOME/rotrod/plans`` (``~/.cache/rotrod/plans``).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import tempfile
from collections.abc import Callable
from importlib import metadata
from pathlib import Path

from .profiles import SpinUpProfile

ENV = 'ROTROD_PLAN_CACHE'
OFF = 'off'
MAX_ENTRIES = 256
_CORE = Path(__file__).resolve().parents[1]
_FIELDS = ('duration', 'control_points', 'peak_deflection', 'residual_amplitude',
           'band_residual', 'robust', 't_start')


def directory() -> Path | None:
    """The cache's directory (None: the cache is off)."""
    where = os.environ.get(ENV)
    if where is not None:
        return None if where.strip().lower() in (OFF, '') else Path(where)
    base = os.environ.get('XDG_CACHE_HOME') or str(Path.home() / '.cache')
    return Path(base) / 'rotrod' / 'plans'


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 of rotrod_core's sources and the numerical libraries' versions."""
    h = hashlib.sha256()
    for path in sorted(_CORE.rglob('*.py')):
        h.update(str(path.relative_to(_CORE)).encode() + b'\0' + path.read_bytes() + b'\0')
    for package in ('numpy', 'scipy'):
        h.update(f'{package}=={metadata.version(package)}\0'.encode())
    h.update(platform.python_version().encode())
    return h.hexdigest()


def key(request: dict) -> str:
    """The entry's name for ``request`` (JSON-able: floats, strings, None)."""
    text = json.dumps(request, sort_keys=True, default=float)
    return hashlib.sha256((code_fingerprint() + '\0' + text).encode()).hexdigest()


def _encode(result: SpinUpProfile | ValueError) -> dict:
    if isinstance(result, ValueError):
        return {'error': str(result)}
    plan = {name: getattr(result, name) for name in _FIELDS}
    plan['control_points'] = [float(c) for c in result.control_points]
    return {'plan': plan}


def _decode(entry: dict) -> SpinUpProfile | ValueError:
    if set(entry) == {'error'} and isinstance(entry['error'], str):
        return ValueError(entry['error'])
    plan = entry['plan']
    if set(plan) != set(_FIELDS):
        raise ValueError('not a cached plan')
    return SpinUpProfile(plan['duration'], plan['control_points'],
                         peak_deflection=plan['peak_deflection'],
                         residual_amplitude=plan['residual_amplitude'],
                         band_residual=plan['band_residual'], robust=plan['robust'],
                         t_start=plan['t_start'])


def _read(path: Path) -> SpinUpProfile | ValueError | None:
    try:
        return _decode(json.loads(path.read_text()))
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None                         # absent or malformed: plan again


def _write(folder: Path, path: Path, result: SpinUpProfile | ValueError) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile('w', dir=folder, suffix='.tmp', delete=False) as f:
            json.dump(_encode(result), f)
        os.replace(f.name, path)
        entries = sorted(folder.glob('*.json'), key=lambda p: p.stat().st_mtime)
        for old in entries[:max(0, len(entries) - MAX_ENTRIES)]:
            old.unlink(missing_ok=True)
    except OSError:
        pass                                # a cache that cannot be written is skipped


def cached_plan(request: dict, plan: Callable[[], SpinUpProfile]) -> SpinUpProfile:
    """The plan for ``request``: from the cache, else ``plan()`` (then stored).

    A ValueError from ``plan()`` (no plan exists) is stored and raised again.
    """
    folder = directory()
    if folder is None:
        return plan()
    path = folder / f'{key(request)}.json'
    result = _read(path)
    if result is None:
        try:
            result = plan()
        except ValueError as exc:
            result = exc
        _write(folder, path, result)
    if isinstance(result, ValueError):
        raise result
    return result


__all__ = ['ENV', 'MAX_ENTRIES', 'OFF', 'cached_plan', 'code_fingerprint', 'directory',
           'key']
