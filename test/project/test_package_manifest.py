"""Package metadata and layering checks (no ROS runtime needed).

* ``package.xml`` is a valid format-3 manifest (``catkin_pkg``) for an ``ament_python``
  package named ``rotrod`` with the runtime and test dependencies the code needs, and its
  version equals the one in ``setup.py`` (read with ``ast``, not by running it);
* every ``install_requires`` entry of ``setup.py`` has a matching ``python3-*`` exec_depend;
* ``rotrod_core`` (the ROS-free numerical core) and every one of its submodules import in a
  fresh interpreter in which importing ``rclpy`` or any ROS message package fails.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from setup_py import setup_kwargs

ROOT = Path(__file__).resolve().parents[2]
CORE = 'rotrod_core'

REQUIRED_EXEC_DEPENDS = {
    'rclpy', 'rotrod_interfaces', 'std_msgs', 'geometry_msgs', 'sensor_msgs', 'std_srvs',
    'visualization_msgs', 'diagnostic_msgs', 'rosgraph_msgs', 'python3-numpy', 'python3-scipy',
}
REQUIRED_TEST_DEPENDS = {'python3-pytest'}
# PyPI name (lower case) -> rosdep key, where it is not simply python3-<name>.
ROSDEP_KEYS = {'pyyaml': 'python3-yaml'}


@pytest.fixture(scope='module')
def manifest():
    from catkin_pkg.package import parse_package

    warnings = []
    package = parse_package(str(ROOT / 'package.xml'), warnings=warnings)
    assert warnings == [], f'package.xml warnings: {warnings}'
    return package


def test_manifest_format_name_and_build_type(manifest):
    assert manifest.package_format == 3
    assert manifest.name == 'rotrod'
    assert manifest.get_build_type() == 'ament_python'
    manifest.validate()


def test_manifest_dependencies(manifest):
    exec_depends = {dep.name for dep in manifest.exec_depends}
    test_depends = {dep.name for dep in manifest.test_depends}
    assert REQUIRED_EXEC_DEPENDS <= exec_depends, REQUIRED_EXEC_DEPENDS - exec_depends
    assert REQUIRED_TEST_DEPENDS <= test_depends, REQUIRED_TEST_DEPENDS - test_depends


def test_install_requires_are_exec_depends(manifest):
    exec_depends = {dep.name for dep in manifest.exec_depends}
    requires = setup_kwargs().get('install_requires') or []
    for req in requires:
        name = req.split(';')[0].strip()
        for sep in '<>=!~[ ':
            name = name.split(sep)[0]
        key = ROSDEP_KEYS.get(name.lower(), 'python3-' + name.lower())
        assert key in exec_depends, f'setup.py requires {req!r}; package.xml lacks {key}'


def test_version_matches_setup_py(manifest):
    kwargs = setup_kwargs()
    assert kwargs.get('name') == manifest.name
    assert kwargs.get('version') == manifest.version


# Runs in a fresh interpreter: block ROS, import rotrod_core and all its submodules.
IMPORT_WITHOUT_ROS = textwrap.dedent('''
    import importlib, json, pkgutil, re, sys

    EXTRA = set(json.loads(sys.argv[1]))
    ROS = re.compile(r'^(rclpy|rcl|rcl_.*|rmw.*|rosidl.*|rpyutils|ament_.*|launch.*|ros2.*'
                     r'|tf2.*|message_filters|builtin_interfaces|.*_msgs|.*_srvs'
                     r'|.*_interfaces)$')
    attempts = []

    class BlockRos:
        def find_spec(self, fullname, path=None, target=None):
            top = fullname.partition('.')[0]
            if top in EXTRA or ROS.match(top):
                attempts.append(fullname)
                raise ImportError(f'{fullname} is blocked: rotrod_core must not need ROS',
                                  name=fullname)
            return None

    sys.meta_path.insert(0, BlockRos())
    for probe in ('rclpy', 'std_msgs.msg', 'geometry_msgs.msg', 'rosidl_runtime_py'):
        try:
            importlib.import_module(probe)
        except ImportError:
            pass
        else:
            raise SystemExit(f'the import blocker failed to block {probe}')
    attempts.clear()

    def onerror(name):
        raise  # walk_packages calls this inside its `except ImportError`

    import rotrod_core
    modules = ['rotrod_core']
    for info in pkgutil.walk_packages(rotrod_core.__path__, 'rotrod_core.', onerror=onerror):
        importlib.import_module(info.name)
        modules.append(info.name)
    print(json.dumps({'file': rotrod_core.__file__, 'modules': modules,
                      'blocked_attempts': attempts}))
''')


def _source_modules(package_dir: Path) -> set:
    """Dotted module names of the .py files of a package tree (packages need __init__.py)."""
    names = set()
    for path in package_dir.rglob('*.py'):
        rel = path.relative_to(package_dir.parent).with_suffix('')
        parts = rel.parts
        if not all((package_dir.parent.joinpath(*parts[:i]) / '__init__.py').is_file()
                   for i in range(1, len(parts))):
            continue  # not inside a regular package
        if parts[-1] == '__init__':
            parts = parts[:-1]
        names.add('.'.join(parts))
    return names


def test_core_imports_without_ros(manifest):
    ros_packages = sorted(dep.name for dep in manifest.exec_depends
                          if not dep.name.startswith('python3-'))
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(ROOT), env.get('PYTHONPATH')]))
    proc = subprocess.run(
        [sys.executable, '-c', IMPORT_WITHOUT_ROS, json.dumps(ros_packages)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, (
        f'importing {CORE} with ROS blocked failed:\n{proc.stdout}\n{proc.stderr}')
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    print(f'imported without ROS: {", ".join(result["modules"])}')
    if result['blocked_attempts']:
        print(f'(blocked imports, handled by the code: {result["blocked_attempts"]})')
    assert Path(result['file']).resolve().is_relative_to(ROOT / CORE)
    # walk_packages saw every module of the source tree, so all of them were imported.
    assert set(result['modules']) == _source_modules(ROOT / CORE)
