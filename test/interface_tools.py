"""``tools/build_interfaces.py`` loaded as a module, for the tests (tools/ is no package),
and what the tests of the interface packages that copy a published one share."""

import hashlib
import importlib.util
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFINITION_SUFFIXES = ('.msg', '.srv', '.action')
PACKAGE_FILES = ('CMakeLists.txt', 'package.xml')
"""The files of an interface package besides its definitions."""


def _load():
    spec = importlib.util.spec_from_file_location(
        'build_interfaces', ROOT / 'tools' / 'build_interfaces.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


build_interfaces = _load()
"""The build tool's module: its functions and constants."""


def normalized(text: str) -> str:
    """A definition without comments, blank lines and spacing: what goes on the wire."""
    out = []
    for line in text.splitlines():
        line = line.split('#', 1)[0].strip()
        if line:
            out.append(re.sub(r'\s+', ' ', re.sub(r'\s*=\s*', '=', line)))
    return '\n'.join(out)


def definition_digest(path: Path) -> str:
    """SHA-256 of the :func:`normalized` definition in ``path``."""
    return hashlib.sha256(normalized(path.read_text()).encode()).hexdigest()


def package_files(source: Path) -> list:
    """Every file of the package directory ``source``, relative (``msg/X.msg``...)."""
    return sorted(str(p.relative_to(source)) for p in source.rglob('*') if p.is_file())


def definitions(source: Path) -> list:
    """The package's ``.msg``, ``.srv`` and ``.action`` files, relative."""
    return [f for f in package_files(source) if f.endswith(DEFINITION_SUFFIXES)]


def cmake_generated(source: Path) -> list:
    """The definitions the package's CMakeLists.txt hands to rosidl, sorted."""
    cmake = (source / 'CMakeLists.txt').read_text()
    return sorted(re.findall(r'"((?:msg|srv|action)/\w+\.(?:msg|srv|action))"', cmake))


def built_type_hash(prefix: Path, package: str, name: str) -> str:
    """The type hash (RIHS01) rosidl computed for ``package/name`` (e.g. ``msg/Result``),
    from the type description installed in ``prefix``."""
    description = json.loads((prefix / 'share' / package / f'{name}.json').read_text())
    hashes = {h['type_name']: h['hash_string'] for h in description['type_hashes']}
    return hashes[f'{package}/{name}']


class PublishedCopyTests:
    """The checks of an interface package that copies a published one, with its own
    comments: a test module subclasses this (as ``Test...``) and sets the attributes.

    The package directory holds nothing but its manifest, its CMakeLists.txt and
    definitions each with a published reference, and CMake hands rosidl each of them;
    each definition is the published one but for comments and spacing (its
    :func:`definition_digest` is the published file's); the venv (``sys.prefix``) holds
    the build of the current sources; each built type carries the type hash rosidl
    computed for the published package.
    """

    PACKAGE = ''
    """The package's name, also its directory at the repository's root."""
    VERSION = ''
    """The published version it copies (package.xml's)."""
    DEFINITIONS: dict = {}
    """``{'msg/X.msg': SHA-256 of the normalized published file}``."""
    HASHES: dict = {}
    """``{'msg/X': the published package's RIHS01 type hash}``."""

    def pytest_generate_tests(self, metafunc):
        """One test per definition and per type (pytest calls this for the class)."""
        for argument, names in (('definition', self.DEFINITIONS), ('type_name', self.HASHES)):
            if argument in metafunc.fixturenames:
                metafunc.parametrize(argument, sorted(names))

    @property
    def source(self) -> Path:
        return ROOT / self.PACKAGE

    def test_the_package_holds_the_pinned_types_and_cmake_generates_each(self):
        assert package_files(self.source) == sorted([*PACKAGE_FILES, *self.DEFINITIONS])
        assert sorted(name.partition('.')[0] for name in self.DEFINITIONS) == sorted(
            self.HASHES)
        assert cmake_generated(self.source) == definitions(self.source)
        xml = (self.source / 'package.xml').read_text()
        assert f'<name>{self.PACKAGE}</name>' in xml
        assert f'<version>{self.VERSION}</version>' in xml
        assert self.PACKAGE in build_interfaces.PACKAGES

    def test_each_definition_is_the_published_one_but_for_comments(self, definition):
        path = self.source / definition
        assert definition_digest(path) == self.DEFINITIONS[definition], normalized(
            path.read_text())

    def test_the_venv_holds_the_build_of_the_current_sources(self):
        stamp = Path(sys.prefix) / build_interfaces.stamp_name(self.PACKAGE)
        assert stamp.is_file(), f'run.sh builds {self.PACKAGE} before the tests'
        assert stamp.read_text().strip() == build_interfaces.source_digest(self.source)

    def test_each_built_type_carries_the_published_type_hash(self, type_name):
        assert built_type_hash(Path(sys.prefix), self.PACKAGE, type_name) == self.HASHES[
            type_name]
