"""The repository built by colcon as a ROS user builds it, for the tests that need it.

``copy_sources(ws)`` puts the repository's files (``git ls-files --cached --others
--exclude-standard``: nothing from ``.venv`` or ``build``) in ``<ws>/src/rotrod``.
``build_with_interfaces(ws)`` runs ``colcon build --base-paths src
src/rotrod/rotrod_interfaces src/rotrod/simulation_interfaces src/rotrod/control_msgs``
(docs/usage.md): the four packages, with this venv as the ROS install (its ament and
rosidl build wheels, cmake and ninja, as tools/build_interfaces.py sets them up).

That build is made once per test session (conftest's ``colcon_interfaces`` fixture):
test/project/test_colcon_build.py checks it, and test/ros/test_simulation_control.py's
client talks to the simulator through its ``simulation_interfaces``, built from the
upstream definitions apart from the venv's.
"""

import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from interface_tools import build_interfaces

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = 'rotrod'
EXCLUDED_DIRS = {'.git', '.venv', 'build', 'install', 'log', '__pycache__', '.pytest_cache',
                 '.ruff_cache', '.hypothesis'}
BUILD_TIMEOUT = 900
"""s: the four packages took 365 s here with the machine idle (control_msgs' C and C++
typesupports); in .ci/run they build at nice 19 beside the soak."""


def source_files() -> list:
    """Repository files a checkout would contain (relative paths)."""
    try:
        proc = subprocess.run(
            ['git', 'ls-files', '-z', '--cached', '--others', '--exclude-standard'],
            cwd=ROOT, capture_output=True, check=True, timeout=60)
        files = [f for f in proc.stdout.decode().split('\0') if f]
    except (OSError, subprocess.CalledProcessError):
        # Not a git checkout (e.g. a source archive): everything but build products.
        files = []
        for dirpath, dirnames, filenames in os.walk(ROOT):
            dirnames[:] = [d for d in dirnames
                           if d not in EXCLUDED_DIRS and not d.endswith('.egg-info')]
            rel = Path(dirpath).relative_to(ROOT)
            files += [str(rel / f) for f in filenames if not f.endswith('.pyc')]
    return [f for f in files if (ROOT / f).is_file()]


def copy_sources(ws: Path) -> list:
    """The repository's files copied to ``<ws>/src/rotrod``; their relative paths."""
    src = ws / 'src' / PACKAGE
    files = source_files()
    for rel in files:
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / rel, src / rel)
    return files


def tail(text: str, n: int = 60) -> str:
    return '\n'.join(text.splitlines()[-n:])


@dataclass(frozen=True)
class ColconBuild:
    """A finished ``colcon build``: its workspace, exit status, output and wall time (s)."""

    ws: Path
    returncode: int
    output: str
    seconds: float

    def install(self, package: str) -> Path:
        """The install prefix of ``package`` (colcon's isolated layout)."""
        return self.ws / 'install' / package


def colcon_build(ws: Path, *args: str, base_paths: tuple = ('src',),
                 env: dict | None = None, timeout: float = BUILD_TIMEOUT) -> ColconBuild:
    """``colcon build --base-paths *base_paths *args`` in ``ws`` (base paths relative to
    it), with this interpreter's colcon and a COLCON_HOME of its own (the user's colcon
    defaults ignored)."""
    colcon = Path(sys.executable).parent / 'colcon'
    if not colcon.exists():
        found = shutil.which('colcon')
        assert found, 'colcon is not installed (pip install -e ".[dev]")'
        colcon = Path(found)
    env = dict(os.environ if env is None else env, COLCON_HOME=str(ws / 'colcon_home'))
    cmd = [str(colcon), '--log-base', str(ws / 'log'), 'build', '--base-paths', *base_paths,
           '--build-base', str(ws / 'build'), '--install-base', str(ws / 'install'), *args]
    t0 = time.monotonic()
    proc = subprocess.run(cmd, cwd=ws, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)
    return ColconBuild(ws, proc.returncode, proc.stdout + proc.stderr,
                       time.monotonic() - t0)


def build_with_interfaces(ws: Path) -> ColconBuild:
    """The sources and the three message packages built by colcon in ``ws``."""
    copy_sources(ws)
    venv = Path(sys.prefix)
    env = dict(os.environ, PATH=f'{venv / "bin"}{os.pathsep}{os.environ.get("PATH", "")}',
               AMENT_PREFIX_PATH=str(venv), CMAKE_PREFIX_PATH=str(venv))
    paths = ('src', *(f'src/{PACKAGE}/{name}' for name in build_interfaces.PACKAGES))
    return colcon_build(ws, '--cmake-args', '-G', 'Ninja',
                        f'-DPython3_EXECUTABLE={sys.executable}', '-DBUILD_TESTING=OFF',
                        base_paths=paths, env=env)
