"""``tools/build_interfaces.py`` loaded as a module, for the tests (tools/ is no package)."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _load():
    spec = importlib.util.spec_from_file_location(
        'build_interfaces', ROOT / 'tools' / 'build_interfaces.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


build_interfaces = _load()
"""The build tool's module: its functions and constants."""
