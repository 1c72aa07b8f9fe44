"""One source per fact for the nodes: docs/nodes.md is generated from the tables the
nodes use, every parameter is declared one way (description, unit, range), and the
simulator checks a change when it is set and applies it after."""

import math
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions

from rotrod_core.model.params import FIELDS
from rotrod_ros import nodes_doc
from rotrod_ros.parameters import ROD_SPECS, SPECS_BY_NAME
from rotrod_ros.profile_publisher import ProfilePublisher
from rotrod_ros.rerun_logger import RerunLogger
from rotrod_ros.rig_monitor import RigMonitorNode
from rotrod_ros.simulator import SimulatorNode

ROOT = Path(__file__).resolve().parents[2]
NODE_CLASSES = {'simulator': SimulatorNode, 'profile_publisher': ProfilePublisher,
                'rerun_logger': RerunLogger, 'rig_monitor': RigMonitorNode}


def test_docs_nodes_md_is_what_the_generator_prints():
    text = (ROOT / 'docs' / 'nodes.md').read_text()
    assert text == nodes_doc.render(), (
        'docs/nodes.md is stale: python -m rotrod_ros.nodes_doc > docs/nodes.md')


def test_every_node_and_parameter_is_in_the_doc_with_its_unit_and_range():
    text = (ROOT / 'docs' / 'nodes.md').read_text()
    for executable, module, specs, _ in nodes_doc.NODES:
        section = text.split(f'## `{executable}`')[1].split('\n## ')[0]
        for i in module.INTERFACES:
            assert f'`{i.name}` | {i.type_name} |' in section
        for s in specs:
            row = next(line for line in section.splitlines()
                       if line.startswith(f'| `{s.name}` |'))
            assert f'| {s.unit} |' in row and nodes_doc.range_text(s).replace(
                '|', '\\|') in row


@pytest.mark.parametrize('executable', list(NODE_CLASSES))
def test_numbers_have_a_range_and_floats_a_unit(executable):
    _, _, specs, _ = next(n for n in nodes_doc.NODES if n[0] == executable)
    assert len({s.name for s in specs}) == len(specs)
    for s in specs:
        assert len(s.text) > 10, s.name
        if isinstance(s.default, bool):
            continue
        if isinstance(s.default, (int, float)):
            assert s.low is not None and s.low <= s.default <= s.high, s.name
        if isinstance(s.default, float):
            assert s.unit, f'{s.name} has no unit'


def test_the_rod_parameters_are_the_rod_fields_with_their_units_and_ranges():
    assert [s.name for s in ROD_SPECS] == [f.name for f in FIELDS]
    for spec, field in zip(ROD_SPECS, FIELDS):
        assert (spec.unit, spec.low, spec.high, spec.choices) == (
            field.unit, field.low, field.high, field.choices)
        assert spec.text.startswith(field.description)
    assert SPECS_BY_NAME['mass'].description == 'tip mass m (> 0), kg'


@pytest.fixture
def context():
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    yield context
    context.try_shutdown()


def builtin(name: str) -> bool:
    return name in ('/rosout', '/parameter_events') or name.rsplit('/', 1)[-1] in (
        'describe_parameters', 'get_parameter_types', 'get_parameters', 'list_parameters',
        'set_parameters', 'set_parameters_atomically', 'get_type_description')


@pytest.mark.parametrize('executable', list(NODE_CLASSES))
def test_each_node_declares_its_specs_and_creates_its_interfaces(executable, context,
                                                                  tmp_path):
    _, module, specs, read_only = next(n for n in nodes_doc.NODES if n[0] == executable)
    overrides = [Parameter('output', value=str(tmp_path / 'x.rrd'))] if (
        executable == 'rerun_logger') else []
    if executable == 'profile_publisher':        # every interface: the action's too
        overrides = [Parameter('serve_spin_up', value=True)]
    node = NODE_CLASSES[executable](context=context, parameter_overrides=overrides)
    try:
        declared = set(node._parameters) - {'use_sim_time', 'start_type_description_service'}
        assert declared == {s.name for s in specs}
        for s in specs:
            d = node.describe_parameter(s.name)
            assert d.description == s.description
            assert d.read_only == (s.read_only if read_only is None else read_only)
            if s.low is not None and s.integer:
                assert (d.integer_range[0].from_value, d.integer_range[0].to_value) == (
                    s.low, s.high)
            elif s.low is not None:
                assert (d.floating_point_range[0].from_value,
                        d.floating_point_range[0].to_value) == (s.low, s.high)
        ns = node.get_namespace().rstrip('/')
        # topics by their resolved name, services (rclpy keeps it) by the one given
        want = {i.name if i.kind == 'srv' or i.name.startswith('/') else f'{ns}/{i.name}'
                for i in module.INTERFACES if i.kind not in ('action', 'action client')}
        for name, choices in getattr(module, 'TOPIC_CHOICES', {}).items():  # one of each
            chosen = node.get_parameter(name).value
            want -= {f'{ns}/{topic}' for choice, topic in choices.items() if choice != chosen}
        made = {x.topic_name for x in (*node.publishers, *node.subscriptions)} | {
            x.srv_name for x in node.services}
        assert {m for m in made if not builtin(m)} == want
        from rclpy.action import ActionServer
        actions = [w._action_type for w in node.waitables if isinstance(w, ActionServer)]
        assert sorted(actions, key=str) == sorted(
            (i.type for i in module.INTERFACES if i.kind == 'action'), key=str)
        from rclpy.action import ActionClient
        clients = [w._action_type for w in node.waitables if isinstance(w, ActionClient)]
        assert clients == [i.type for i in module.INTERFACES if i.kind == 'action client']
    finally:
        node.destroy_node()


def test_the_simulator_checks_a_change_when_set_and_applies_it_after(context):
    node = SimulatorNode(context=context, parameter_overrides=[
        Parameter('cpu_dma_latency', value=-1), Parameter('markers', value=False)])
    try:
        config = node.engine.config
        # validation alone (the on-set callback) changes nothing
        assert node._validate_parameters([Parameter('mass', value=0.5)]).successful
        assert node.engine.config is config and node.engine.config.params.mass == 0.3
        # a change set through rclpy is checked, then applied by the post-set callback
        result = node.set_parameters([Parameter('mass', value=0.5),
                                      Parameter('publish_rate', value=50.0)])
        assert all(r.successful for r in result)
        assert node.engine.config.params.mass == 0.5 and node.settings.publish_rate == 50.0
        k = node.engine.config.params.stiffness
        assert node.engine.config.params.natural_frequency == pytest.approx(math.sqrt(k / 0.5))
        # a refused change leaves everything as it was
        refused = node.set_parameters([Parameter('physics_rate', value=20.0)])[0]
        assert not refused.successful and 'too low' in refused.reason
        assert node.engine.config.physics_rate == 1000.0
        assert node.get_parameter('physics_rate').value == 1000.0
        read_only = node.set_parameters([Parameter('start_paused', value=True)])[0]
        assert not read_only.successful and node.settings.start_paused is False
    finally:
        node.destroy_node()
