"""A fleet of rods: N rods in the namespaces rod0 .. rod{N-1}, from one command.

    python -m rotrod_ros.fleet --rods 10 [--processes] [--profile] [--record]
        [--duration S] ...

By default one simulator process holds them all, a world of rods (``rods:=N``: their
interfaces under ``rodK/``, frames ``rodK/rotor``, stepped as one batch); with
``--processes`` each rod is a simulator process of its own in its namespace (the layout
before worlds, kept to compare). Every simulator gets config/table1.yaml,
config/fleet.yaml (real time, markers off), then the given files. With ``--profile``
each rod also gets its own profile publisher in its namespace, streaming
config/fleet.yaml's profile (Eq. 26, looped) on its ``cmd/omega``. With ``--record``
each rod gets a rerun logger in its namespace writing ``<log-dir>/rodK.rrd`` (``rerun
<log-dir>/*.rrd`` opens them all). The processes log to
``<log-dir>/<name>.log``; the fleet runs until ``--duration`` has passed or Ctrl-C,
then stops them all. A full ROS install does the same with ``ros2 launch rotrod
fleet.launch.py rods:=10`` (launch/fleet.launch.py).

DDS stays on this machine unless the caller set otherwise
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST; a ROS_DOMAIN_ID is chosen if none is set).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path

from .demo import DemoError, Processes, ros_environment
from .install import executable, share_file

PARAM_FILES = ('config/table1.yaml', 'config/fleet.yaml')
"""Parameter files of every node of the fleet, in order (later ones override)."""
MAX_RODS = 100


def namespaces(rods: int) -> list[str]:
    """The rods' namespaces: /rod0, /rod1, ..."""
    if isinstance(rods, bool) or not isinstance(rods, int) or not 1 <= rods <= MAX_RODS:
        raise ValueError(f'rods must be an integer 1..{MAX_RODS}, got {rods!r}')
    return [f'/rod{k}' for k in range(rods)]


def fleet_commands(rods: int, *, profile: bool = False, params_files=(),
                   processes: bool = False, record: Path | None = None) -> dict[str, list[str]]:
    """The commands (``<name>`` -> argv) that start the fleet.

    One world, or a simulator per rod (``processes``); a profile publisher per rod with
    ``profile``; a rerun logger per rod writing into the directory ``record`` if given.
    """
    files = []
    for f in (*(str(share_file(p)) for p in PARAM_FILES), *map(str, params_files)):
        files += ['--params-file', f]
    cmds = {}
    if not processes:
        cmds['world_simulator'] = [*executable('simulator'), '--ros-args', *files,
                                   '-p', f'rods:={rods}', '-p', f'max_rods:={max(rods, 128)}']
    for ns in namespaces(rods):
        if processes:
            cmds[f'{ns[1:]}_simulator'] = [*executable('simulator'), '--ros-args',
                                           '-r', f'__ns:={ns}', *files,
                                           '-p', f'frame_prefix:={ns[1:]}/']
        if profile:
            cmds[f'{ns[1:]}_profile_publisher'] = [
                *executable('profile_publisher'), '--ros-args', '-r', f'__ns:={ns}', *files]
        if record is not None:
            cmds[f'{ns[1:]}_rerun_logger'] = [
                *executable('rerun_logger'), '--ros-args', '-r', f'__ns:={ns}',
                '-p', f'output:={Path(record) / (ns[1:] + ".rrd")}']
    return cmds


def start(rods: int, log_dir: Path, *, profile: bool = False, params_files=(),
          env: dict | None = None, ready_timeout: float = 60.0,
          processes: bool = False, record: bool = False) -> Processes:
    """Start the fleet and wait until every simulator is ready; return the processes."""
    procs = Processes(Path(log_dir), ros_environment(dict(os.environ) if env is None else env))
    cmds = fleet_commands(rods, profile=profile, params_files=params_files,
                          processes=processes, record=Path(log_dir) if record else None)
    try:
        for name, cmd in cmds.items():
            if name.endswith('_simulator'):
                procs.start(name, cmd)
        for name in cmds:
            if name.endswith('_simulator'):
                procs.wait_for_log(name, 'ready', ready_timeout)
        for name, cmd in cmds.items():
            if not name.endswith('_simulator'):
                procs.start(name, cmd)
    except BaseException:
        procs.stop_all()
        raise
    return procs


def main(argv: list | None = None) -> int:
    """``python -m rotrod_ros.fleet``: run a fleet until the duration or Ctrl-C."""
    parser = argparse.ArgumentParser(prog='python -m rotrod_ros.fleet',
                                     description=__doc__.split('\n')[0])
    parser.add_argument('--rods', type=int, default=10, help='number of rods (default 10)')
    parser.add_argument('--processes', action='store_true',
                        help='a simulator process per rod (the layout before worlds), '
                             'instead of one world')
    parser.add_argument('--profile', action='store_true',
                        help="a profile publisher per rod (config/fleet.yaml's profile)")
    parser.add_argument('--record', action='store_true',
                        help='a rerun logger per rod, writing <log-dir>/rodK.rrd')
    parser.add_argument('--duration', type=float, default=None,
                        help='wall seconds to run (default: until Ctrl-C)')
    parser.add_argument('--params-file', action='append', default=[], type=Path,
                        help='another parameter file for every node (repeatable)')
    parser.add_argument('--log-dir', type=Path, default=Path('out/fleet'),
                        help='where the nodes log (default out/fleet)')
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        namespaces(args.rods)
    except ValueError as exc:
        parser.error(str(exc))
    if args.duration is not None and not args.duration > 0:
        parser.error(f'--duration must be > 0, got {args.duration!r}')
    for f in args.params_file:
        if not f.is_file():
            parser.error(f'--params-file {f}: no such file')
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    try:
        procs = start(args.rods, args.log_dir, profile=args.profile,
                      params_files=args.params_file, processes=args.processes,
                      record=args.record)
    except (DemoError, FileNotFoundError) as exc:
        print(f'fleet: {exc}', file=sys.stderr)
        return 1
    layout = 'a process each' if args.processes else 'one world process'
    print(f'fleet: {args.rods} rods running in /rod0 .. /rod{args.rods - 1}, {layout} '
          f'(ROS_DOMAIN_ID={procs.env["ROS_DOMAIN_ID"]}); logs in {args.log_dir}',
          flush=True)
    deadline = None if args.duration is None else time.monotonic() + args.duration
    try:
        while not stop and (deadline is None or time.monotonic() < deadline):
            dead = [n for n, (p, _) in procs.procs.items() if p.poll() is not None]
            if dead:
                print(f'fleet: {", ".join(dead)} exited:\n{procs.log(dead[0])}',
                      file=sys.stderr)
                return 1
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        stop_fleet(procs)
    return 0


def stop_fleet(procs: Processes) -> None:
    """Stop the publishers and loggers, then the simulators.

    A logger's file then ends with the simulator's last publication.
    """
    for name in list(procs.procs):
        if not name.endswith('_simulator'):
            procs.stop(name)
    procs.stop_all()


if __name__ == '__main__':
    sys.exit(main())
