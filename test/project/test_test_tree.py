"""The test tree mirrors the source tree (issue #17).

* ``test/core/<sub>/test_<mod>.py`` tests ``rotrod_core/<sub>/<mod>.py`` and
  ``test/core/test_<mod>.py`` tests ``rotrod_core/<mod>.py``;
* ``test/ros/test_<mod>.py`` tests ``rotrod_ros/<mod>.py``;
* ``test/acceptance/`` holds tests of the whole product through its executables (user
  journeys, the main job, faults, the soak, security), ``test/project/`` checks of the
  repository itself (layers, docs, package manifest, colcon build, benches, the ROS test
  harness, this file);
* the helpers (``conftest.py``, ``ros_harness.py``, ``node_probes.py``, ``reference.py``,
  ``properties.py``, ...) and ``nodes/`` stay in ``test/``, imported as top-level modules
  (``pythonpath = ["test"]`` in pyproject.toml; ``--import-mode=importlib``, so test
  files may share a basename and no directory has an ``__init__.py``).

A test file under ``test/core`` or ``test/ros`` whose module does not exist fails here.
Source modules without a test file of their own (tested through others) are listed,
not failed.
"""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GROUPS = ('core', 'ros', 'acceptance', 'project')
PACKAGES = {'core': 'rotrod_core', 'ros': 'rotrod_ros'}


def tree_problems(root: Path) -> list:
    """What in ``root/test`` breaks the layout above, one sentence each."""
    test = root / 'test'
    problems = []
    for path in sorted(test.rglob('*.py')):
        rel = path.relative_to(test)
        if 'nodes' == rel.parts[0] or (len(rel.parts) == 1 and not rel.name.startswith('test_')):
            continue                                        # helpers and nodes/ stay in test/
        if rel.name == '__init__.py':
            problems.append(f'{rel}: no __init__.py in the test tree (importlib mode)')
        elif len(rel.parts) == 1 or rel.parts[0] not in GROUPS:
            problems.append(f'{rel}: a test file belongs in one of test/{{{",".join(GROUPS)}}}')
        elif rel.name == 'conftest.py':
            continue
        elif not rel.name.startswith('test_'):
            problems.append(f'{rel}: only test_*.py and conftest.py below test/; '
                            'helpers stay in test/')
        elif rel.parts[0] in PACKAGES:
            source = root / PACKAGES[rel.parts[0]] / Path(*rel.parts[1:-1]) / rel.name[5:]
            if not source.is_file() or rel.name == 'test___init__.py':
                problems.append(f'{rel}: no module {source.relative_to(root)} to test')
        elif len(rel.parts) != 2:
            problems.append(f'{rel}: test/{rel.parts[0]} has no subdirectories')
    for path in sorted(p for p in test.rglob('*') if p.is_dir()):
        if path.name in PACKAGES.values():
            problems.append(f'{path.relative_to(test)}: would shadow the package {path.name}')
    return problems


def untested_modules(root: Path) -> list:
    """Source modules with no test file of their own."""
    missing = []
    for group, package in PACKAGES.items():
        for source in sorted((root / package).rglob('*.py')):
            rel = source.relative_to(root / package)
            if source.name != '__init__.py' and not (
                    root / 'test' / group / rel.parent / f'test_{source.name}').is_file():
                missing.append(f'{package}/{rel}')
    return missing


def test_every_test_file_under_core_and_ros_tests_an_existing_module():
    assert tree_problems(ROOT) == []
    missing = untested_modules(ROOT)
    print(f'{len(missing)} modules tested through others, without a test file of their own:',
          *missing, sep='\n  ')


def test_the_check_catches_a_stray_or_misplaced_test_file(tmp_path):
    (tmp_path / 'rotrod_core' / 'live').mkdir(parents=True)
    (tmp_path / 'rotrod_core' / 'live' / 'engine.py').touch()
    (tmp_path / 'rotrod_ros').mkdir()
    (tmp_path / 'rotrod_ros' / 'simulator.py').touch()
    files = ['reference.py', 'conftest.py', 'nodes/talker.py', 'core/live/test_engine.py',
             'ros/test_simulator.py', 'acceptance/test_soak.py', 'core/live/conftest.py']
    for name in files:
        (tmp_path / 'test' / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / 'test' / name).touch()
    assert tree_problems(tmp_path) == []
    assert untested_modules(tmp_path) == []
    for name in ('core/live/test_engine2.py', 'core/model/test_engine.py', 'ros/test_engine.py',
                 'core/test_live.py', 'test_engine.py', 'misc/test_engine.py',
                 'core/live/helpers.py', 'project/sub/test_x.py', 'core/__init__.py',
                 'rotrod_core/test_x.py'):
        (tmp_path / 'test' / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / 'test' / name).touch()
    problems = tree_problems(tmp_path)
    assert [p.split(':')[0] for p in problems] == [
        'core/__init__.py', 'core/live/helpers.py', 'core/live/test_engine2.py',
        'core/model/test_engine.py', 'core/test_live.py', 'misc/test_engine.py',
        'project/sub/test_x.py', 'ros/test_engine.py', 'rotrod_core/test_x.py',
        'test_engine.py', 'rotrod_core'], problems
    (tmp_path / 'rotrod_ros' / 'fleet.py').touch()
    assert untested_modules(tmp_path) == ['rotrod_ros/fleet.py']
