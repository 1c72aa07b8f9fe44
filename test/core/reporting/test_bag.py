"""rosbag2 (MCAP) files of offline runs, read back by independent readers.

The bag is written with ``rosbags``; here it is read with the MCAP project's own
reader and ROS 2 decoder (``mcap``, ``mcap-ros2-support``), which decode each message
from the ``ros2msg`` schema stored in the file, and its metadata.yaml is checked
against what Jazzy's rosbag2 reads (``rosbag2_storage``'s yaml.hpp and qos.cpp,
metadata version 9). The values must be the run's; the messages must be the ones
the live node builds (``rotrod_ros.messages``, compared after rclpy deserializes the
bag's bytes), and the type hashes those of the installed ROS message packages.
"""

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from reference import R0, W0, L

from rotrod_core import Eq26Profile, RodParams, simulate
from rotrod_core.live.publication import PublicationSettings
from rotrod_core.model import interface
from rotrod_core.model.geometry import rod_centerline, sphere_radius
from rotrod_core.reporting.bag import BAG_TOPICS, topic_name, write_bag

ROOT = Path(__file__).resolve().parents[3]
T_END = 20.0
RATE = 100.0
TYPES = {
    '/joint_states': 'sensor_msgs/msg/JointState',
    '/tip/deflection': 'geometry_msgs/msg/Vector3Stamped',
    '/tip/position': 'geometry_msgs/msg/PointStamped',
    '/frequencies': 'rotrod_interfaces/msg/DynamicFrequencies',
    '/frequencies/estimate': 'rotrod_interfaces/msg/WhirlEstimate',
    '/markers': 'visualization_msgs/msg/MarkerArray',
    '/clock': 'rosgraph_msgs/msg/Clock',
}
"""Written out here (not taken from the code): what the node publishes, in /."""


@pytest.fixture(scope='module')
def run():
    return simulate(RodParams(), Eq26Profile(period=15.0, omega_target=2.0), T_END, dt=1e-3)


@pytest.fixture(scope='module')
def bag(run, tmp_path_factory):
    path = tmp_path_factory.mktemp('bags') / 'eq26'
    counts = write_bag(path, run)
    return path, counts


def read(path: Path) -> dict:
    """topic -> list of (log time ns, schema name, decoded message, raw bytes)."""
    (mcap_file,) = path.glob('*.mcap')
    out: dict = {}
    with mcap_file.open('rb') as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == 'ros2'
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            assert channel.message_encoding == 'cdr' and schema.encoding == 'ros2msg'
            out.setdefault(channel.topic, []).append(
                (message.log_time, schema.name, decoded, message.data))
    return out


def seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def test_topics_types_and_counts_are_the_nodes(run, bag):
    path, counts = bag
    got = read(path)
    n = int(T_END * RATE) + 1                     # t = 0, 0.01, ..., 20 s
    assert set(got) == set(TYPES) and counts == {k: len(v) for k, v in got.items()}
    for topic, rows in got.items():
        assert {schema for _, schema, _, _ in rows} == {TYPES[topic]}, topic
    for topic in ('/joint_states', '/tip/deflection', '/tip/position', '/frequencies',
                  '/clock'):
        assert len(got[topic]) == n, topic
    assert len(got['/markers']) == n // 5        # marker_rate 20 Hz of 100 Hz
    # an estimate every 0.1 s once the 1 s window is full: t = 0.99, 1.09, ..., 19.99 s
    assert len(got['/frequencies/estimate']) == 191


def test_values_stamps_and_frames_are_the_runs(run, bag):
    got = read(bag[0])
    i = np.arange(0, len(run.t), 10)              # every 10 ms of the 1 ms run
    t = run.t[i]
    joints = got['/joint_states']
    assert [log for log, *_ in joints] == [round(x * 1e9) for x in t]
    stamps = np.array([seconds(m.header.stamp) for _, _, m, _ in joints])
    assert np.max(np.abs(stamps - t)) < 1e-9
    assert all(list(m.name) == ['hub', 'tip_radial', 'tip_tangential', 'tip_pitch', 'tip_roll']
               for _, _, m, _ in joints)
    assert all(m.header.frame_id == '' for _, _, m, _ in joints)
    pos = np.array([m.position for _, _, m, _ in joints])
    vel = np.array([m.velocity for _, _, m, _ in joints])
    eff = np.array([m.effort for _, _, m, _ in joints])
    assert np.array_equal(pos[:, :3], np.c_[run.theta[i], run.u[i], run.v[i]])
    assert np.array_equal(vel[:, :3], np.c_[run.omega[i], run.du[i], run.dv[i]])
    assert np.array_equal(eff, np.c_[run.torque[i], np.zeros((len(i), 4))])
    # the tip's tilt: the cantilever's slope 3/2 u / l about y (small: atan ~ itself)
    assert np.allclose(pos[:, 3], np.arctan(1.5 * run.u[i] / L), rtol=1e-12, atol=0)

    defl = got['/tip/deflection']
    assert all(m.header.frame_id == 'rotor' for _, _, m, _ in defl)
    uv = np.array([(m.vector.x, m.vector.y, m.vector.z) for _, _, m, _ in defl])
    assert np.array_equal(uv, np.c_[run.u[i], run.v[i], np.zeros(len(i))])

    position = got['/tip/position']
    assert all(m.header.frame_id == 'world' for _, _, m, _ in position)
    xyz = np.array([(m.point.x, m.point.y, m.point.z) for _, _, m, _ in position])
    theta, u, v = run.theta[i], run.u[i], run.v[i]
    closed = np.c_[(R0 + u) * np.cos(theta) - v * np.sin(theta),
                   (R0 + u) * np.sin(theta) + v * np.cos(theta), np.full(len(i), L)]
    assert np.max(np.abs(xyz - closed)) < 1e-15

    freq = got['/frequencies']
    assert [log for log, *_ in freq] == [log for log, *_ in joints]
    assert all(round(seconds(m.header.stamp) * 1e9) == log for log, _, m, _ in freq)
    f = np.array([(m.f1, m.f2) for _, _, m, _ in freq])
    w = np.array([m.omega for _, _, m, _ in freq])
    assert np.array_equal(w, run.omega[i])                 # the sample's w, and at it
    assert np.max(np.abs(f - np.c_[(W0 - w), (W0 + w)] / (2 * math.pi))) < 1e-12   # Eq. 28

    clock = got['/clock']
    assert [log for log, *_ in clock] == [log for log, *_ in joints]
    assert all(round(seconds(m.clock) * 1e9) == log for log, _, m, _ in clock)

    # the whirl estimate over the hold at 2 rad/s (windows within 15-20 s): Eq. 28;
    # stamped at its window's middle, 0.495 s before the publication that completed it
    # (the 100 samples from 0.99 s before it)
    estimates = got['/frequencies/estimate']
    for log, _, m, _ in estimates:
        assert seconds(m.header.stamp) == pytest.approx(log * 1e-9 - 0.495, abs=1e-9)
        assert m.window == pytest.approx(0.99, abs=1e-12) and m.samples == 100
    hold = [m for log, _, m, _ in estimates if 16.0 <= log * 1e-9 <= 20.0]
    assert len(hold) >= 39
    f1, f2 = (W0 - 2.0) / (2 * math.pi), (W0 + 2.0) / (2 * math.pi)
    for m in hold:
        assert m.f1_valid and m.f2_valid and m.reason == ''
        assert m.f1 == pytest.approx(f1, rel=1e-3) and m.f2 == pytest.approx(f2, rel=1e-3)
        assert 0 < m.f1_std < 1e-3 * f1 and 0 < m.f2_std < 1e-3 * f2


def test_markers_are_drawn_in_world_at_the_drawn_tip(run, bag):
    got = read(bag[0])
    markers = got['/markers']
    first_log, _, first, _ = markers[0]
    assert first_log == round(0.04e9)             # the 5th publication, as the node's
    last_log, _, last, _ = markers[-1]
    assert [m.id for m in first.markers] == [0, 1, 2, 3]          # no trail from 1 point
    assert [m.id for m in last.markers] == [0, 1, 2, 3, 4]
    assert all(m.header.frame_id == 'world' and m.ns == 'rotrod' for m in last.markers)
    k = int(round(last_log * 1e-9 / 1e-3))
    mass = last.markers[3]
    assert mass.type == 2 and mass.scale.x == pytest.approx(2 * sphere_radius(0.3))
    # the drawn tip: the deflection scaled by 20 on the closed form, at z = l
    theta, u, v = run.theta[k], 20 * run.u[k], 20 * run.v[k]
    assert (mass.pose.position.x, mass.pose.position.y, mass.pose.position.z) == \
        pytest.approx(((R0 + u) * math.cos(theta) - v * math.sin(theta),
                       (R0 + u) * math.sin(theta) + v * math.cos(theta), L), abs=1e-15)
    assert len(last.markers[4].points) == 200      # the trail is bounded


def test_the_messages_are_the_live_nodes(run, bag):
    """rclpy reads the bag's bytes as the messages rotrod_ros.messages builds.

    Compared as rclpy messages after deserializing (the bytes differ in CDR padding,
    which Fast CDR leaves unset); the live message goes through its own serialization
    too, so that its float32 fields (colours) are rounded alike.
    """
    from geometry_msgs.msg import PointStamped, Vector3Stamped
    from rclpy.serialization import deserialize_message, serialize_message
    from rosgraph_msgs.msg import Clock
    from rotrod_interfaces.msg import DynamicFrequencies, WhirlEstimate
    from sensor_msgs.msg import JointState
    from visualization_msgs.msg import MarkerArray

    from rotrod_core.analysis.modes import dynamic_frequencies
    from rotrod_core.estimation.whirl import stream_estimator
    from rotrod_core.model.equations import State
    from rotrod_ros import messages

    got = read(bag[0])
    j, k = 1234, 12340                            # publication j is run sample k
    state = State(*(float(a[k]) for a in (run.u, run.v, run.du, run.dv, run.theta,
                                          run.omega)))
    stamp = messages.stamp(run.t[k])
    expected = {
        '/joint_states': (JointState, messages.joint_state(stamp, state, run.torque[k], L)),
        '/tip/deflection': (Vector3Stamped, messages.deflection(stamp, state.u, state.v,
                                                                'rotor')),
        '/tip/position': (PointStamped, messages.position(
            stamp, (run.x[k], run.y[k], L), 'world')),
        '/frequencies': (DynamicFrequencies, messages.frequencies(
            stamp, state.omega, *dynamic_frequencies(RodParams(), state.omega))),
        '/clock': (Clock, messages.clock(stamp)),
    }
    for topic, (cls, msg) in expected.items():
        assert deserialize_message(got[topic][j][3], cls) == msg, topic
        assert deserialize_message(serialize_message(msg), cls) == msg    # no float32
    # the first estimate, as the node makes it from the same publications
    estimator = stream_estimator(1.0, 100.0, 10.0)
    for k in range(0, len(run.t), 10):
        first = estimator.push(run.t[k], run.u[k], run.v[k])
        if first is not None:
            break
    live_estimate = messages.whirl_estimate(messages.stamp(first.time), first)
    bagged = deserialize_message(got['/frequencies/estimate'][0][3], WhirlEstimate)
    for name in WhirlEstimate.get_fields_and_field_types():
        a, b = getattr(bagged, name), getattr(live_estimate, name)
        assert a == b or (a != a and b != b), name             # NaN where not valid
    # the first markers: the trail holds one point, so none is drawn
    k0 = 40
    rod = rod_centerline(RodParams(), run.u[k0], run.v[k0], run.theta[k0], scale=20.0)
    live = messages.markers(messages.stamp(run.t[k0]), 'world', 'rotrod', disk_radius=0.15,
                            theta=run.theta[k0], rod=rod, rod_diameter=0.003,
                            mass_radius=sphere_radius(0.3), trail=[rod[-1]])
    assert deserialize_message(got['/markers'][0][3], MarkerArray) == \
        deserialize_message(serialize_message(live), MarkerArray)


def test_a_bag_is_written_with_the_nodes_own_settings(run, tmp_path):
    """One settings class: the node's NodeSettings are PublicationSettings, which a bag takes."""
    from rotrod_ros.parameters import NodeSettings, build_settings, defaults
    _, node = build_settings(defaults())            # the node's parameter defaults
    assert isinstance(node, PublicationSettings) and issubclass(NodeSettings,
                                                                PublicationSettings)
    assert PublicationSettings(**{f: getattr(node, f) for f in
                                  PublicationSettings.__dataclass_fields__}) == \
        PublicationSettings()                      # a bag's defaults are the node's
    # the node's topics (test_urdf checks interface.TOPICS against a live node's graph)
    assert {topic_name('/', t): interface.TOPICS[t] for t in BAG_TOPICS} == TYPES
    # a node configured without estimate and markers: a bag without those topics
    quiet = NodeSettings(estimate_window=0.0, markers=False, publish_rate=50.0,
                         frame_prefix='rod1/')
    counts = write_bag(tmp_path / 'quiet', run, quiet, namespace='/rod1', clock=False)
    assert set(counts) == {'/rod1/joint_states', '/rod1/tip/deflection',
                           '/rod1/tip/position', '/rod1/frequencies'}
    assert counts['/rod1/joint_states'] == int(T_END * 50) + 1


def test_rosbags_reads_the_custom_types_back_from_the_bag_alone(bag):
    """A reader that knows no rotrod type: it registers them from the bag's definitions."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    assert 'rotrod_interfaces/msg/WhirlEstimate' not in store.types
    with Reader(bag[0]) as reader:
        for conn in reader.connections:
            if conn.msgtype.startswith('rotrod_interfaces/'):
                store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        custom = [c for c in reader.connections if c.msgtype.startswith('rotrod_interfaces/')]
        assert {c.msgtype for c in custom} == {'rotrod_interfaces/msg/DynamicFrequencies',
                                               'rotrod_interfaces/msg/WhirlEstimate'}
        rows = [(conn.msgtype, store.deserialize_cdr(raw, conn.msgtype))
                for conn, _, raw in reader.messages(connections=custom)]
    freq = [m for t, m in rows if t.endswith('DynamicFrequencies')]
    assert len(freq) == int(T_END * RATE) + 1
    for m in freq[::50]:                                   # Eq. 28 at each message's w
        assert m.f1 == pytest.approx((W0 - m.omega) / (2 * math.pi), rel=1e-12)
        assert m.f2 == pytest.approx((W0 + m.omega) / (2 * math.pi), rel=1e-12)
    assert max(m.omega for m in freq) == pytest.approx(2.0, rel=1e-12)
    estimates = [m for t, m in rows if t.endswith('WhirlEstimate')]
    assert len(estimates) == 191 and all(isinstance(m.reason, str) for m in estimates)


def test_metadata_yaml_is_what_jazzys_rosbag2_reads(bag):
    path, counts = bag
    info = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap'
    (rel,) = info['relative_file_paths']
    assert (path / rel).is_file() and rel.endswith('.mcap')
    (mcap_file,) = path.glob('*.mcap')
    with mcap_file.open('rb') as f:
        stats = make_reader(f).get_summary().statistics
    assert info['message_count'] == stats.message_count == sum(counts.values())
    assert info['starting_time']['nanoseconds_since_epoch'] == stats.message_start_time == 0
    assert info['duration']['nanoseconds'] == stats.message_end_time - \
        stats.message_start_time == round(T_END * 1e9)
    (file_info,) = info['files']
    assert file_info['path'] == rel and file_info['message_count'] == stats.message_count
    assert file_info['starting_time'] == info['starting_time']
    assert file_info['duration'] == info['duration']
    assert info['compression_format'] == '' and info['compression_mode'] == ''
    assert info['custom_data'] is None or isinstance(info['custom_data'], dict)
    assert isinstance(info['ros_distro'], str)
    share = Path(sys.prefix) / 'share'
    topics = {}
    for entry in info['topics_with_message_count']:
        meta = entry['topic_metadata']
        topics[meta['name']] = meta['type']
        assert entry['message_count'] == counts[meta['name']]
        assert meta['serialization_format'] == 'cdr'
        # the hash of the installed ROS message package's type description
        package, _, name = meta['type'].split('/')
        described = json.loads((share / package / 'msg' / f'{name}.json').read_text())
        own = [h['hash_string'] for h in described['type_hashes']
               if h['type_name'] == meta['type']]
        assert meta['type_description_hash'] == own[0]
        assert re.fullmatch(r'RIHS01_[0-9a-f]{64}', own[0])
        # v9 QoS: a list of profiles with rmw's policy names (rosbag2_storage qos.cpp)
        (qos,) = meta['offered_qos_profiles']
        assert qos['history'] == 'keep_last' and qos['depth'] == 10
        assert qos['reliability'] == 'reliable' and qos['durability'] == 'volatile'
        assert qos['liveliness'] == 'automatic'
        for duration in ('deadline', 'lifespan', 'liveliness_lease_duration'):
            assert set(qos[duration]) == {'sec', 'nsec'}
        assert qos['avoid_ros_namespace_conventions'] is False
    assert topics == TYPES


def test_rerun_converts_the_bag(bag, tmp_path):
    """A third reader: the Rerun viewer's MCAP loader (rerun-sdk's CLI), ROS 2 decoders."""
    rerun = Path(sys.executable).parent / 'rerun'
    if not rerun.exists():
        pytest.skip('no rerun CLI beside this interpreter (pip install rerun-sdk)')
    from rerun.chunk import RrdReader
    (mcap_file,) = bag[0].glob('*.mcap')
    out = tmp_path / 'bag.rrd'
    done = subprocess.run([str(rerun), 'mcap', 'convert', str(mcap_file), '-o', str(out),
                           '--timeline-type', 'duration'], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    paths = {str(p) for p in RrdReader(str(out)).store().schema().entity_paths()}
    assert set(TYPES) <= paths
    assert {'/joint_states/position', '/joint_states/velocity'} <= paths


def test_rotrod_simulate_writes_a_namespaced_bag_and_refuses_bad_requests(tmp_path):
    cmd = [sys.executable, '-m', 'rotrod_core.cli', 'simulate', '--profile', 'eq26',
           '--t-end', '2']
    path = tmp_path / 'offline'
    done = subprocess.run([*cmd, '--bag', str(path), '--bag-namespace', '/offline',
                           '--bag-frame-prefix', 'offline/', '--bag-rate', '50'],
                          cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert 'ros2 bag play' in done.stdout
    got = read(path)
    assert set(got) == {'/clock'} | {'/offline' + t for t in TYPES if t != '/clock'}
    assert len(got['/offline/joint_states']) == 101                 # 50 Hz over 2 s
    assert got['/offline/tip/position'][0][2].header.frame_id == 'offline/world'
    assert got['/offline/tip/deflection'][0][2].header.frame_id == 'offline/rotor'
    assert got['/offline/markers'][0][2].markers[0].header.frame_id == 'offline/world'
    again = subprocess.run([*cmd, '--bag', str(path)], cwd=ROOT, capture_output=True,
                           text=True)
    assert again.returncode == 2 and 'exists' in again.stderr
    odd = subprocess.run([*cmd, '--bag', str(tmp_path / 'odd'), '--bag-rate', '300'],
                         cwd=ROOT, capture_output=True, text=True)
    assert odd.returncode == 2 and 'whole number' in odd.stderr
    assert not (tmp_path / 'odd').exists()
    nothing = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    assert nothing.returncode == 2 and 'nothing to write' in nothing.stderr
    with pytest.raises(ValueError, match='estimate_rate'):
        PublicationSettings(estimate_rate=200.0)
    with pytest.raises(ValueError, match='namespace'):
        write_bag(tmp_path / 'ns', None, namespace='offline')
    bad_ns = subprocess.run([*cmd, '--bag', str(tmp_path / 'ns'), '--bag-namespace', 'x'],
                            cwd=ROOT, capture_output=True, text=True)
    assert bad_ns.returncode == 2 and 'namespace must start with /' in bad_ns.stderr
