"""Read setup.py's literal values with ``ast`` (without running it), for the tests."""

import ast
from pathlib import Path

SETUP_PY = Path(__file__).resolve().parent.parent / 'setup.py'


def _tree():
    return ast.parse(SETUP_PY.read_text(), filename='setup.py')


def constants() -> dict:
    """Module-level ``NAME = <literal>`` assignments of setup.py."""
    out = {}
    for node in _tree().body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                and isinstance(node.targets[0], ast.Name):
            try:
                out[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                pass
    return out


def setup_kwargs() -> dict:
    """The literal keyword arguments of ``setup()`` (names of constants resolved)."""
    consts = constants()
    calls = [node for node in ast.walk(_tree()) if isinstance(node, ast.Call)
             and getattr(node.func, 'id', getattr(node.func, 'attr', None)) == 'setup']
    assert len(calls) == 1, 'setup.py must call setup() exactly once'
    kwargs = {}
    for kw in calls[0].keywords:
        if isinstance(kw.value, ast.Name) and kw.value.id in consts:
            kwargs[kw.arg] = consts[kw.value.id]
        else:
            try:
                kwargs[kw.arg] = ast.literal_eval(kw.value)
            except ValueError:
                kwargs[kw.arg] = None  # computed (e.g. glob); not needed here
    return kwargs
