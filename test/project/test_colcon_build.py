"""Build the package with colcon, as a ROS user would, and check the installed tree.

The repository's source files (``git ls-files --cached --others --exclude-standard``, so
nothing from ``.venv``/``build``) are copied to ``<tmp>/ws/src/rotrod`` and built with
``colcon build --base-paths src`` using this interpreter's colcon and setuptools. Then,
with the environment computed from the install tree's colcon ``.dsv`` hooks (nothing is
sourced) and from a directory outside the repository:

* ``ament_index_python.get_package_prefix('rotrod')`` is the install prefix, and
  ``rotrod_core`` resolves to the install tree, not the source tree;
* every console script declared in setup.py's ``CONSOLE_SCRIPTS`` (parsed with ``ast``;
  compared with the installed ``entry_points.txt``) is an executable
  ``<prefix>/lib/rotrod/<name>`` that runs ``--help`` with exit status 0, importing only
  installed ``rotrod_*`` modules;
* ``share/rotrod/package.xml``, ``share/rotrod/config/`` (with every ``config/*.yaml``),
  ``share/rotrod/urdf/rotrod.urdf`` and the ament resource marker
  ``share/ament_index/resource_index/packages/rotrod`` exist.

And the message packages: with ``rotrod_interfaces/``, ``simulation_interfaces/`` and
``control_msgs/`` (tools/build_interfaces.py's ``PACKAGES``) named as base paths too,
colcon builds them (ament_cmake, with the venv's ament and rosidl wheels standing in for
a ROS install), those ``rotrod`` depends on before it, and their messages import from
the install tree.
"""

import configparser
import json
import os
import re
import subprocess
import sys
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from importlib import metadata
from pathlib import Path

import pytest
import setup_py
from colcon_workspace import BUILD_TIMEOUT, PACKAGE, colcon_build, copy_sources, tail
from interface_tools import build_interfaces

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]


def declared_console_scripts() -> dict:
    """``{name: 'module:function'}`` from setup.py's ``CONSOLE_SCRIPTS`` list (via ast)."""
    scripts = setup_py.constants().get('CONSOLE_SCRIPTS')
    assert scripts is not None, 'setup.py has no module-level CONSOLE_SCRIPTS list'
    return parse_entry_points(scripts)


def parse_entry_points(lines) -> dict:
    out = {}
    for line in lines:
        name, sep, target = line.partition('=')
        assert sep, f'malformed console script {line!r}'
        assert name.strip() not in out, f'duplicate console script {name.strip()!r}'
        out[name.strip()] = re.sub(r'\s+', '', target)
    return out


def environment_from_install(prefix: Path, base: dict) -> dict:
    """Apply the colcon ``.dsv`` hooks of ``<prefix>/share/rotrod/package.dsv`` to ``base``."""
    env = dict(base)

    def apply(dsv: Path) -> None:
        for line in dsv.read_text().splitlines():
            if not line.strip():
                continue
            kind, _, rest = line.partition(';')
            if kind == 'source':
                if rest.endswith('.dsv'):
                    apply(prefix / rest)
                continue
            name, _, values = rest.partition(';')
            paths = [str(prefix / v) if v else str(prefix) for v in values.split(';')]
            if kind.endswith('-if-exists'):
                paths = [p for p in paths if os.path.exists(p)]
            current = [p for p in env.get(name, '').split(os.pathsep) if p]
            if kind.startswith('prepend-non-duplicate'):
                env[name] = os.pathsep.join(paths + [p for p in current if p not in paths])
            elif kind.startswith('append-non-duplicate'):
                env[name] = os.pathsep.join([p for p in current if p not in paths] + paths)
            elif kind == 'set' or (kind == 'set-if-unset' and not env.get(name)):
                env[name] = os.pathsep.join(paths)

    apply(prefix / 'share' / PACKAGE / 'package.dsv')
    return env


@pytest.fixture(scope='module')
def colcon_install(tmp_path_factory):
    """Build into a temporary workspace once per module; return its facts."""
    tmp = tmp_path_factory.mktemp('colcon')
    ws = tmp / 'ws'
    files = copy_sources(ws)
    assert 'package.xml' in files and 'setup.py' in files

    build = colcon_build(ws, '--event-handlers', 'console_direct+', timeout=600)
    output = build.output
    assert build.returncode == 0, \
        f'colcon build failed ({build.returncode}):\n{tail(output)}'

    setuptools_version = metadata.version('setuptools')
    print(f'colcon build: {build.seconds:.1f} s with setuptools {setuptools_version}')
    constraints = ROOT / 'constraints.txt'
    if constraints.is_file():
        pin = re.search(r'^setuptools==(\S+)', constraints.read_text(), re.MULTILINE)
        if pin and pin.group(1) != setuptools_version:
            warnings.warn(f'built with setuptools {setuptools_version}, but constraints.txt '
                          f'pins {pin.group(1)}', stacklevel=1)
    build_warnings = sorted({line.strip() for line in output.splitlines()
                             if re.search(r'warning:', line, re.IGNORECASE)
                             and 'byte-compiling is disabled' not in line})
    for line in build_warnings:
        print(f'  build warning: {line}')
    if build_warnings:
        warnings.warn('colcon build of rotrod printed warnings: ' + ' | '.join(build_warnings),
                      stacklevel=1)

    prefix = ws / 'install' / PACKAGE
    base = {k: v for k, v in os.environ.items()
            if k not in ('AMENT_PREFIX_PATH', 'PYTHONPATH', 'COLCON_PREFIX_PATH')}
    elsewhere = tmp / 'elsewhere'
    elsewhere.mkdir()
    return {'ws': ws, 'prefix': prefix, 'env': environment_from_install(prefix, base),
            'cwd': elsewhere, 'seconds': build.seconds}


PROBE = '''
import importlib.metadata, json, sys
from ament_index_python.packages import get_package_prefix, get_package_share_directory
import rotrod_core
dist = importlib.metadata.distribution('rotrod')
print(json.dumps({
    'prefix': get_package_prefix('rotrod'),
    'share': get_package_share_directory('rotrod'),
    'rotrod_core': rotrod_core.__file__,
    'metadata': str(getattr(dist, '_path', '')),
    'console_scripts': {ep.name: ep.value for ep in dist.entry_points
                        if ep.group == 'console_scripts'},
}))
'''

# Runs an installed script in-process (as its shebang interpreter would) to see which
# rotrod modules it imported.
RUN_SCRIPT = '''
import json, runpy, sys
script = sys.argv[1]
sys.argv = [script, '--help']
code = 0
try:
    runpy.run_path(script, run_name='__main__')
except SystemExit as exc:
    code = exc.code
mods = {name: getattr(mod, '__file__', None) for name, mod in list(sys.modules.items())
        if name.partition('.')[0] in ('rotrod_core', 'rotrod_ros')}
sys.stdout.flush()
print('@@PROBE@@' + json.dumps({'code': code, 'modules': mods}), file=sys.__stderr__)
'''


def _under(path, root: Path) -> bool:
    return path is not None and Path(path).resolve().is_relative_to(root.resolve())


def test_ament_index_and_import_resolve_to_install(colcon_install):
    prefix = colcon_install['prefix']
    proc = subprocess.run([sys.executable, '-c', PROBE], cwd=colcon_install['cwd'],
                          env=colcon_install['env'], capture_output=True, text=True,
                          timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    assert Path(info['prefix']).resolve() == prefix.resolve()
    assert Path(info['share']).resolve() == (prefix / 'share' / PACKAGE).resolve()
    assert _under(info['rotrod_core'], prefix), f'rotrod_core from {info["rotrod_core"]}'
    assert not _under(info['rotrod_core'], ROOT)
    if info['metadata']:
        assert _under(info['metadata'], prefix), info['metadata']
    assert info['console_scripts'] == declared_console_scripts()


def test_data_files_installed(colcon_install):
    prefix = colcon_install['prefix']
    share = prefix / 'share' / PACKAGE
    assert (share / 'package.xml').read_text() == (ROOT / 'package.xml').read_text()
    assert (share / 'config').is_dir()
    source_configs = {p.name for p in (ROOT / 'config').glob('*.yaml')}
    installed_configs = {p.name for p in (share / 'config').glob('*.yaml')}
    assert installed_configs == source_configs
    assert {p.name for p in (share / 'urdf').glob('*.urdf')} == {'rotrod.urdf'}
    urdf = Path('urdf') / 'rotrod.urdf'
    assert (share / urdf).read_text() == (ROOT / urdf).read_text()
    marker = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages' / PACKAGE
    assert marker.is_file()


def test_console_scripts_installed_and_run(colcon_install):
    prefix = colcon_install['prefix']
    declared = declared_console_scripts()
    print(f'console scripts declared in setup.py: {", ".join(sorted(declared)) or "none"}')
    assert declared, 'setup.py declares no console scripts'

    egg_infos = list(prefix.glob(f'lib/python*/site-packages/{PACKAGE}-*.egg-info'))
    assert len(egg_infos) == 1, egg_infos
    parser = configparser.ConfigParser(delimiters=('=',))
    parser.optionxform = str
    parser.read(egg_infos[0] / 'entry_points.txt')
    installed = parse_entry_points(f'{k} = {v}' for k, v in parser['console_scripts'].items())
    assert installed == declared

    lib_dir = prefix / 'lib' / PACKAGE
    assert sorted(p.name for p in lib_dir.iterdir()) == sorted(declared)

    env, cwd = colcon_install['env'], colcon_install['cwd']

    def run(argv: list[str]) -> tuple[subprocess.CompletedProcess, float]:
        t0 = time.monotonic()
        proc = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True,
                              timeout=120, check=False)
        return proc, time.monotonic() - t0

    scripts = {}
    for name in sorted(declared):
        exe = lib_dir / name
        assert exe.is_file() and os.access(exe, os.X_OK), f'{exe} is not executable'
        shebang = exe.read_text().splitlines()[0]
        assert shebang.startswith('#!'), f'{exe}: no shebang'
        scripts[name] = (exe, shebang[2:].strip().split()[0])
    # each script's --help, and a probe of what the same script imports with the same
    # interpreter and environment: all together (each starts Python and its imports)
    with ThreadPoolExecutor(max_workers=4) as pool:
        helps = {name: pool.submit(run, [str(exe), '--help'])
                 for name, (exe, _) in scripts.items()}
        probes = {name: pool.submit(run, [interpreter, '-c', RUN_SCRIPT, str(exe)])
                  for name, (exe, interpreter) in scripts.items()}
    for name, target in sorted(declared.items()):
        exe = scripts[name][0]
        proc, seconds = helps[name].result()
        assert proc.returncode == 0, (
            f'{name} --help failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}')
        assert proc.stdout.strip(), f'{name} --help printed nothing'
        print(f'  {name} = {target}: {exe} --help ok ({seconds:.2f} s, run with the '
              f'others): {proc.stdout.strip().splitlines()[0]}')
        proc, _ = probes[name].result()
        lines = [ln for ln in proc.stderr.splitlines() if ln.startswith('@@PROBE@@')]
        assert lines, f'{name}: probe failed:\n{proc.stderr}'
        probe = json.loads(lines[-1][len('@@PROBE@@'):])
        assert probe['code'] in (0, None), probe
        module = target.partition(':')[0]
        assert module in probe['modules'], f'{name} did not import {module}'
        for mod, path in probe['modules'].items():
            if path is not None:
                assert _under(path, prefix), f'{name}: {mod} imported from {path}'


@pytest.mark.long      # minutes (cmake and the rosidl generators): .ci/run runs it
# the session's build (colcon_workspace.BUILD_TIMEOUT), not pytest.ini's 300 s per test
@pytest.mark.timeout(BUILD_TIMEOUT + 60)
def test_colcon_builds_the_interface_packages_beside_rotrod(colcon_interfaces, tmp_path):
    """``colcon build --base-paths src src/rotrod/rotrod_interfaces
    src/rotrod/simulation_interfaces src/rotrod/control_msgs`` (docs/usage.md; the
    session's build, test/colcon_workspace.py): the four packages, those rotrod depends
    on before it, with this venv as the ROS install (its ament and rosidl build wheels,
    cmake and ninja, as tools/build_interfaces.py sets them up); the installed messages
    import from the install tree and serialize."""
    build = colcon_interfaces
    print(f'colcon build of the four packages: {build.seconds:.0f} s')
    assert build.returncode == 0, \
        f'colcon build failed ({build.returncode}):\n{tail(build.output)}'
    interfaces = list(build_interfaces.PACKAGES)
    order = [m.group(1) for m in re.finditer(r'Finished <<< (\w+)', build.output)]
    assert sorted(order) == sorted([*interfaces, PACKAGE])
    depends = set(re.findall(r'<\w*depend>(\w+)</', (ROOT / 'package.xml').read_text()))
    assert {'rotrod_interfaces', 'simulation_interfaces'} <= depends
    for name in depends.intersection(interfaces):
        assert order.index(name) < order.index(PACKAGE), (name, order)
    assert sorted(INSTALLED_PROBES) == sorted(interfaces)
    for name, (code, expected) in INSTALLED_PROBES.items():
        site, out = _run_from_install(build.install(name), tmp_path, code)
        first, second = out.split()
        assert first.startswith(str(site)) and second == expected, name


INSTALLED_PROBES = {
    'rotrod_interfaces': (
        'import rotrod_interfaces.msg as m, rotrod_interfaces.action as a\n'
        'from rclpy.serialization import serialize_message as s\n'
        'print(m.__file__); s(m.WhirlEstimate(f1=1.5)); print(a.SpinUp.Goal.PLANNED)',
        'planned'),
    'simulation_interfaces': (
        'import simulation_interfaces.srv as s\n'
        'from rclpy.serialization import serialize_message as m\n'
        'print(s.__file__); m(s.StepSimulation.Request(steps=3)); '
        'print(s.ResetSimulation.Request.SCOPE_ALL)',
        '255'),
    'control_msgs': (
        'import control_msgs.action as a\n'
        'from rclpy.serialization import serialize_message as m\n'
        'print(a.__file__); m(a.FollowJointTrajectory.Goal(path_tolerance=[])); '
        'print(a.FollowJointTrajectory.Result.GOAL_TOLERANCE_VIOLATED)',
        '-5'),
}
"""Per interface package: code run with only its colcon install added (it prints the
module's file, then a value), and the value it must print."""


def _run_from_install(prefix: Path, cwd: Path, code: str) -> tuple[Path, str]:
    """Run ``code`` with only the colcon install ``prefix``'s Python package and
    libraries added; return (its site-packages, the output)."""
    site = next(prefix.glob('lib/python3*/site-packages'))
    run_env = dict(os.environ, PYTHONPATH=str(site),
                   LD_LIBRARY_PATH=f'{prefix / "lib"}{os.pathsep}'
                                   f'{os.environ.get("LD_LIBRARY_PATH", "")}')
    run_env.pop('_ROS_WHEELS_BOOTSTRAP_COMPLETE', None)
    done = subprocess.run([sys.executable, '-c', code], cwd=cwd, env=run_env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return site, done.stdout
