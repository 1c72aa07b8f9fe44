"""rotrod lockstep controller: a torque controller that steps the simulator, run after run alike.

Node ``rotrod_lockstep_controller``, the example of testing a controller
deterministically (docs/simulation_control.md#lockstep). It drives the simulator
through the ROS 2 simulation_interfaces standard only, so the same node would step
any simulator that serves it. Start the simulator with ``drive:=torque`` (and
``start_paused:=true``, so that nothing runs before the controller is there); then:

1. pause (SetSimulationState; already paused or stopped is fine) and reset in full
   (ResetSimulation SCOPE_ALL: simulated time 0, the initial state);
2. every ``control_steps`` physics steps: read the tip (GetEntityState ``tip``),
   compute the hub torque (rotrod_core.command.damped_spin_up: a spin-up to
   ``omega_target`` with the rod's tangential vibration fed back as damping), publish
   it on cmd/torque (reliable) and step (StepSimulation, or the SimulateSteps action
   with ``stepping:=action``): the simulator applies a command that reached it before
   a step request at that request's start, and a command published before the request
   from the same process reaches it first;
3. after ``duration`` s of simulated time, write each control instant (the stamp in
   ns, w, the tip's world position and velocity, the torque; floats as Python's repr,
   which reads back to the same float) to ``output`` and exit with status 0 (1 if a
   call failed: the reason is logged).

Nothing depends on the wall clock: the same parameters give the same file, byte for
byte, on a loaded machine or an idle one.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rclpy.node import Node
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result, SimulationState
from simulation_interfaces.srv import (
    GetEntityState,
    ResetSimulation,
    SetSimulationState,
    StepSimulation,
)
from std_msgs.msg import Float64

from rotrod_core.command.damped_spin_up import DampedSpinUp

from . import interfaces, node_main, parameter_specs
from .interfaces import action_client, client, pub
from .node_main import ConfigurationError
from .parameter_specs import Spec

NODE_NAME = 'rotrod_lockstep_controller'
READY_TIMEOUT = 30.0
"""Wall seconds to wait for the simulator's services to appear."""
COLUMNS = ('stamp_ns', 'omega', 'x', 'y', 'vx', 'vy', 'torque')
"""The output's columns: stamp ns, w rad/s, tip position m and velocity m/s (world), Q N m."""

_LAW = DampedSpinUp()
READ_ONLY = True
PARAMETERS = (
    Spec('simulator', '/rotrod_simulator', 'the simulator node whose ~/ services are '
         'called (its namespace and name)'),
    Spec('omega_target', _LAW.omega_target, 'the w to spin up to', 'rad/s', -1e3, 1e3),
    Spec('rate', _LAW.rate, 'k_w of the approach to omega_target (> 0)', '1/s', 0.0, 1e3),
    Spec('inertia', _LAW.inertia, "the rotor's inertia the law assumes (> 0; default: "
         "Table 1's)", 'kg m^2', 0.0, 1e3),
    Spec('damping', _LAW.damping, 'c, the feedback of the tangential deflection rate',
         'N s', 0.0, 1e3),
    Spec('max_torque', _LAW.max_torque, 'the torque is clipped to +-this (> 0)', 'N m',
         0.0, 1e3),
    Spec('control_steps', 10, 'physics steps between two control instants', '', 1, 10**6),
    Spec('duration', 4.0, 'simulated time to control for', 's', 0.0, 1e6),
    Spec('stepping', 'service', 'service (StepSimulation) | action (SimulateSteps)',
         choices=('service', 'action')),
    Spec('output', 'lockstep.csv', 'the file written at the end (CSV: ' + ', '.join(COLUMNS)
         + ')'),
)

INTERFACES = (
    pub('cmd/torque', Float64, 'the hub torque, N m, once per control_steps steps, before '
        'the step request (reliable)'),
    client('{simulator}/set_simulation_state', SetSimulationState, 'pause at the start'),
    client('{simulator}/reset_simulation', ResetSimulation, 'SCOPE_ALL at the start'),
    client('{simulator}/get_entity_state', GetEntityState, "the tip's world position and "
           'velocity, the hub angle and rate (its orientation and angular velocity)'),
    client('{simulator}/step_simulation', StepSimulation, 'control_steps steps at a time '
           '(stepping service)'),
    action_client('{simulator}/simulate_steps', SimulateSteps, 'control_steps steps at a '
                  'time (stepping action)'),
)


class CallFailed(RuntimeError):
    """A call to the simulator failed (the reason in the text)."""


class LockstepController(Node):
    """The controller: parameters, clients, and the control loop as an executor task."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        values = parameter_specs.declare(self, PARAMETERS, read_only=READ_ONLY)
        try:
            self.law = DampedSpinUp(values['omega_target'], values['rate'], values['inertia'],
                                    values['damping'], values['max_torque'])
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        self.values = values
        self._io = interfaces.create(self, INTERFACES, names={
            'simulator': values['simulator'].rstrip('/')})
        self._torque = self._io['cmd/torque']
        self.done = False
        self.status = 0
        self.rows: list[tuple] = []

    def start(self) -> None:
        """Run the control loop as a task of the node's executor."""
        assert self.executor is not None
        self.executor.create_task(self._run)

    async def _run(self) -> None:
        try:
            await self._control()
            path = Path(self.values['output'])
            path.write_text(table(self.rows))
            self.get_logger().info(f'done: {len(self.rows)} control instants to {path}')
        except CallFailed as exc:
            self.get_logger().error(f'stopped: {exc}')
            self.status = 1
        self.done = True

    async def _call(self, name: str, request):
        cli = self._io[name]
        if not cli.wait_for_service(timeout_sec=READY_TIMEOUT):
            raise CallFailed(f'no service {cli.srv_name}')
        return await cli.call_async(request)

    @staticmethod
    def _check(result, what: str, also=()) -> None:
        if result.result not in (Result.RESULT_OK, *also):
            raise CallFailed(f'{what}: code {result.result}: {result.error_message}')

    async def _control(self) -> None:
        paused = SetSimulationState.Request(state=SimulationState(
            state=SimulationState.STATE_PAUSED))
        response = await self._call('{simulator}/set_simulation_state', paused)
        self._check(response.result, 'pause',
                    (SetSimulationState.Response.ALREADY_IN_TARGET_STATE,))
        response = await self._call('{simulator}/reset_simulation', ResetSimulation.Request(
            scope=ResetSimulation.Request.SCOPE_ALL))
        self._check(response.result, 'reset')
        steps, v = self.values['control_steps'], self.values
        while True:
            tip = await self._call('{simulator}/get_entity_state',
                                   GetEntityState.Request(entity='tip'))
            self._check(tip.result, 'tip state')
            s = tip.state
            stamp = s.header.stamp.sec * 10**9 + s.header.stamp.nanosec
            p, vel, q = s.pose.position, s.twist.linear, s.pose.orientation
            theta = 2.0 * math.atan2(q.z, q.w)
            omega = s.twist.angular.z
            if stamp >= v['duration'] * 1e9:
                self.rows.append((stamp, omega, p.x, p.y, vel.x, vel.y, 0.0))
                return
            torque = self.law.torque((p.x, p.y), (vel.x, vel.y), theta, omega)
            self.rows.append((stamp, omega, p.x, p.y, vel.x, vel.y, torque))
            self._command(torque)
            await self._step(steps)

    def _command(self, torque: float) -> None:
        """Publish the torque (to a subscribed simulator)."""
        if self._torque.get_subscription_count() == 0:
            raise CallFailed('nobody subscribes to cmd/torque')
        self._torque.publish(Float64(data=torque))

    async def _step(self, steps: int) -> None:
        if self.values['stepping'] == 'service':
            response = await self._call('{simulator}/step_simulation',
                                        StepSimulation.Request(steps=steps))
            self._check(response.result, 'step')
            return
        actions = self._io['{simulator}/simulate_steps']
        if not actions.wait_for_server(timeout_sec=READY_TIMEOUT):
            raise CallFailed('no SimulateSteps server')
        handle = await actions.send_goal_async(SimulateSteps.Goal(steps=steps))
        if not handle.accepted:
            raise CallFailed('SimulateSteps goal rejected')
        result = await handle.get_result_async()
        self._check(result.result.result, 'SimulateSteps')


def table(rows) -> str:
    """The CSV text of the control instants (floats as repr: exact)."""
    lines = [','.join(COLUMNS)]
    lines += [','.join(repr(x) for x in row) for row in rows]
    return '\n'.join(lines) + '\n'


def _parser() -> argparse.ArgumentParser:
    return node_main.parser('lockstep_controller', __doc__, [
        *interfaces.help_lines(INTERFACES), 'Parameters:',
        *parameter_specs.help_lines(PARAMETERS, READ_ONLY)])


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod lockstep_controller``."""
    made: list[LockstepController] = []

    def make() -> LockstepController:
        made.append(LockstepController())
        return made[0]

    code = node_main.run(NODE_NAME, make, _parser(), args, started=LockstepController.start,
                         until=lambda node: node.done)
    return code or (made[0].status if made else 0)


if __name__ == '__main__':
    sys.exit(main())
