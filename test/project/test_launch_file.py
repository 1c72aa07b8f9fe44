"""The launch file (for a full ROS 2 install) starts what ``rotrod demo`` starts.

``launch`` is not on PyPI, so the file is read, not run: its Node actions must name
the demo's three executables of this package, and its parameter files must be the
demo's, in the same order; beside them robot_state_publisher, with the URDF generated
from those parameter files; and it must be installed with the package.
"""

import ast
from pathlib import Path

import setup_py

from rotrod_ros import demo

ROOT = Path(__file__).resolve().parents[2]
LAUNCH = ROOT / 'launch' / 'demo.launch.py'


def node_calls(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, 'id', None) == 'Node':
            yield {kw.arg: kw.value for kw in node.keywords}


def test_launch_file_names_the_demos_executables_and_parameter_files():
    tree = ast.parse(LAUNCH.read_text())
    nodes = [n for n in node_calls(tree) if ast.literal_eval(n['package']) == 'rotrod']
    assert sorted(ast.literal_eval(n['executable']) for n in nodes) == sorted(demo.EXECUTABLES)
    assert all(ast.literal_eval(n['package']) == 'rotrod' for n in nodes)
    assert all(isinstance(n['parameters'], ast.Name) and n['parameters'].id == 'params'
               for n in nodes)
    names = [c for c in ast.walk(tree) if isinstance(c, ast.Tuple)
             and all(isinstance(e, ast.Constant) and str(e.value).endswith('.yaml')
                     for e in c.elts)]
    (files,) = names
    assert [f'config/{e.value}' for e in files.elts] == list(demo.PARAM_FILES)
    for f in demo.PARAM_FILES:
        assert (ROOT / f).is_file()
    # node names match the parameter files' keys (/**/<node name>)
    for n in nodes:
        key = f'/**/{ast.literal_eval(n["name"])}:'
        assert key in (ROOT / 'config' / 'demo.yaml').read_text()
    compile(LAUNCH.read_text(), str(LAUNCH), 'exec')


def test_launch_file_starts_robot_state_publisher_with_the_urdf_of_the_parameter_files():
    tree = ast.parse(LAUNCH.read_text())
    (rsp,) = [n for n in node_calls(tree)
              if ast.literal_eval(n['package']) == 'robot_state_publisher']
    assert ast.literal_eval(rsp['executable']) == 'robot_state_publisher'
    (mapping,) = rsp['parameters'].elts
    entries = {ast.literal_eval(k): v for k, v in zip(mapping.keys, mapping.values)}
    assert set(entries) == {'robot_description', 'use_sim_time'}
    # robot_description is urdf_for_parameter_files(params): the simulator's files
    (assign,) = [a for a in ast.walk(tree) if isinstance(a, ast.Assign)
                 and a.targets[0].id == entries['robot_description'].id]
    call = assign.value
    assert call.func.id == 'urdf_for_parameter_files' and call.args[0].id == 'params'
    imports = {alias.name: node.module for node in ast.walk(tree)
               if isinstance(node, ast.ImportFrom) for alias in node.names}
    assert imports['urdf_for_parameter_files'] == 'rotrod_core.model.urdf'
    # the launch argument it follows, declared with the demo's default (it runs on /clock)
    (declare,) = [c for c in ast.walk(tree) if isinstance(c, ast.Call)
                  and getattr(c.func, 'id', None) == 'DeclareLaunchArgument']
    assert ast.literal_eval(declare.args[0]) == 'use_sim_time'
    assert {kw.arg: kw.value for kw in declare.keywords}['default_value'].value == 'true'
    assert 'robot_state_publisher' in (ROOT / 'package.xml').read_text()


def test_launch_file_is_installed_with_the_package():
    assert "('share/' + PACKAGE + '/launch', glob('launch/*.launch.py'))" in (
        ROOT / 'setup.py').read_text()
    assert setup_py.constants()['PACKAGE'] == 'rotrod'
