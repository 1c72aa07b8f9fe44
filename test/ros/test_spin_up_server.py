"""The SpinUp server's reading of a goal's motion, fed messages directly (the acceptance
tests, test/acceptance/test_spin_up_action.py, run it through the executables)."""

from types import SimpleNamespace

import pytest
from geometry_msgs.msg import Vector3Stamped
from sensor_msgs.msg import JointState

from rotrod_ros.messages import HUB_JOINT, stamp
from rotrod_ros.spin_up_server import SpinUpServer, _Run

pytestmark = pytest.mark.ros


def stamped(msg, t):
    msg.header.stamp = stamp(t)
    return msg


def joint_state(t, w):
    return stamped(JointState(name=[HUB_JOINT], velocity=[w]), t)


def deflection(t, u):
    msg = stamped(Vector3Stamped(), t)
    msg.vector.x = u
    return msg


def test_the_goals_motion_counts_from_its_start_before_the_tick_that_notes_the_acceptance():
    """The simulator starts a trajectory on its acceptance, and its joint states may
    arrive before the server's next timer tick notes that acceptance (``started``, the
    feedback's phase): they are the goal's motion. The first change of w among them
    starts the goal's duration, w at the target is its arrival, and the tip's samples
    count toward the peak. (On CI three 100 Hz states were missed that way: an Eq. 26
    goal of T = 15 s measured 14.97 s.)"""
    logger = SimpleNamespace(info=lambda *_: None)
    server = SpinUpServer(SimpleNamespace(get_logger=lambda: logger), settle_time=0.5,
                          residual_window=4.0, arrival_timeout=5.0)
    server.on_joint_state(joint_state(10.0, 0.0))           # at rest: the goal's start
    server.run = run = _Run(goal_handle=None, target=2.0, omega_start=0.0, plan=None,
                            params=None, future=None)
    for k, w in enumerate((0.0, 1e-9, 0.5, 2.0)):
        server.on_joint_state(joint_state(10.01 + 0.01 * k, w))
        server.on_deflection(deflection(10.01 + 0.01 * k, 1e-4 * k))
    assert run.started is None                                 # no tick yet
    assert run.moved == pytest.approx(10.02, abs=1e-9)
    assert run.arrival == pytest.approx(10.04, abs=1e-9)
    assert run.peak == pytest.approx(3e-4) and len(run.samples) == 4
