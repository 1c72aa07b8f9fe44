"""The simulator's simulation_interfaces services and action (the ROS 2 standard, 2.1.0).

What Gazebo (ros_gz_sim), Isaac Sim and O3DE serve, served by the rotrod simulator
under its own name (``~/``, like Gazebo's ``/gzserver/``): features, the simulation
state (playing, paused, stopped), stepping while paused (a service and an action) and
reset by scope, for the whole world; the entities (spawn, delete, their states) are
:mod:`rotrod_ros.entities`'. The stepping itself is
the physics thread's (:meth:`rotrod_core.live.loop.RealTimeLoop.request_steps`, whose
docstring states the lockstep rule); this module turns requests into loop calls and
results into the standard's codes. docs/simulation_control.md describes each call.

State: PLAYING while the loop runs; paused, STOPPED while nothing has happened since
the start (``start_paused``), a SetSimulationState to STOPPED or a full reset, and
PAUSED otherwise. A step is taken in PAUSED or STOPPED (then PAUSED); in PLAYING it is
RESULT_INCORRECT_STATE.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rclpy.action import CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.task import Future
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
from simulation_interfaces.srv import (
    GetSimulationState,
    GetSimulatorFeatures,
    ResetSimulation,
    SetSimulationState,
    StepSimulation,
)

from rotrod_core.live.lockstep import (
    STEPS_CANCELLED,
    STEPS_NOT_PAUSED,
    StepOutcome,
    StepRequest,
)
from rotrod_core.live.loop import RealTimeLoop

from .interfaces import action, srv

FEATURES = (
    SimulatorFeatures.SPAWNING,
    SimulatorFeatures.DELETING,
    SimulatorFeatures.ENTITY_CATEGORIES,
    SimulatorFeatures.SPAWNING_RESOURCE_STRING,
    SimulatorFeatures.ENTITY_STATE_GETTING,
    SimulatorFeatures.ENTITY_STATE_SETTING,
    SimulatorFeatures.ENTITY_INFO_GETTING,
    SimulatorFeatures.SPAWNABLES,
    SimulatorFeatures.SIMULATION_RESET,
    SimulatorFeatures.SIMULATION_RESET_TIME,
    SimulatorFeatures.SIMULATION_RESET_STATE,
    SimulatorFeatures.SIMULATION_RESET_SPAWNED,
    SimulatorFeatures.SIMULATION_STATE_GETTING,
    SimulatorFeatures.SIMULATION_STATE_SETTING,
    SimulatorFeatures.SIMULATION_STATE_PAUSE,
    SimulatorFeatures.STEP_SIMULATION_SINGLE,
    SimulatorFeatures.STEP_SIMULATION_MULTIPLE,
    SimulatorFeatures.STEP_SIMULATION_ACTION,
    SimulatorFeatures.SPAWNING_ENTITIES,
)
"""What works, as GetSimulatorFeatures lists it (not: tags, bounds, named poses, entity
info setting, worlds: there is one world, always loaded)."""
SPAWN_FORMATS = ('urdf',)
"""What SpawnEntity reads: a URDF with rotrod's <rotrod> element (rotrod urdf)."""
SUPPORTED_SCOPES = (ResetSimulation.Request.SCOPE_TIME | ResetSimulation.Request.SCOPE_STATE
                    | ResetSimulation.Request.SCOPE_SPAWNED)
"""The reset scope bits served alone or together (SCOPE_DEFAULT: time and state;
SCOPE_ALL: all three)."""
STATE_NAMES = {SimulationState.STATE_STOPPED: 'stopped', SimulationState.STATE_PLAYING:
               'playing', SimulationState.STATE_PAUSED: 'paused',
               SimulationState.STATE_QUITTING: 'quitting',
               SimulationState.STATE_NO_WORLD: 'no world',
               SimulationState.STATE_LOADING_WORLD: 'loading a world'}

INTERFACES = (
    srv('~/get_simulator_features', GetSimulatorFeatures,
        'simulation_interfaces: what is supported (entity state getting, reset with '
        'scopes time and state, state getting and setting with pause, single and multiple '
        'steps, the step action); docs/simulation_control.md'),
    srv('~/get_simulation_state', GetSimulationState,
        'simulation_interfaces: STATE_PLAYING, STATE_PAUSED, or STATE_STOPPED (paused with '
        'nothing done since the start, a stop or a full reset)'),
    srv('~/set_simulation_state', SetSimulationState,
        'simulation_interfaces: PLAYING (time runs), PAUSED (time stands still, commands '
        'wait for the next step), STOPPED (paused and reset in full); the same state again '
        'is ALREADY_IN_TARGET_STATE, a state that cannot be set INCORRECT_TRANSITION '
        '(QUITTING: RESULT_FEATURE_UNSUPPORTED)'),
    srv('~/step_simulation', StepSimulation,
        'simulation_interfaces: while paused or stopped, take steps physics steps of '
        '1/physics_rate s and publish what falls due (and /clock); answers when done. '
        'Playing: RESULT_INCORRECT_STATE; steps 0 or halted: RESULT_OPERATION_FAILED'),
    srv('~/reset_simulation', ResetSimulation,
        'simulation_interfaces: scope bits SCOPE_TIME (simulated time to 0), SCOPE_STATE '
        '(every rod to its initial state; clears a halt), SCOPE_SPAWNED (the spawned rods '
        'removed); SCOPE_DEFAULT time and state, SCOPE_ALL all three: the same steps and '
        'commands then replay bit for bit. Other bits: RESULT_FEATURE_UNSUPPORTED. The '
        'play/pause state is kept; a step request being served ends'),
    action('~/simulate_steps', SimulateSteps,
           'simulation_interfaces: as ~/step_simulation, with feedback (completed and '
           'remaining steps) after each run of steps up to a publication, and cancel '
           '(ends at the next publication instant, result RESULT_OK)'),
)
"""The standard's services and action, for the simulator's INTERFACES table."""


def _result(code: int, message: str = '') -> Result:
    return Result(result=code, error_message=message)


class SimulationControl:
    """The callbacks of :data:`INTERFACES` over the simulator's loop.

    Args:
        node: the simulator node (the executor that answers is woken through a guard
            condition of its own when the physics thread has taken the steps).
        loop: the simulator's RealTimeLoop.
        reset: ``reset(state, time)`` resets the loop and what the node shows of it
            (the noise sequence too when both); returns the loop's reset result.
        world_frame: the frame id of entity states.
        take_commands: takes the commands that have reached the node and queues them
            (called before each step request is queued).
    """

    def __init__(self, node, loop: RealTimeLoop, reset: Callable[[bool, bool], tuple],
                 world_frame: str, take_commands: Callable[[], int] = lambda: 0, *,
                 remove_spawned: Callable[[], list] = lambda: [],
                 max_steps: Callable[[], int] = lambda: 2**63) -> None:
        self.loop = loop
        self._take_commands = take_commands
        self._reset = reset
        self._remove_spawned = remove_spawned
        self._max_steps = max_steps
        self._world_frame = world_frame
        self._logger = node.get_logger()
        # an awaiting callback resumes when the executor wakes: the loop's thread
        # wakes it once the steps are taken
        self._wake = node.create_guard_condition(lambda: None)
        self.stopped = loop.paused
        """Paused with nothing done since the start, a stop or a full reset."""
        self.callback_group = ReentrantCallbackGroup()
        """Theirs: another call is taken while a step request is served."""

    def callbacks(self) -> dict[str, Any]:
        """The callbacks by interface name, for :func:`rotrod_ros.interfaces.create`."""
        return {
            '~/get_simulator_features': self.get_features,
            '~/get_simulation_state': self.get_state,
            '~/set_simulation_state': self.set_state,
            '~/step_simulation': self.step,
            '~/reset_simulation': self.reset,
            '~/simulate_steps': {'execute_callback': self.simulate_steps,
                                 'cancel_callback': lambda goal_handle: CancelResponse.ACCEPT},
        }

    # ----------------------------------------------------------------- state
    @property
    def state(self) -> int:
        """The SimulationState constant of now."""
        if not self.loop.paused:
            return SimulationState.STATE_PLAYING
        return SimulationState.STATE_STOPPED if self.stopped else SimulationState.STATE_PAUSED

    def get_features(self, request, response):
        """GetSimulatorFeatures: :data:`FEATURES`."""
        response.features = SimulatorFeatures(
            features=list(FEATURES), spawn_formats=list(SPAWN_FORMATS),
            custom_info='rotrod: a world of rods, each a point mass on a flexible rod on a '
                        'rotating disk; entities: each rod, its hub and its tip; spawn '
                        'from the URDF of rotrod urdf; one step = 1/physics_rate s; '
                        'docs/simulation_control.md')
        return response

    def get_state(self, request, response):
        """GetSimulationState."""
        response.state = SimulationState(state=self.state)
        response.result = _result(Result.RESULT_OK)
        return response

    def set_state(self, request, response):
        """SetSimulationState: play, pause or stop (pause and reset in full)."""
        target, now = request.state.state, self.state
        response.result = self.transition(target, now)
        if response.result.result == Result.RESULT_OK:
            self._logger.info(f'simulation state {STATE_NAMES[now]} -> {STATE_NAMES[target]} '
                              f'at simulated time {self.loop.world.time:.6f} s')
        return response

    def transition(self, target: int, now: int) -> Result:
        """Go from state ``now`` to ``target``; the Result (the standard's codes)."""
        S, R = SimulationState, SetSimulationState.Response
        if target == now:
            return _result(R.ALREADY_IN_TARGET_STATE, f'already {STATE_NAMES[now]}')
        if target == S.STATE_QUITTING:
            return _result(Result.RESULT_FEATURE_UNSUPPORTED, 'quitting is not served: stop '
                           'the simulator process (SIGINT)')
        if target not in (S.STATE_PLAYING, S.STATE_PAUSED, S.STATE_STOPPED):
            name = STATE_NAMES.get(target, f'unknown ({target})')
            return _result(R.INCORRECT_TRANSITION, f'state {name} cannot be set: rotrod has '
                           'one world, always loaded; set STATE_PLAYING, STATE_PAUSED or '
                           'STATE_STOPPED')
        if target == S.STATE_PLAYING:
            self.loop.pause(False)
            self.stopped = False
        elif target == S.STATE_PAUSED:
            self.loop.pause(True)
            self.stopped = False
        else:
            with self.loop.lock:
                self.loop.pause(True)
                self._reset(True, True)
                self.stopped = True
        return _result(Result.RESULT_OK)

    # ----------------------------------------------------------------- reset
    def reset(self, request, response):
        """ResetSimulation: scopes TIME, STATE and SPAWNED, alone or together."""
        scope = request.scope
        Req = ResetSimulation.Request
        if scope == Req.SCOPE_DEFAULT:
            scope = Req.SCOPE_TIME | Req.SCOPE_STATE
        elif scope == Req.SCOPE_ALL:
            scope = SUPPORTED_SCOPES
        if scope & ~SUPPORTED_SCOPES:
            response.result = _result(
                Result.RESULT_FEATURE_UNSUPPORTED,
                f'scope {request.scope}: only SCOPE_TIME ({Req.SCOPE_TIME}), SCOPE_STATE '
                f'({Req.SCOPE_STATE}), SCOPE_SPAWNED ({Req.SCOPE_SPAWNED}), together or '
                'alone, SCOPE_DEFAULT or SCOPE_ALL')
            return response
        state, time = bool(scope & Req.SCOPE_STATE), bool(scope & Req.SCOPE_TIME)
        removed = self._remove_spawned() if scope & Req.SCOPE_SPAWNED else []
        with self.loop.lock:
            was_halted, t = self._reset(state, time)
            if self.loop.paused:
                self.stopped = state and time
        done = [w for w, on in (('state', state), ('time', time),
                                (f'{len(removed)} spawned rod(s) removed', removed)) if on]
        message = f'reset ({" and ".join(done) or "nothing"}) at simulated time {t:.6f} s'
        if was_halted:
            message += f' (cleared the halt: {was_halted})'
        self._logger.info(message)
        response.result = _result(Result.RESULT_OK)
        return response

    # ----------------------------------------------------------------- stepping
    def _request(self, steps: int, future: Future, **kwargs) -> Result | None:
        """Queue ``steps`` on the loop; the refusal's Result, or None (queued)."""
        if steps < 1:
            return _result(Result.RESULT_OPERATION_FAILED, f'steps must be at least 1, got '
                           f'{steps}')
        if steps > self._max_steps():
            return _result(Result.RESULT_OPERATION_FAILED, f'steps {steps} is more than one '
                           f'request may ask for (max_steps_per_request {self._max_steps()}): '
                           'ask in several')
        if not self.loop.paused:
            return _result(Result.RESULT_INCORRECT_STATE, 'the simulation is playing: pause '
                           'it (SetSimulationState STATE_PAUSED) to step')
        self._take_commands()

        def done(outcome: StepOutcome) -> None:
            future.set_result(outcome)
            self._wake.trigger()

        problem = self.loop.request_steps(StepRequest(steps, done, **kwargs))
        if problem is not None:
            return _result(Result.RESULT_INCORRECT_STATE if problem == STEPS_NOT_PAUSED
                           else Result.RESULT_OPERATION_FAILED, problem)
        self.stopped = False
        return None

    def _outcome(self, steps: int, outcome: StepOutcome) -> Result:
        if outcome.problem is None:
            return _result(Result.RESULT_OK)
        done = f'{outcome.completed} of {steps} steps taken'
        if outcome.problem == STEPS_CANCELLED:
            return _result(Result.RESULT_OK, f'cancelled: {done}')
        if outcome.problem == STEPS_NOT_PAUSED:      # played before the request's turn
            return _result(Result.RESULT_INCORRECT_STATE, f'{outcome.problem}; {done}')
        return _result(Result.RESULT_OPERATION_FAILED, f'{outcome.problem}; {done}')

    async def step(self, request, response):
        """StepSimulation: ``steps`` steps while paused; answers when they are done."""
        future = Future()
        refused = self._request(request.steps, future)
        if refused is not None:
            response.result = refused
            return response
        response.result = self._outcome(request.steps, await future)
        return response

    async def simulate_steps(self, goal_handle):
        """SimulateSteps: as :meth:`step`, with feedback and cancel."""
        steps = goal_handle.request.steps
        future = Future()

        def progress(completed: int, remaining: int) -> None:
            goal_handle.publish_feedback(SimulateSteps.Feedback(
                completed_steps=completed, remaining_steps=remaining))

        refused = self._request(steps, future, progress=progress,
                                cancelled=lambda: goal_handle.is_cancel_requested)
        if refused is not None:
            goal_handle.abort()
            return SimulateSteps.Result(result=refused)
        outcome = await future
        result = self._outcome(steps, outcome)
        if outcome.problem == STEPS_CANCELLED:
            goal_handle.canceled()
        elif outcome.problem is None:
            progress(outcome.completed, 0)
            goal_handle.succeed()
        else:
            goal_handle.abort()
        return SimulateSteps.Result(result=result)
