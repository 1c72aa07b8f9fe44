"""``control_msgs/``: wire-compatible with the published control_msgs of ROS 2 Jazzy.

The repository holds the part of ros-controls/control_msgs that a FollowJointTrajectory
client needs (the action and the JointTolerance and JointComponentTolerance messages it
holds), written with rotrod's comments, so that a client built against the published
package talks, unchanged, to a trajectory server built with this one: every type's hash
(RIHS01, which Jazzy checks when it matches endpoints) and every constant must be the
published one. Both references below were taken from the published files at tag 5.5.0
(commit ec20e603fe94e3280b6d7ca5f419a40ed9a37e1b of github.com/ros-controls/control_msgs,
on its jazzy branch: the release Jazzy's distribution file lists; the three files are the
same in every 5.x release, 5.0.0 to 5.8.0): :data:`PUBLISHED_DEFINITIONS` is the SHA-256
of each file with its comments and spacing taken out (``normalized`` in
test/interface_tools.py); :data:`PUBLISHED_HASHES` are the type hashes rosidl computed
when the published package (all of it) was built with tools/build_interfaces.py into a
temporary prefix (the same generators, pinned in constraints.txt). On a ROS install the
distribution's control_msgs is used and none is built (tools/build_interfaces.py).
"""

from interface_tools import PublishedCopyTests

PUBLISHED_DEFINITIONS = {
    'action/FollowJointTrajectory.action':
        'dd1412800707688a7849ee54c4d2b38eb8ccde18be6aa031384b44ac0264a8f1',
    'msg/JointComponentTolerance.msg':
        'fa79588f623ec59a31f311abfa89e6287e6513613d51accec8337627cea86a6c',
    'msg/JointTolerance.msg': 'c8e83c214f64f31ba9ab67a615a61044c0e62075f71f7173811d3338ab97a04d',
}
"""SHA-256 of the normalized published definitions, by file."""

PUBLISHED_HASHES = {
    'action/FollowJointTrajectory':
        'RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6',
    'msg/JointComponentTolerance':
        'RIHS01_739ea7566931944d33830fa10f1bf5e7a7fbdc3172bce7a7eaac642bd6e3ffa4',
    'msg/JointTolerance':
        'RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648',
}
"""The published package's type hash of each type (its top-level entry)."""


class TestThePublishedCopy(PublishedCopyTests):
    PACKAGE = 'control_msgs'
    VERSION = '5.5.0'
    DEFINITIONS = PUBLISHED_DEFINITIONS
    HASHES = PUBLISHED_HASHES


def test_the_generated_classes_carry_the_published_constants():
    from control_msgs.action import FollowJointTrajectory
    from control_msgs.msg import JointComponentTolerance
    result = FollowJointTrajectory.Result
    assert (result.SUCCESSFUL, result.INVALID_GOAL, result.INVALID_JOINTS) == (0, -1, -2)
    assert (result.OLD_HEADER_TIMESTAMP, result.PATH_TOLERANCE_VIOLATED,
            result.GOAL_TOLERANCE_VIOLATED) == (-3, -4, -5)
    assert (JointComponentTolerance.X_AXIS, JointComponentTolerance.TRANSLATION,
            JointComponentTolerance.ROTATION) == (1, 4, 5)


def _round_trip(msg):
    """``msg`` through rclpy's serialization (the C type support) and back."""
    from rclpy.serialization import deserialize_message, serialize_message
    return deserialize_message(serialize_message(msg), type(msg))


def _hub_point(position: float, velocity: float, seconds: int):
    """A trajectory point of the one joint, 'hub', due ``seconds`` after the start."""
    from builtin_interfaces.msg import Duration
    from trajectory_msgs.msg import JointTrajectoryPoint
    return JointTrajectoryPoint(positions=[position], velocities=[velocity],
                                time_from_start=Duration(sec=seconds))


def test_a_hub_goal_and_its_feedback_round_trip_through_rclpys_serialization():
    from control_msgs.action import FollowJointTrajectory
    from control_msgs.msg import JointTolerance

    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = ['hub']
    goal.trajectory.points = [_hub_point(0.0, 0.0, 0), _hub_point(3.0, 2.0, 3)]
    goal.path_tolerance = [JointTolerance(name='hub', velocity=0.05)]
    goal.goal_tolerance = [JointTolerance(name='hub', position=-1.0, velocity=0.01)]
    goal.goal_time_tolerance.nanosec = 500_000_000
    assert _round_trip(goal) == goal
    feedback = FollowJointTrajectory.Feedback(joint_names=['hub'])
    feedback.desired.velocities = [2.0]
    feedback.actual.velocities = [1.999]
    back = _round_trip(feedback)
    assert back.joint_names == ['hub'] and list(back.actual.velocities) == [1.999]
    result = FollowJointTrajectory.Result(
        error_code=FollowJointTrajectory.Result.GOAL_TOLERANCE_VIOLATED, error_string='hub')
    assert _round_trip(result) == result
