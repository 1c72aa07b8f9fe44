"""The documentation: a short README, links that resolve inside the repository, runnable
snippets."""

import re
import subprocess
import sys
from pathlib import Path

from rotrod_core.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md'))]
LINK = re.compile(r'\]\(([^)\s]+)\)')


def test_the_readme_is_what_a_newcomer_needs_at_most_150_lines():
    assert len((ROOT / 'README.md').read_text().splitlines()) <= 150


def test_every_relative_link_resolves_inside_the_repository():
    broken = []
    for page in PAGES:
        for target in LINK.findall(page.read_text()):
            if re.match(r'[a-z]+:', target) or target.startswith('#'):
                continue
            path = (page.parent / target.split('#')[0]).resolve()
            if ROOT not in path.parents and path != ROOT or not path.exists():
                broken.append(f'{page.relative_to(ROOT)}: {target}')
    assert broken == []


def test_no_page_points_outside_the_repository():
    for page in PAGES:
        assert '../shared' not in page.read_text(), page


def test_the_readme_python_snippet_runs(tmp_path):
    blocks = re.findall(r'```python\n(.*?)```', (ROOT / 'README.md').read_text(), re.S)
    assert blocks
    for code in blocks:
        subprocess.run([sys.executable, '-c', code], cwd=tmp_path, check=True, timeout=120)


def test_the_readme_commands_are_real_subcommands():
    readme = (ROOT / 'README.md').read_text()
    commands = set(re.findall(r'^rotrod ([a-z-]+)', readme, re.M))
    choices = next(a for a in build_parser()._actions if a.dest == 'command').choices
    assert commands and commands <= set(choices), commands - set(choices)


def model_anchors() -> set:
    return set(re.findall(r'<a id="([^"]+)"></a>', (ROOT / 'docs' / 'model.md').read_text()))


def cited_anchors() -> dict:
    """docs/model.md#anchor citations in the package's code, anchor -> files."""
    cited: dict = {}
    for path in [*ROOT.joinpath('rotrod_core').rglob('*.py'),
                 *ROOT.joinpath('rotrod_ros').rglob('*.py')]:
        for anchor in re.findall(r'docs/model\.md#([A-Za-z0-9_-]+)', path.read_text()):
            cited.setdefault(anchor, set()).add(str(path.relative_to(ROOT)))
    return cited


def test_every_equation_of_the_model_page_is_cited_by_the_code_that_computes_it():
    anchors, cited = model_anchors(), cited_anchors()
    assert len(anchors) >= 15
    assert sorted(anchors - set(cited)) == []                    # each anchor has its code
    assert {a: f for a, f in cited.items() if a not in anchors} == {}   # no dead citation


def test_the_code_cites_the_repository_s_model_page_not_the_shared_one():
    for path in [*ROOT.joinpath('rotrod_core').rglob('*.py'),
                 *ROOT.joinpath('rotrod_ros').rglob('*.py')]:
        assert 'MODEL.md' not in path.read_text(), path
