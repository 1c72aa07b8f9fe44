"""The main job: the paper's spin-up scenario through the three ROS nodes.

Starts ``simulator`` (Table 1, faster than real time on /clock by default),
``rerun_logger`` and ``profile_publisher`` (Eq. 26 for 40 s of simulated time, sent
as one FollowJointTrajectory goal that the simulator executes on its clock) as
separate processes with config/table1.yaml and config/demo.yaml, waits for the
profile to end, stops the logger (which closes the recording) and the simulator,
reads the recording back and prints, per stage, the extreme u and v beside the
offline ``simulate`` run of the same profile.

``--profile planned`` sends the planned spin-up of config/planned.yaml instead
(added after the other files, for every node) and holds 2 rad/s for HOLD s after it;
it prints the arrival, the peak deflection and the whirl left after arrival, recorded
beside the offline run of the plan the profile publisher made from the same files.

DDS stays on this machine unless the caller set otherwise
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST; a ROS_DOMAIN_ID is chosen if none is set).
"""

from __future__ import annotations

import argparse
import math
import os
import random
import signal
import subprocess
import sys
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np
import yaml

from rotrod_core import RodParams, simulate, whirl_residual
from rotrod_core.analysis.alignment import profile_delay
from rotrod_core.analysis.modes import static_deflection
from rotrod_core.analysis.stages import format_stage_table, series_stage_extremes
from rotrod_core.command.planner import fitted_whirl_residual
from rotrod_core.command.profiles import Eq26Profile, SpinUpProfile
from rotrod_core.command.registry import describe, plan_from_options
from rotrod_core.reporting import recording

from .child_process import ending_with_this_process
from .install import executable, share_file
from .parameters import defaults, rod_params

EXECUTABLES = ('simulator', 'rerun_logger', 'profile_publisher')
PARAM_FILES = ('config/table1.yaml', 'config/demo.yaml')
"""Parameter files of every node, in order (later ones override)."""
PLANNED_FILE = 'config/planned.yaml'
"""Added after PARAM_FILES for ``--profile planned``."""
PROFILES = ('eq26', 'planned')
HOLD = 5.0
"""Simulated time held at the target speed after a planned spin-up, s."""
SETTLE = 0.5
"""Time after a plan's arrival before its whirl is measured, s (the stream's delay)."""


class DemoError(RuntimeError):
    """The run did not complete (the reason and the nodes' logs are in the message)."""


def ros_environment(env: Mapping[str, str]) -> dict[str, str]:
    """The environment for the nodes: DDS on localhost and a domain id, unless set."""
    env = dict(env)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env.setdefault('ROS_DOMAIN_ID', str(random.randint(1, 100)))
    return env


def param_files(profile: str = 'eq26') -> tuple[str, ...]:
    """The parameter files of every node for ``profile``, in order."""
    return PARAM_FILES + ((PLANNED_FILE,) if profile == 'planned' else ())


def _file_values(files: Iterable[str], node: str, values: dict) -> dict:
    """``values`` updated with the files' "/**" and "/**/<node>" parameters, in order."""
    values = dict(values)
    for f in files:
        doc = yaml.safe_load(share_file(f).read_text()) or {}
        for key in ('/**', f'/**/{node}'):
            values.update((doc.get(key) or {}).get('ros__parameters') or {})
    return values


def planned_profile(files: Iterable[str]) -> tuple[SpinUpProfile, dict[str, Any], RodParams]:
    """The plan the profile publisher makes from ``files``: (profile, its options, rod).

    As the node plans it: for the simulator's rod and limits (the simulator's parameters
    from the files: what its robot_description carries), with the publisher's options,
    through the same functions (rod_params, plan_from_options).
    """
    simulator = _file_values(files, 'rotrod_simulator', defaults())
    params = rod_params(simulator)
    options = _file_values(files, 'rotrod_profile_publisher', {
        name: simulator[name] for name in ('max_angular_acceleration', 'deflection_limit')})
    return plan_from_options(params, options), options, params


def node_commands(output: Path, speed: float | None, real_time: bool, profile: str = 'eq26',
                  duration: float | None = None) -> dict[str, list[str]]:
    """The three commands (name -> argv), with their parameter files and overrides.

    ``duration``: where the profile publisher's trajectory ends (s; default: the files').
    """
    files = []
    for f in param_files(profile):
        files += ['--params-file', str(share_file(f))]
    sim_over, pub_over = [], []
    if duration is not None:
        pub_over += ['-p', f'duration:={float(duration)!r}']
    if real_time:
        sim_over = ['-p', 'real_time_factor:=1.0']
        pub_over += ['-p', 'use_sim_time:=false']
    elif speed is not None:
        sim_over = ['-p', f'real_time_factor:={float(speed)}']
    return {
        'simulator': [*executable('simulator'), '--ros-args', *files, *sim_over],
        'rerun_logger': [*executable('rerun_logger'), '--ros-args', *files,
                         '-p', f'output:={output}'],
        'profile_publisher': [*executable('profile_publisher'), '--ros-args', *files,
                              *pub_over],
    }


class Processes:
    """The node processes, each logging to its own file; they end with this process."""

    def __init__(self, log_dir: Path, env: Mapping[str, str]):
        self.log_dir, self.env = log_dir, env
        self.procs: dict[str, tuple[subprocess.Popen, IO[str]]] = {}
        log_dir.mkdir(parents=True, exist_ok=True)

    def start(self, name: str, cmd: list[str]) -> subprocess.Popen:
        """Start ``cmd`` as ``name`` in its own session, output to ``<name>.log``."""
        log = open(self.log_dir / f'{name}.log', 'w')  # closed in stop()
        proc = subprocess.Popen(ending_with_this_process(cmd), stdout=log,
                                stderr=subprocess.STDOUT, env=self.env, start_new_session=True)
        self.procs[name] = (proc, log)
        return proc

    def log(self, name: str) -> str:
        """The output of ``name`` so far."""
        return (self.log_dir / f'{name}.log').read_text(errors='replace')

    def wait_for_log(self, name: str, text: str, timeout: float) -> None:
        """Wait until ``text`` appears in the output of ``name`` (DemoError if not)."""
        proc = self.procs[name][0]
        deadline = time.monotonic() + timeout
        while text not in self.log(name):
            if proc.poll() is not None:
                raise DemoError(f'{name} exited with {proc.returncode}:\n{self.log(name)}')
            if time.monotonic() > deadline:
                raise DemoError(f'{name} did not report "{text}" within {timeout:g} s:\n'
                                f'{self.log(name)}')
            time.sleep(0.05)

    def stop(self, name: str, timeout: float = 10.0) -> int | None:
        """SIGINT, then SIGKILL after ``timeout`` s; return the exit status."""
        proc, log = self.procs[name]
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        log.close()
        return proc.returncode

    def stop_all(self) -> None:
        """Stop every process still running."""
        for name in list(self.procs):
            self.stop(name)


def run(output: str | Path = 'out/rotrod.rrd', *, speed: float | None = None,
        real_time: bool = False, timeout: float | None = None, quiet: bool = False,
        profile: str = 'eq26') -> dict[str, Any]:
    """Run the scenario; return the summary (also printed unless ``quiet``).

    ``profile``: ``eq26`` (the paper's) or ``planned`` (config/planned.yaml's).
    """
    if profile not in PROFILES:
        raise ValueError(f'profile must be one of {PROFILES}, got {profile!r}')
    output = Path(output).resolve()
    if output.exists():
        output.unlink()
    say = (lambda *a: None) if quiet else print
    env = ros_environment(os.environ)
    factor = 1.0 if real_time else float(speed or 2.0)
    planned: SpinUpProfile | None = None
    eq26 = Eq26Profile(period=15.0, omega_target=2.0)
    if profile == 'planned':
        planned, values, planned_rod = planned_profile(param_files(profile))
        t_run = planned.end_time + HOLD
        what = f'the planned spin-up of {PLANNED_FILE} (Table 1)'
        cmds = node_commands(output, speed, real_time, profile, duration=t_run)
    else:
        t_run = 40.0
        what = 'Eq. 26 (Table 1)'
        cmds = node_commands(output, speed, real_time)
    timeout = timeout or 60.0 + 3.0 * t_run / factor
    procs = Processes(output.parent / 'logs', env)
    say(f'rotrod demo: {what} through simulator, profile_publisher and '
        f'rerun_logger; {t_run:g} s of simulated time at {factor:g}x real time '
        f'(ROS_DOMAIN_ID={env["ROS_DOMAIN_ID"]}, discovery '
        f'{env["ROS_AUTOMATIC_DISCOVERY_RANGE"]})')
    if planned is not None:
        say(describe(planned, values)[0])
    t0 = time.monotonic()
    try:
        procs.start('simulator', cmds['simulator'])
        procs.wait_for_log('simulator', 'ready', 30)
        procs.start('rerun_logger', cmds['rerun_logger'])
        # the profile starts once the logger has the simulator's data: its subscriptions
        # can match a few seconds after they exist (a missed discovery announcement)
        procs.wait_for_log('rerun_logger', 'receiving: first joint state', 30)
        publisher = procs.start('profile_publisher', cmds['profile_publisher'])
        deadline = time.monotonic() + timeout
        while publisher.poll() is None:
            if 'simulation halted' in procs.log('simulator'):
                raise DemoError('the simulator halted (its /clock stopped, so the profile '
                                'cannot go on):\n' + procs.log('simulator'))
            if time.monotonic() > deadline:
                raise DemoError(f'the profile did not end within {timeout:g} s:\n'
                                f'{procs.log("profile_publisher")}')
            time.sleep(0.1)
        if publisher.returncode != 0:
            raise DemoError(f'profile_publisher failed:\n{procs.log("profile_publisher")}')
        time.sleep(1.0 / factor + 0.3)            # the last second of simulated time
        if procs.stop('rerun_logger') != 0:
            raise DemoError(f'rerun_logger failed:\n{procs.log("rerun_logger")}')
        procs.stop('simulator')
    finally:
        procs.stop_all()
    wall = time.monotonic() - t0
    if planned is not None:
        summary = summarize_planned(output, planned, planned_rod, t_run)
    else:
        summary = summarize(output, eq26, t_run)
    summary['wall_s'] = wall
    say(summary['table'])
    say(f'max |u - u_offline| = {summary["du"] * 1e3:.2e} mm '
        f'({summary["du_rel"]:.2%} of max u), max |v - v_offline| = {summary["dv"] * 1e3:.2e} '
        f'mm ({summary["dv_rel"]:.2%} of max |v|); ' + (
            f'the profile starts {summary["lead_s"]:.3f} s into the recording'
            if planned is None else
            f'the hub starts moving {summary["lead_s"] + planned.t_start:.3f} s into the '
            'recording'))
    say(f'recording: {output} ({summary["samples"]} samples, {wall:.1f} s wall); open it '
        f'with: rerun {output}')
    return summary


def summarize(path: Path, profile: Eq26Profile, t_run: float) -> dict[str, Any]:
    """Stage extremes of the recorded run beside the offline run of the same profile."""
    t, w = recording.read_series(path, recording.OMEGA)
    tu, u = recording.read_series(path, recording.U)
    _, v = recording.read_series(path, recording.V)
    shift = profile_delay(t, w, profile)
    keep = (tu - shift >= 0) & (tu - shift <= t_run)
    tt, uu, vv = tu[keep] - shift, u[keep], v[keep]
    offline = simulate(RodParams(), profile, t_run, dt=1e-3)
    du = float(np.max(np.abs(uu - np.interp(tt, offline.t, offline.u))))
    dv = float(np.max(np.abs(vv - np.interp(tt, offline.t, offline.v))))
    recorded = series_stage_extremes(tt, uu, vv, profile.period, t_end=t_run)
    reference = series_stage_extremes(offline.t, offline.u, offline.v, profile.period)
    lead = shift - min(t[0], tu[0])       # the recording's start to the profile's
    return {'table': format_stage_table(recorded, reference), 'shift': shift, 'lead_s': lead,
            'du': du, 'dv': dv, 'du_rel': du / float(np.max(offline.u)),
            'dv_rel': dv / float(np.max(np.abs(offline.v))), 'samples': int(len(t)),
            'stages': recorded, 'reference': reference}


def summarize_planned(path: Path, profile: SpinUpProfile, params: RodParams,
                      t_run: float) -> dict[str, Any]:
    """A planned spin-up's recording beside the offline run of the plan.

    The arrival (the recorded w first at the target), the peak deflection, and the
    whirl after arrival: the free whirl about the static deflection fitted to the
    recorded motion from SETTLE s after arrival to the end (``fitted_whirl_residual``),
    beside the plan's prediction, the offline run's (``whirl_residual`` at the
    arrival) and Eq. 26's.
    """
    predicted = profile.residual_amplitude
    if predicted is None:
        raise ValueError('the profile is not a plan: it predicts no residual whirl')
    t, w = recording.read_series(path, recording.OMEGA)
    tu, u = recording.read_series(path, recording.U)
    _, v = recording.read_series(path, recording.V)
    shift = profile_delay(t, w, profile, search=profile.end_time)
    keep = (tu - shift >= 0) & (tu - shift <= t_run)
    tt, uu, vv = tu[keep] - shift, u[keep], v[keep]
    target, end = profile.omega_target, profile.end_time
    n = math.ceil(t_run / 1e-3)
    offline = simulate(params, profile, t_run, dt=t_run / n,
                       initial={'u': static_deflection(params, profile.omega_start)[0]})
    arrived = float(t[np.nonzero(w == target)[0][0]] - shift)
    after = tt >= end + SETTLE
    whirl, misfit = fitted_whirl_residual(params, target, tt[after], uu[after], vv[after])
    i = int(np.argmin(np.abs(offline.t - end)))
    offline_whirl = whirl_residual(params, target, offline.u[i], offline.v[i], offline.du[i],
                                   offline.dv[i])
    eq26 = simulate(params, Eq26Profile(period=15.0, omega_target=target), 15.0, dt=1e-3)
    eq26_whirl = whirl_residual(params, target, eq26.u[-1], eq26.v[-1], eq26.du[-1],
                                eq26.dv[-1])
    du = float(np.max(np.abs(uu - np.interp(tt, offline.t, offline.u))))
    dv = float(np.max(np.abs(vv - np.interp(tt, offline.t, offline.v))))
    peak = float(np.max(np.hypot(uu, vv)))
    rows = [
        ('arrival at the target speed [s]', f'{arrived:.3f}', f'{end:.3f}'),
        ('peak deflection [mm]', f'{1e3 * peak:.5f}',
         f'{1e3 * float(np.max(np.hypot(offline.u, offline.v))):.5f}'),
        ('whirl after arrival [um]', f'{1e6 * whirl:.3f}', f'{1e6 * offline_whirl:.3f}'),
    ]
    lines = [f'{"":<34}{"recorded":>12}{"offline":>12}']
    lines += [f'{a:<34}{b:>12}{c:>12}' for a, b, c in rows]
    lines.append(f'(the plan predicts {1e6 * predicted:.3f} um; Eq. 26 leaves '
                 f'{1e6 * eq26_whirl:.3f} um offline; recorded: the free whirl about the '
                 f'static deflection fitted from {SETTLE:g} s after the plan to the end, '
                 f'misfit {1e6 * misfit:.3f} um rms)')
    lead = shift - min(t[0], tu[0])
    return {'table': '\n'.join(lines), 'shift': shift, 'lead_s': lead, 'du': du, 'dv': dv,
            'du_rel': du / float(np.max(offline.u)),
            'dv_rel': dv / float(np.max(np.abs(offline.v))), 'samples': int(len(t)),
            'arrival_s': arrived, 'peak_m': peak, 'whirl_m': whirl,
            'offline_whirl_m': offline_whirl, 'eq26_whirl_m': eq26_whirl,
            'predicted_m': predicted, 'duration_s': profile.duration}


def main(argv: list[str] | None = None) -> int:
    """``python -m rotrod_ros.demo``, which ``rotrod demo`` runs (exit 1 on a failure)."""
    parser = argparse.ArgumentParser(
        prog='rotrod demo', description="the paper's spin-up scenario through the ROS "
                                        'nodes, to a Rerun recording, with a stage summary')
    parser.add_argument('-o', '--output', default='out/rotrod.rrd',
                        help='Rerun recording to write (default out/rotrod.rrd)')
    parser.add_argument('--speed', type=float, default=None,
                        help='real-time factor of the simulator (default 2, from '
                             'config/demo.yaml)')
    parser.add_argument('--real-time', action='store_true',
                        help='run at wall-clock speed (no /clock)')
    parser.add_argument('--profile', choices=PROFILES, default='eq26',
                        help="eq26 (the paper's, default) or planned (the planned spin-up of "
                             f'{PLANNED_FILE})')
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.speed is not None and not (math.isfinite(args.speed) and args.speed > 0):
        parser.error(f'--speed must be a finite number > 0, got {args.speed!r}')
    try:
        run(args.output, speed=args.speed, real_time=args.real_time, profile=args.profile)
    except DemoError as exc:
        print(f'rotrod demo: {exc}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
