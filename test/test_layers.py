"""The physics package imports no ROS: not rotrod_ros, not rclpy, not even inside a function."""

import ast
from pathlib import Path

CORE = Path(__file__).resolve().parent.parent / 'rotrod_core'
FORBIDDEN = ('rotrod_ros', 'rclpy')


def imported_modules(path: Path) -> set:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module)
    return names


def test_rotrod_core_imports_nothing_of_ros_anywhere():
    found = {f'{path.name}: {name}' for path in CORE.rglob('*.py')
             for name in imported_modules(path) if name.split('.')[0] in FORBIDDEN}
    assert not found, sorted(found)


def test_the_walk_sees_imports_inside_functions(tmp_path):
    sample = tmp_path / 'x.py'
    sample.write_text('def f():\n    from rotrod_ros import demo\n    import rclpy\n')
    assert {'rotrod_ros', 'rclpy'} <= imported_modules(sample)
