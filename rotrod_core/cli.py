"""The ``rotrod`` command line: offline runs, frequencies, critical speeds, the demo.

rotrod simulate --profile eq26 -o run.csv
rotrod simulate --drive torque --torque 0.01 --t-end 10 -o spin.npz
rotrod frequencies --omega 0 1 2
rotrod critical-speed --limit 0.003 --eccentricity 0.05 0.1 0.2
rotrod simulate --profile eq26 -o run.csv --bag run_bag
rotrod plan --omega 2 --robust 0.1 --residual 1e-6 -o plan.csv
rotrod urdf --params-file config/table1.yaml -o rotrod.urdf
rotrod demo
rotrod reproduce --out out/reproduce
rotrod analyze --out out/analyze --only campbell coupling
rotrod sweep --grid eccentricity=0.0:0.2:5 damping_ratio=0,0.01 -o sweep.parquet
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
from pathlib import Path

import numpy as np

from rotrod_core.analysis.critical import STARTS, critical_speed, critical_speed_for_profile
from rotrod_core.analysis.modes import dynamic_frequencies, modal_analysis, static_deflection
from rotrod_core.analysis.stages import format_stage_table, stage_extremes
from rotrod_core.command.planner import plan_spin_up, residual_bound
from rotrod_core.command.profiles import Eq26Profile
from rotrod_core.command.registry import (
    OPTION_PROFILES,
    PROFILE_OPTIONS,
    describe,
    profile_from_options,
)
from rotrod_core.model.description import DriveLimits
from rotrod_core.model.equations import COUPLINGS
from rotrod_core.model.params import DEFAULT_HUB_RADIUS, FIELDS, RodParams
from rotrod_core.offline.simulate import simulate

NUMBER_FIELDS = tuple(f for f in FIELDS if not f.choices)
"""The RodParams fields given as numbers (all but the section's choice)."""
PARAM_FIELDS = tuple(f.name for f in NUMBER_FIELDS)
LIMIT_FIELDS = tuple(f.name for f in dataclasses.fields(DriveLimits))
"""The simulator's limits a robot description carries (rotrod urdf's options)."""
UNITS = {f.name: f.unit for f in NUMBER_FIELDS}


def _finite(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f'must be finite: {text!r}')
    return x


def _add_params(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group('system parameters (SI units; defaults: the paper, Table 1)')
    for f in FIELDS:
        flag = '--' + f.name.replace('_', '-')
        if f.choices:
            g.add_argument(flag, choices=f.choices, default=None, help=f'{f.description} '
                           '(rectangular needs --section-width/-thickness)')
            continue
        default = 'unused' if f.default is None else f'{f.default:g}'
        g.add_argument(flag, type=_finite, default=None,
                       metavar=f.unit.upper().replace(' ', '') if f.unit != '1' else 'RATIO',
                       help=f'{f.description} [{f.unit}] (default {default})'
                       .replace('%', '%%'))


def _params(args) -> RodParams:
    given = {k: getattr(args, k) for k in PARAM_FIELDS if getattr(args, k) is not None}
    if args.section:
        given['section'] = args.section
    return RodParams(**given)


def _add_profile(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group('angular-velocity profile (velocity drive)')
    g.add_argument('--profile', choices=OPTION_PROFILES, default='eq26')
    for o in PROFILE_OPTIONS:
        flags = ['--' + o.name.replace('_', '-')]
        if o.name == 'omega_target':
            flags.append('--omega')
        if o.name == 'table_file':
            g.add_argument('--table', '--table-file', dest='table_file', type=Path,
                           help=o.description)
            continue
        g.add_argument(*flags, dest=o.name, type=_finite, default=None,
                       metavar=o.unit if o.unit not in ('', '1') else 'X',
                       help=f'{o.description} [{o.unit}] (default {o.default:g})')


def _profile_options(args) -> dict:
    return {o.name: getattr(args, o.name) for o in PROFILE_OPTIONS}


def _profile(args):
    """The --profile of the arguments; a planned one is planned for the rod's options."""
    return profile_from_options(args.profile, _profile_options(args), _params(args))


def _initial(args) -> dict:
    out = {}
    for item in args.initial or []:
        name, sep, value = item.partition('=')
        if not sep:
            raise ValueError(f'--initial takes NAME=VALUE, got {item!r}')
        out[name.strip()] = _finite(value)
    return out


def cmd_simulate(args) -> int:
    """Run one offline simulation; write CSV or NPZ (-o) and/or a rosbag2 (--bag)."""
    params = _params(args)
    if args.output is None and args.bag is None:
        raise ValueError('nothing to write: give -o FILE.csv|.npz and/or --bag DIR')
    if args.output is not None:
        if args.output.suffix.lower() not in ('.csv', '.npz'):
            raise ValueError(f'-o must end in .csv or .npz, got {str(args.output)!r}')
        if not args.output.parent.exists():
            raise ValueError(f'output directory {str(args.output.parent)!r} does not exist')
    bag_settings = None
    if args.bag is not None:
        from rotrod_core.live.publication import PublicationSettings
        from rotrod_core.reporting.bag import check_namespace
        bag_settings = PublicationSettings(publish_rate=args.bag_rate,
                                           frame_prefix=args.bag_frame_prefix)
        check_namespace(args.bag_namespace)
        if args.bag.exists():
            raise ValueError(f'{args.bag} exists: a bag is written into a new directory')
    initial = _initial(args)
    if args.drive == 'velocity':
        if args.torque is not None:
            raise ValueError('--torque applies to --drive torque')
        profile = _profile(args)
        for line in describe(profile, _profile_options(args))[:1]:    # what was planned
            print(line)
        run = simulate(params, profile, args.t_end, dt=args.dt, coupling=args.coupling,
                       initial=initial)
    else:
        if args.torque is None:
            raise ValueError('--drive torque needs --torque Q [N m]')
        run = simulate(params, torque=args.torque, t_end=args.t_end, dt=args.dt,
                       coupling=args.coupling, initial=initial)
    summary = (f'({len(run.t)} samples, {args.drive} drive, '
               f'{args.coupling} coupling): max u {1e3 * run.u.max():.6f} mm, '
               f'v in [{1e3 * run.v.min():.6f}, {1e3 * run.v.max():.6f}] mm, '
               f'final omega {run.omega[-1]:.6f} rad/s')
    if args.output is not None:
        run.save(args.output)
        print(f'wrote {args.output} {summary}')
    if bag_settings is not None:
        from rotrod_core.reporting.bag import write_bag
        try:
            counts = write_bag(args.bag, run, bag_settings, namespace=args.bag_namespace)
        except ImportError as exc:
            print(f'rotrod simulate: no bag: {exc} (pip install rosbags)', file=sys.stderr)
            return 2
        size = sum(f.stat().st_size for f in args.bag.iterdir())
        print(f'wrote rosbag2 (mcap) {args.bag}, {size / 1e6:.1f} MB: '
              + ', '.join(f'{topic} {n}' for topic, n in counts.items())
              + f'; play it with: ros2 bag play {args.bag}')
    return 0


def cmd_frequencies(args) -> int:
    """Print the dynamic frequencies, modes and static deflection at constant speeds."""
    params = _params(args)
    print('omega [rad/s]  f1 [Hz]    f2 [Hz]    whirl (f1, f2)      stable  u_static [mm]')
    for w in args.omega:
        f1, f2 = dynamic_frequencies(params, w)
        modes = modal_analysis(params, w)
        whirl = ', '.join(m.whirl for m in modes.modes)
        us, _ = static_deflection(params, w)
        print(f'{w:13.4f}  {f1:9.6f}  {f2:9.6f}  {whirl:<18}  {str(modes.stable):<6}  '
              f'{1e3 * us:.6f}')
    return 0


def cmd_critical(args) -> int:
    """Print critical speeds (closed forms and, on request, numerical for a profile)."""
    params = _params(args)
    r0 = np.asarray(args.eccentricity_list if args.eccentricity_list else
                    [params.eccentricity], dtype=float)
    batch = params.replace(eccentricity=r0)
    cols = {s: critical_speed(batch, args.limit, s) for s in STARTS}
    if args.profile_numerical:
        prof = _profile(args)
        cols[f'{args.profile} (numerical)'] = critical_speed_for_profile(
            batch, prof, args.limit, t_end=args.t_end, dt=args.dt)
    print(f'critical angular velocity [rad/s] for a deflection limit of {args.limit} m')
    print('r0 [m]     ' + ''.join(f'{k:>24}' for k in cols))
    for i, r in enumerate(r0):
        print(f'{r:<10.4f} ' + ''.join(f'{np.atleast_1d(v)[i]:24.6f}' for v in cols.values()))
    return 0


def cmd_plan(args) -> int:
    """Plan the fastest vibration-free change of speed; CSV, PNG and a summary line."""
    params = _params(args)
    if args.output.suffix.lower() != '.csv':
        raise ValueError(f'-o must end in .csv, got {str(args.output)!r}')
    if not args.output.parent.exists():
        raise ValueError(f'output directory {str(args.output.parent)!r} does not exist')
    plan = plan_spin_up(params, args.omega, omega_start=args.start,
                        deflection_limit=args.deflection_limit, residual=args.residual,
                        robust=args.robust, max_angular_acceleration=args.max_acc)
    T = plan.duration
    start = static_deflection(params, args.start)[0]
    run = simulate(params, plan, 1.25 * T, dt=T / 1000, initial={'u': start})
    header = 't_s,omega_rad_s,omega_dot_rad_s2,u_m,v_m'
    np.savetxt(args.output, np.c_[run.t, run.omega, run.omega_dot, run.u, run.v],
               delimiter=',', header=header, comments='', fmt='%.10g')
    figure = args.output.with_suffix('.png')
    from rotrod_core.reporting.figures import require_matplotlib, spin_up_plan
    try:
        require_matplotlib()
    except ImportError as exc:
        figure = None
        print(f'rotrod plan: no figure: {exc}', file=sys.stderr)
    if figure is not None:
        reference = reference_run = None
        if args.start == 0:
            reference = Eq26Profile(period=15.0, omega_target=args.omega)
            reference_run = simulate(params, reference, 15.0, dt=0.01)
        spin_up_plan(plan, run, figure, reference, reference_run, args.deflection_limit)
    predicted = [math.nan if x is None else x for x in (
        plan.peak_deflection, plan.residual_amplitude, plan.band_residual)]
    band = (f', band (1 +- {args.robust:g}) w0 residual {residual_bound(predicted[2])}'
            if args.robust else '')
    print(f'plan {args.start:g} -> {args.omega:g} rad/s: duration {T:.3f} s, peak '
          f'{predicted[0] * 1e3:.3f} mm, residual '
          f'{residual_bound(predicted[1])}{band}, '
          f'max |w\'| {plan.max_angular_acceleration:.3g} rad/s^2; wrote {args.output}'
          + (f' and {figure}' if figure is not None else ''))
    return 0


def cmd_urdf(args) -> int:
    """Write the URDF for the parameter files and options (stdout without -o)."""
    from rotrod_core.model.urdf import (
        Ros2Control,
        drive_limits_from_files,
        rod_params_from_files,
        simulator_parameters,
        urdf_text,
    )
    files = args.params_file or []
    ros2_control = None
    if args.ros2_control:
        ros2_control = Ros2Control(tuple(args.ros2_control), args.joint_commands_topic,
                                   args.joint_states_topic)
    elif args.joint_commands_topic != Ros2Control.joint_commands_topic or (
            args.joint_states_topic != Ros2Control.joint_states_topic):
        raise ValueError('--joint-commands-topic and --joint-states-topic go with '
                         '--ros2-control')
    params = rod_params_from_files(files, namespace=args.namespace)
    given = {k: getattr(args, k) for k in PARAM_FIELDS if getattr(args, k) is not None}
    if args.section:
        given['section'] = args.section
    disk_radius = args.disk_radius
    if disk_radius is None:
        disk_radius = float(simulator_parameters(files, namespace=args.namespace).get(
            'disk_radius', DEFAULT_HUB_RADIUS))
    limits = drive_limits_from_files(files, namespace=args.namespace)
    limits = dataclasses.replace(limits, **{
        k: getattr(args, k) for k in LIMIT_FIELDS if getattr(args, k) is not None})
    text = urdf_text(params.replace(**given), limits=limits, disk_radius=disk_radius,
                     ros2_control=ros2_control)
    if args.output is None:
        sys.stdout.write(text)
        return 0
    if not args.output.parent.exists():
        raise ValueError(f'output directory {str(args.output.parent)!r} does not exist')
    args.output.write_text(text)
    print(f'wrote {args.output}')
    return 0


def cmd_fleet(args) -> int:
    """A fleet of rods through the ROS nodes: ``python -m rotrod_ros.fleet``'s arguments."""
    return _become([sys.executable, '-m', 'rotrod_ros.fleet', *args.fleet_args])


def _become(command: list[str]) -> int:
    """Replace this process by ``command`` (exec); it does not return.

    The nodes' orchestration (the demo, the fleet) lives with the nodes, above the core,
    so it runs as a program of its own; becoming it, rather than waiting for a child,
    lets Ctrl-C and SIGTERM reach it, so that it stops its nodes and finishes its files
    (subprocess.call would SIGKILL a child on KeyboardInterrupt).
    """
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(command[0], command)
    raise AssertionError('unreachable')   # execv returns only by raising OSError


def cmd_demo(args) -> int:
    """The paper's Eq. 26 scenario through the ROS nodes (or offline), per-stage summary."""
    if not args.offline:
        # the nodes' orchestration lives with the nodes (rotrod_ros), above the core
        command = [sys.executable, '-m', 'rotrod_ros.demo', '-o', str(args.output),
                   '--profile', args.profile]
        if args.speed is not None:
            command += ['--speed', repr(args.speed)]
        if args.real_time:
            command.append('--real-time')
        return _become(command)
    params = RodParams()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.profile == 'planned':
        from rotrod_core.reporting.spin_ups import PLANNED
        label, options = PLANNED[-1]
        profile = profile_from_options('planned', options, params)
        end_time = profile.end_time
        assert end_time is not None     # a planned spin-up is constant after its end
        run = simulate(params, profile, end_time + 5.0, dt=1e-3)
        path = run.save(out / 'planned_run.csv')
        print(f'rotrod demo: {label}, Table 1, offline core run')
        print(describe(profile, options)[0])
        print(f'time history: {path}')
        return 0
    profile = Eq26Profile(period=15.0, omega_target=2.0)
    run = simulate(params, profile, 40.0, dt=1e-3)
    path = run.save(out / 'eq26_run.csv')
    print('rotrod demo: the paper\'s spin-up scenario (Eq. 26, Table 1), offline core run')
    print(format_stage_table(stage_extremes(run, profile.period)))
    print(f'time history: {path}')
    return 0


def _command_line(args, name: str, extra: list) -> str:
    return ' '.join(['rotrod', name, '--out', str(args.out)] + extra)


def cmd_reproduce(args) -> int:
    """The paper's Figs. 3-10, the fact report and the Eq. 26 recording, into --out."""
    from rotrod_core.reporting.reproduce import reproduce
    extra = ['--no-recording'] if args.no_recording else []
    try:
        result = reproduce(args.out, recording=not args.no_recording,
                           command=_command_line(args, 'reproduce', extra))
    except ImportError as exc:
        print(f'rotrod reproduce: error: {exc}', file=sys.stderr)
        return 2
    print(f'report: {result.report}')
    print(f'figures: {", ".join(str(p) for p in result.figures)}')
    if result.recording is not None:
        print(f'recording: {result.recording} (open it with: rerun {result.recording})')
    return 0


def cmd_screenshot(args) -> int:
    """The Rerun viewer's own screenshot of a recording, headless."""
    from rotrod_core.reporting.viewer_screenshot import ViewerUnavailable, compact, screenshot
    try:
        path = screenshot(args.recording, args.output)
        if args.compact:
            compact(path)
    except (ViewerUnavailable, FileNotFoundError) as exc:
        print(f'rotrod screenshot: error: {exc}', file=sys.stderr)
        return 2
    print(f'wrote {path}')
    return 0


def cmd_analyze(args) -> int:
    """Campbell diagrams, critical-speed maps and the coupling drift, into --out."""
    from rotrod_core.reporting.analyze import PARTS, analyze
    parts = tuple(args.only) if args.only else PARTS
    extra = ['--only', *parts] if args.only else []
    try:
        result = analyze(args.out, parts, command=_command_line(args, 'analyze', extra))
    except ImportError as exc:
        print(f'rotrod analyze: error: {exc}', file=sys.stderr)
        return 2
    for path in result.files:
        print(f'wrote {path}')
    return 0


def cmd_sweep(args) -> int:
    """Run a parameter sweep on Dask and write its per-run summary to Parquet."""
    from rotrod_core.offline.sweep import SweepClient, grid_table, read_table, run_sweep
    from rotrod_core.reporting.output import ProgressBar
    from rotrod_core.reporting.sweep_file import SweepParquetWriter
    if (args.grid is None) == (args.sets is None):
        raise ValueError('give --grid NAME=... or --sets FILE.csv (one of them)')
    table = grid_table(args.grid) if args.grid else read_table(args.sets)
    base = _params(args)
    profile = _profile(args)
    runs = len(next(iter(table.values())))
    where = args.scheduler or f'a local cluster of {args.workers or "one worker per core"} ' \
        'process(es) on 127.0.0.1'
    print(f'rotrod sweep: {runs} runs of {args.t_end:g} s ({args.profile} profile), chunks '
          f'of {args.chunk_size}, tolerance {args.tolerance:g} m, on {where}', file=sys.stderr)
    meta = {'command': ' '.join(['rotrod', 'sweep', *sys.argv[2:]]) if args.argv is None
            else ' '.join(['rotrod', *args.argv]), 'profile': repr(profile),
            't_end_s': args.t_end, 'tolerance_m': args.tolerance,
            'base_parameters': base._numeric(), 'section': base.section}
    bar = ProgressBar('sweep', runs)
    with SweepParquetWriter(args.output, meta) as writer:
        def on_chunk(chunk):
            writer.write(chunk)
            bar.update(len(chunk.index), sum(s != 'ok' for s in chunk.status))
        with SweepClient(args.scheduler, args.workers) as client:
            summary = run_sweep(table, profile, args.t_end, base=base,
                                tolerance=args.tolerance, client=client,
                                chunk_size=args.chunk_size, on_chunk=on_chunk)
    print(f'wrote {args.output}: {summary.runs} rows, {summary.ok} with results, '
          f'{len(summary.problems)} without, in {summary.elapsed:.1f} s '
          f'({summary.runs / max(summary.elapsed, 1e-9):.0f} runs/s)')
    for index, values, status in summary.problems[:20]:
        shown = ', '.join(f'{k}={v:g}' for k, v in values.items())
        print(f'  run {index} ({shown}): {status}', file=sys.stderr)
    if len(summary.problems) > 20:
        print(f'  ... and {len(summary.problems) - 20} more (status column of the file)',
              file=sys.stderr)
    return 0 if not summary.problems else 1


def _positive_int(text: str) -> int:
    try:
        x = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a whole number: {text!r}') from None
    if x < 1:
        raise argparse.ArgumentTypeError(f'must be >= 1: {text!r}')
    return x


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``rotrod`` command."""
    parser = argparse.ArgumentParser(prog='rotrod', description=__doc__.split('\n')[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='command', required=True)

    p = sub.add_parser('simulate', help='offline run to CSV or NPZ')
    _add_params(p)
    _add_profile(p)
    p.add_argument('--drive', choices=('velocity', 'torque'), default='velocity')
    p.add_argument('--coupling', choices=COUPLINGS, default='exact')
    p.add_argument('--torque', type=_finite, help='hub torque [N m] (torque drive)')
    p.add_argument('--initial', nargs='*', metavar='NAME=VALUE',
                   help='initial state: u, v [m], du, dv [m/s], theta [rad], omega [rad/s]')
    p.add_argument('--t-end', type=_finite, default=40.0, help='duration [s] (default 40)')
    p.add_argument('--dt', type=_finite, default=1e-3, help='step [s] (default 0.001)')
    p.add_argument('-o', '--output', type=Path, help='FILE.csv or FILE.npz')
    g = p.add_argument_group('rosbag2 (MCAP) of the run, as the simulator node publishes it '
                             '(docs/ros_integration.md)')
    g.add_argument('--bag', type=Path, metavar='DIR', help='bag directory to create')
    g.add_argument('--bag-rate', type=_finite, default=100.0, metavar='HZ',
                   help="the node's publish_rate [Hz of simulated time] (default 100)")
    g.add_argument('--bag-namespace', default='/', metavar='NS',
                   help='namespace of the topics, e.g. /offline (default /)')
    g.add_argument('--bag-frame-prefix', default='', metavar='PREFIX',
                   help="prefix of the frame ids world and rotor, as the node's frame_prefix")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser('frequencies', help='dynamic frequencies at constant speeds (Eq. 28)')
    _add_params(p)
    p.add_argument('--omega', type=_finite, nargs='+', default=[0.0, 1.0, 2.0],
                   help='angular velocities [rad/s]')
    p.set_defaults(func=cmd_frequencies)

    p = sub.add_parser('critical-speed', help='critical angular velocity vs eccentricity')
    _add_params(p)
    _add_profile(p)
    p.add_argument('--limit', type=_finite, default=3e-3, help='deflection limit [m]')
    p.add_argument('--eccentricities', dest='eccentricity_list', type=_finite, nargs='+',
                   help='several r0 values [m]')
    p.add_argument('--profile-numerical', action='store_true',
                   help='also the numerical critical speed of --profile')
    p.add_argument('--t-end', type=_finite, default=None, help='run length [s]')
    p.add_argument('--dt', type=_finite, default=2e-3, help='step [s]')
    p.set_defaults(func=cmd_critical)

    p = sub.add_parser('plan', help='the fastest vibration-free spin-up under a deflection '
                                    'limit (CSV, PNG, summary)')
    _add_params(p)
    p.add_argument('--omega', type=_finite, required=True, help='target speed [rad/s]')
    p.add_argument('--from', dest='start', type=_finite, default=0.0,
                   help='starting speed [rad/s] (default 0)')
    p.add_argument('--deflection-limit', type=_finite, default=3e-3,
                   help='largest tip deflection |r| [m] (default 0.003)')
    p.add_argument('--residual', type=_finite, default=2.5e-7,
                   help='largest free whirl left after arrival [m] (default 2.5e-7)')
    p.add_argument('--robust', type=_finite, default=0.0,
                   help='hold the residual for natural frequencies within +- this '
                        'fraction of w0 (default 0)')
    p.add_argument('--max-angular-acceleration', dest='max_acc', type=_finite, default=None,
                   help="bound on |w'| [rad/s^2] (default none)")
    p.add_argument('-o', '--output', type=Path, required=True,
                   help='FILE.csv (the figure goes beside it as FILE.png)')
    p.set_defaults(func=cmd_plan)

    p = sub.add_parser('urdf', help='the URDF of the rod on its disk for the given '
                                    "parameters (robot_state_publisher's robot_description)")
    p.add_argument('--params-file', type=Path, action='append', metavar='FILE',
                   help="the simulator's ROS 2 parameter file(s), applied in order; the "
                        'options below override them')
    p.add_argument('--namespace', default='/',
                   help='namespace of the simulator node whose parameters apply (default /)')
    _add_params(p)
    p.add_argument('--disk-radius', type=_finite, default=None,
                   help="radius of the drawn disk [m] (default: the files' disk_radius, "
                        f'else {DEFAULT_HUB_RADIUS:g})')
    for name, unit in zip(LIMIT_FIELDS, ('rad/s^2', 'rad/s', 'N m', 'm')):
        p.add_argument(f'--{name.replace("_", "-")}', type=_finite, default=None,
                       help=f"the simulator's {name} [{unit}] the description carries "
                            "(default: the files', else the simulator's default)")
    p.add_argument('--ros2-control', action='append', choices=('velocity', 'effort'),
                   metavar='INTERFACE',
                   help="add a <ros2_control> block for topic_based_ros2_control's "
                        "TopicBasedSystem with this command interface on joint 'hub': "
                        'velocity (drive velocity) or effort (drive torque); twice for both')
    p.add_argument('--joint-commands-topic', default='/rotrod/joint_command',
                   help="the block's joint_commands_topic: the simulator's joint_command "
                        '(default /rotrod/joint_command: a simulator in namespace /rotrod)')
    p.add_argument('--joint-states-topic', default='/rotrod/joint_states',
                   help="the block's joint_states_topic: the simulator's joint_states "
                        '(default /rotrod/joint_states)')
    p.add_argument('-o', '--output', type=Path, help='FILE.urdf (default: stdout)')
    p.set_defaults(func=cmd_urdf)

    p = sub.add_parser('demo', help="the paper's spin-up scenario (or the planned one) "
                                    'through the ROS nodes, to a Rerun recording, with a '
                                    'summary')
    p.add_argument('-o', '--output', default='out/rotrod.rrd',
                   help='Rerun recording to write (default out/rotrod.rrd)')
    p.add_argument('--speed', type=_finite, default=None,
                   help='real-time factor of the simulator (default 2, from config/demo.yaml)')
    p.add_argument('--real-time', action='store_true',
                   help='run at wall-clock speed (no /clock)')
    p.add_argument('--offline', action='store_true',
                   help='no ROS: run the scenario in rotrod_core only (CSV in --out)')
    p.add_argument('--profile', choices=('eq26', 'planned'), default='eq26',
                   help="eq26: the paper's Eq. 26 (default); planned: the planned spin-up "
                        'of config/planned.yaml (docs/planner.md)')
    p.add_argument('--out', default='out', help='output directory of --offline (default ./out)')
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser('screenshot', help="the Rerun viewer's own screenshot of a recording, "
                                          'headless (Xvfb and software Vulkan: Debian '
                                          'packages xvfb, mesa-vulkan-drivers)')
    p.add_argument('recording', type=Path, help='the .rrd file (e.g. out/rotrod.rrd)')
    p.add_argument('-o', '--output', type=Path, default=Path('out/dashboard.png'),
                   help='PNG to write (default out/dashboard.png; the README shows '
                        'docs/figures/dashboard.png)')
    p.add_argument('--compact', action='store_true',
                   help='half the size and a 256-colour palette (for docs/figures)')
    p.set_defaults(func=cmd_screenshot)

    p = sub.add_parser('fleet', add_help=False, prefix_chars='\0',
                       help='N simulators in the namespaces rod0.. in real time, from one '
                            'command (python -m rotrod_ros.fleet; --help for its options)')
    p.add_argument('fleet_args', nargs=argparse.REMAINDER,
                   help="python -m rotrod_ros.fleet's arguments")
    p.set_defaults(func=cmd_fleet)

    p = sub.add_parser('reproduce', help="the paper's Figs. 3-10 (PNG), a report of its facts "
                                         'beside measured values, the Eq. 26 Rerun recording')
    p.add_argument('--out', type=Path, default=Path('out/reproduce'),
                   help='output directory (default out/reproduce)')
    p.add_argument('--no-recording', action='store_true',
                   help='skip the Rerun recording (no rerun-sdk needed)')
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser('analyze', help='beyond the paper: Campbell diagrams, critical-speed '
                                       'maps, exact vs Eq. 23 torque coupling')
    p.add_argument('--out', type=Path, default=Path('out/analyze'),
                   help='output directory (default out/analyze)')
    p.add_argument('--only', nargs='+', choices=('campbell', 'critical-map', 'coupling'),
                   help='run only these analyses (default: all)')
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser('sweep', help='many runs over a parameter grid or table, on Dask, to '
                                     'Parquet (docs/sweeps.md)',
                       description='Velocity-drive runs from rest over a grid or a CSV of '
                                   'parameter sets; the per-run summary goes to Parquet as '
                                   'chunks finish. Exit status 1 if some sets have no result '
                                   '(invalid parameters or a failed chunk: listed, and in the '
                                   'status column).')
    _add_params(p)
    _add_profile(p)
    g = p.add_mutually_exclusive_group()
    g.add_argument('--grid', nargs='+', metavar='NAME=SPEC',
                   help='axes of a grid: NAME=START:STOP:COUNT (COUNT values, ends '
                        'included) or NAME=V1,V2,...; NAME a parameter above (e.g. '
                        'eccentricity, damping_ratio)')
    g.add_argument('--sets', type=Path, metavar='FILE.csv',
                   help='parameter sets: a header of parameter names, one row per run')
    p.add_argument('--t-end', type=_finite, default=40.0, help='duration [s] (default 40)')
    p.add_argument('--tolerance', type=_finite, default=1e-10,
                   help='accuracy of u, v along each run [m] (default 1e-10)')
    p.add_argument('--scheduler', metavar='ADDRESS', default=None,
                   help='a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: a '
                        'local cluster on 127.0.0.1, started and stopped here)')
    p.add_argument('--workers', type=_positive_int, default=None,
                   help='worker processes of the local cluster (default: one per core)')
    p.add_argument('--chunk-size', type=_positive_int, default=1024,
                   help='parameter sets per task (default 1024)')
    p.add_argument('-o', '--output', type=Path, required=True, help='FILE.parquet')
    p.set_defaults(func=cmd_sweep, argv=None)
    return parser


def main(argv=None) -> int:
    """Entry point of the ``rotrod`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if argv is not None and hasattr(args, 'argv'):
        args.argv = list(argv)
    try:
        return args.func(args)
    except (ValueError, OSError) as exc:
        print(f'rotrod {args.command}: error: {exc}', file=sys.stderr)
        return 2


if __name__ == '__main__':
    sys.exit(main())
