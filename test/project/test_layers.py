"""The layers import one way, with no cycles (imports inside functions included).

Ranks, lowest first; a module may import its own subpackage and lower ranks only::

    numerics < model < command < offline < analysis < sensors < live < estimation
             < reporting < cli, the package's __init__      (the physics, then above it)

``rotrod_ros`` (the nodes) sits above all of ``rotrod_core``, and nothing in
``rotrod_core`` imports it. The physics imports no ROS, matplotlib or rerun.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RANKS = {name: rank for rank, name in enumerate(
    ['numerics', 'model', 'command', 'offline', 'analysis', 'sensors', 'live', 'estimation',
     'reporting', 'cli', '__init__'])}
PHYSICS = ('numerics', 'model', 'command', 'offline', 'analysis', 'sensors', 'live',
           'estimation')
NOT_IN_PHYSICS = ('rotrod_ros', 'rclpy', 'matplotlib', 'rerun')


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix('').parts)
    if parts[-1] == '__init__' and len(parts) > 1:
        parts.pop()
    return '.'.join(parts)


def imported_modules(path: Path) -> set:
    """Every module ``path`` imports, anywhere in the file, relative ones resolved."""
    inside = ROOT in path.resolve().parents
    name = module_name(path) if inside else path.stem
    package = name if path.name == '__init__.py' else name.rpartition('.')[0]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ''
            if node.level:
                anchor = package.split('.')[:len(package.split('.')) - node.level + 1]
                base = '.'.join(anchor + ([base] if base else []))
            names.add(base)
            names.update(f'{base}.{alias.name}' for alias in node.names)
    return names


def project_modules() -> dict:
    paths = [*ROOT.joinpath('rotrod_core').rglob('*.py'),
             *ROOT.joinpath('rotrod_ros').rglob('*.py')]
    return {module_name(p): p for p in paths}


def import_graph() -> dict:
    modules = project_modules()
    return {name: {m for m in imported_modules(path) if m in modules and m != name}
            for name, path in modules.items()}


def layer(module: str) -> str | None:
    """The rank name of a rotrod_core module, None for rotrod_ros."""
    parts = module.split('.')
    if parts[0] != 'rotrod_core':
        return None
    if len(parts) == 1:
        return '__init__'
    return parts[1]


def reversed_arrows(graph: dict) -> list:
    bad = []
    for source, targets in graph.items():
        for target in targets:
            a, b = layer(source), layer(target)
            if b is None and a is not None:
                bad.append(f'{source} -> {target}: the core imports a node module')
            elif a is not None and b is not None and a != b and RANKS[b] > RANKS[a]:
                bad.append(f'{source} ({a}) -> {target} ({b}): a lower layer imports a '
                           'higher one')
    return sorted(bad)


def cycles(graph: dict) -> list:
    """Every module on an import cycle (package __init__ re-exports excluded)."""
    inits = {name for name, path in project_modules().items() if path.name == '__init__.py'}
    graph = {k: v - inits for k, v in graph.items()}
    found, state = [], {}

    def visit(node, path):
        state[node] = 'open'
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 'open':
                found.append(path[path.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 'done'

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    return found


def test_every_subpackage_of_the_core_has_a_rank():
    packages = {p.parent.name for p in ROOT.joinpath('rotrod_core').glob('*/__init__.py')}
    modules = {p.stem for p in ROOT.joinpath('rotrod_core').glob('*.py')}
    assert packages | modules <= set(RANKS), (packages | modules) - set(RANKS)


def test_layers_import_one_way():
    assert reversed_arrows(import_graph()) == []


def test_no_import_cycles():
    assert cycles(import_graph()) == []


def test_the_physics_imports_no_ros_matplotlib_or_rerun_anywhere():
    found = {f'{name}: {m}' for name, path in project_modules().items()
             if layer(name) in PHYSICS
             for m in imported_modules(path) if m.split('.')[0] in NOT_IN_PHYSICS}
    assert not found, sorted(found)


def test_rotrod_core_imports_nothing_of_ros_anywhere():
    found = {f'{name}: {m}' for name, path in project_modules().items()
             if layer(name) is not None
             for m in imported_modules(path) if m.split('.')[0] in ('rotrod_ros', 'rclpy')}
    assert not found, sorted(found)


def test_the_walk_sees_imports_inside_functions(tmp_path):
    sample = tmp_path / 'x.py'
    sample.write_text('def f():\n    from rotrod_ros import demo\n    import rclpy\n')
    assert {'rotrod_ros', 'rotrod_ros.demo', 'rclpy'} <= imported_modules(sample)


def test_the_checks_catch_a_reversed_arrow_and_a_cycle():
    graph = {'rotrod_core.numerics.a': {'rotrod_core.reporting.b'},
             'rotrod_core.reporting.b': {'rotrod_core.numerics.a'}}
    assert reversed_arrows(graph) == [
        'rotrod_core.numerics.a (numerics) -> rotrod_core.reporting.b (reporting): '
        'a lower layer imports a higher one']
    assert cycles(graph) == [['rotrod_core.numerics.a', 'rotrod_core.reporting.b',
                              'rotrod_core.numerics.a']]
    assert reversed_arrows({'rotrod_core.live.x': {'rotrod_ros.simulator'}})


def test_rotrod_cores_public_names_each_load_from_the_module_that_defines_them():
    """rotrod_core imports its public names on first use (PEP 562): ``__all__``, the
    table ``__getattr__`` reads and the type checker's imports name the same things,
    from the same modules, and each name resolves to that module's object."""
    import importlib

    import rotrod_core
    tree = ast.parse(Path(rotrod_core.__file__).read_text())
    typed = {alias.name: node.module for node in ast.walk(tree)
             if isinstance(node, ast.ImportFrom) for alias in node.names}
    typed.pop('TYPE_CHECKING')
    lazy = rotrod_core._MODULE_OF
    assert sorted(rotrod_core.__all__) == sorted(lazy) == sorted(typed)
    assert lazy == typed
    for name, module in lazy.items():
        assert getattr(rotrod_core, name) is getattr(importlib.import_module(module), name)


def test_a_node_importing_the_live_core_does_not_load_the_analyses_scipy():
    """The simulator's start imports what it runs, not the identification's
    scipy.signal nor the planner (rotrod_core's names load on first use)."""
    import subprocess
    import sys
    code = ('import sys, rotrod_ros.simulator; '
            'print(sorted(m for m in ("scipy.signal", "rotrod_core.command.planner", '
            '"rotrod_core.estimation.identify") if m in sys.modules))')
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          cwd=ROOT, timeout=120, check=True)
    assert done.stdout.strip() == '[]', done.stdout
