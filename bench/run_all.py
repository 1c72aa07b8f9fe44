"""Run every benchmark, print one Markdown table, and write it into docs/performance.md.

    .venv/bin/python bench/run_all.py                 # full run (60 s real-time part);
                                                      # rewrites docs/performance.md's table
    .venv/bin/python bench/run_all.py --quick         # smoke run (5 s); the page untouched
    .venv/bin/python bench/run_all.py --quick --write # ... and written anyway
    .venv/bin/python bench/run_all.py --no-write      # full run, docs/performance.md untouched

Runs bench_core.py, bench_sweep.py, bench_estimator.py, bench_planner.py,
bench_identify.py, bench_realtime.py and bench_fleet.py one after the other, each as its
own process writing its rows as JSON (bench/results.py); their own tables go to stderr.
The combined table, stamped with the date, the machine, the load average at start, the
code measured and this command, goes to stdout and replaces what lies between ``<!--
bench:begin -->`` and ``<!-- bench:end -->`` in docs/performance.md; nothing outside the
markers is touched. A bench that fails, or a row with a missing value, stops the run
before docs/performance.md is written. Exit status: 0 when every target is met, 1 when
some target is not (docs/performance.md is still written), 2 on an error.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / 'bench'
sys.path.insert(0, str(BENCH))

import results  # noqa: E402  (bench/results.py)

BEGIN = '<!-- bench:begin -->'
END = '<!-- bench:end -->'
PACKAGES = ('numpy', 'scipy', 'rerun-sdk', 'rclpy', 'dask', 'distributed', 'pyarrow')
STAMP_KEYS = ('date', 'command', 'run time', 'machine', 'OS', 'Python', 'packages',
              'load average at start', 'code')


# -- the machine ---------------------------------------------------------------------------

def cpu_model() -> str:
    try:
        for line in Path('/proc/cpuinfo').read_text().splitlines():
            if line.startswith('model name'):
                return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def ram() -> str:
    try:
        for line in Path('/proc/meminfo').read_text().splitlines():
            if line.startswith('MemTotal:'):
                return f'{int(line.split()[1]) / 2**20:.1f} GiB RAM'
    except (OSError, ValueError, IndexError):
        pass
    return 'RAM unknown'


def os_name() -> str:
    try:
        for line in Path('/etc/os-release').read_text().splitlines():
            if line.startswith('PRETTY_NAME='):
                return (f"{line.split('=', 1)[1].strip().strip(chr(34))}, "
                        f'{platform.system()} {platform.release()}')
    except OSError:
        pass
    return platform.platform()


def package_versions() -> str:
    out = []
    for name in PACKAGES:
        try:
            out.append(f'{name} {importlib.metadata.version(name)}')
        except importlib.metadata.PackageNotFoundError:
            out.append(f'{name} not installed')
    return ', '.join(out)


def code_version(page: Path | None = None) -> str:
    """The commit measured, and the files changed since (the page we write aside)."""
    try:
        git = ['git', '-C', str(ROOT)]
        head = subprocess.run([*git, 'rev-parse', '--short', 'HEAD'], capture_output=True,
                              text=True, check=True).stdout.strip()
        branch = subprocess.run([*git, 'rev-parse', '--abbrev-ref', 'HEAD'],
                                capture_output=True, text=True, check=True).stdout.strip()
        status = subprocess.run([*git, 'status', '--porcelain', '--untracked-files=no'],
                                capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return 'not a git checkout'
    skip = (page or ROOT / 'docs' / 'performance.md').resolve()
    changed = [line[3:] for line in status.splitlines()
               if (ROOT / line[3:]).resolve() != skip]
    return (f'commit {head} ({branch})'
            + (f', with uncommitted changes to {", ".join(changed)}' if changed else ''))


def machine_stamp(command: str, load: tuple, page: Path | None = None) -> dict:
    """What the block is stamped with (``run time`` is filled in at the end)."""
    return {
        'date': f'{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC',
        'command': command,
        'run time': '',
        'machine': f'{cpu_model()}, {os.cpu_count()} cores, {ram()}',
        'OS': os_name(),
        'Python': f'{platform.python_implementation()} {platform.python_version()}',
        'packages': package_versions(),
        'load average at start': ', '.join(f'{x:.2f}' for x in load) + ' (1, 5, 15 min)',
        'code': code_version(page),
    }


def cpu_jiffies() -> tuple:
    """(busy, steal) CPU seconds of the whole machine since boot, from /proc/stat."""
    try:
        fields = [int(x) for x in Path('/proc/stat').read_text().split('\n', 1)[0].split()[1:]]
    except (OSError, ValueError):
        return (float('nan'), float('nan'))
    user, nice, system, _idle, _iowait, irq, softirq, steal = (fields + [0] * 8)[:8]
    tick = os.sysconf('SC_CLK_TCK')
    return ((user + nice + system + irq + softirq) / tick, steal / tick)


class OtherLoad:
    """CPU used on this machine, during a span, by anything but this process's children.

    Busy time of all CPUs (/proc/stat) minus the CPU time of the children this
    process waited for (the bench and, through it, its nodes and workers); the
    remainder is other processes and the kernel, in % of one core.
    """

    def __enter__(self):
        self.t0, (self.busy0, self.steal0) = time.monotonic(), cpu_jiffies()
        t = os.times()
        self.own0 = t.children_user + t.children_system
        return self

    def __exit__(self, *exc):
        busy, steal = cpu_jiffies()
        t = os.times()
        wall = time.monotonic() - self.t0
        own = t.children_user + t.children_system - self.own0
        self.other = 100 * max(0.0, busy - self.busy0 - own) / wall
        self.steal = 100 * (steal - self.steal0) / wall
        return False

    def describe(self) -> str:
        return f'{self.other:.0f} % (steal {self.steal:.0f} %)'


# -- the table -----------------------------------------------------------------------------

def build_table(rows: list) -> str:
    """The combined Markdown table; ValueError if there is no row or a value is missing."""
    if not rows:
        raise ValueError('no benchmark rows')
    return results.markdown(rows)


def build_block(rows: list, stamp: dict, notes: tuple = ()) -> str:
    """The text that goes between the markers (the markers not included)."""
    missing = [k for k in STAMP_KEYS if not str(stamp.get(k, '')).strip()]
    if missing:
        raise ValueError(f'stamp without {", ".join(missing)}')
    table = build_table(rows)
    failed = [r for r in rows if r.met is False]
    with_target = [r for r in rows if r.met is not None]
    lines = ['<!-- generated by bench/run_all.py: do not edit by hand -->', '']
    lines += [f'- {k}: `{v}`' if k == 'command' else f'- {k}: {v}'
              for k, v in stamp.items()]
    lines += [f'- {n}' for n in notes]
    lines += ['', table, '', results.RATIO_NOTE, '']
    if failed:
        lines.append(f'Targets not met: {len(failed)} of {len(with_target)}: '
                     + '; '.join(f'{r.bench}: {r.name}: {r.format_value()} '
                                 f'(target {r.target_cell()})' for r in failed) + '.')
    else:
        lines.append(f'All {len(with_target)} targets met.')
    return '\n'.join(lines)


def rewrite(text: str, block: str) -> str:
    """``text`` with what lies between the markers replaced by ``block``.

    ValueError unless each marker occurs exactly once, on a line of its own, begin
    before end. Nothing outside the markers changes.
    """
    for marker in (BEGIN, END):
        count = text.count(marker)
        if count != 1:
            raise ValueError(f'{marker} occurs {count} times (expected once)')
        at = text.index(marker)
        line_start = text.rfind('\n', 0, at) + 1
        line_end = text.find('\n', at)
        line = text[line_start:len(text) if line_end < 0 else line_end]
        if line.strip() != marker:
            raise ValueError(f'{marker} is not on a line of its own')
    begin, end = text.index(BEGIN), text.index(END)
    if end < begin:
        raise ValueError(f'{END} comes before {BEGIN}')
    head = text[:begin + len(BEGIN)]
    tail = text[end:]
    return head + '\n' + block.strip('\n') + '\n' + tail


def rewrite_file(path: Path, block: str) -> None:
    """Rewrite the block in the file at ``path`` (atomically)."""
    path = Path(path)
    new = rewrite(path.read_text(), block)
    with tempfile.NamedTemporaryFile('w', dir=path.parent, prefix=f'.{path.name}.',
                                     delete=False) as f:
        f.write(new)
    os.chmod(f.name, path.stat().st_mode & 0o777)
    os.replace(f.name, path)


# -- running the benches -------------------------------------------------------------------

def run_bench(script: str, args: list, json_path: Path, timeout: float) -> list:
    """Run one bench (its table to stderr); return its rows."""
    cmd = [sys.executable, str(BENCH / script), *args, '--json', str(json_path)]
    print(f'run_all: {shlex.join(cmd)}', file=sys.stderr, flush=True)
    t0 = time.monotonic()
    proc = subprocess.run(cmd, stdout=sys.stderr, timeout=timeout, check=False)
    print(f'run_all: {script} took {time.monotonic() - t0:.0f} s (exit status '
          f'{proc.returncode})', file=sys.stderr, flush=True)
    if not json_path.is_file():
        raise RuntimeError(f'{script} wrote no results (exit status {proc.returncode})')
    # the core and estimator benches exit with 1 when a target is not met: still results
    if proc.returncode not in (0, 1):
        raise RuntimeError(f'{script} failed (exit status {proc.returncode})')
    return results.load(json_path)


def format_duration(seconds: float) -> str:
    m, s = divmod(round(seconds), 60)
    return f'{m} min {s:02d} s' if m else f'{s} s'


def main(argv: list | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--quick', action='store_true',
                    help='smoke run: 1000-system batch, 5 s real-time run; the page is not '
                         'written unless --write')
    ap.add_argument('--duration', type=float,
                    help='real-time run, s (default 60, or 5 with --quick)')
    write = ap.add_mutually_exclusive_group()
    write.add_argument('--write', action='store_true', default=None,
                       help='rewrite docs/performance.md (the default for a full run)')
    write.add_argument('--no-write', dest='write', action='store_false',
                       help='do not rewrite docs/performance.md')
    ap.add_argument('--page', type=Path, default=ROOT / 'docs' / 'performance.md',
                    help='the page whose generated block is rewritten')
    ap.add_argument('--json', type=Path, help='also write all rows and the stamp as JSON')
    args = ap.parse_args(argv)
    duration = args.duration if args.duration is not None else (5.0 if args.quick else 60.0)
    do_write = args.write if args.write is not None else not args.quick

    t_start = time.monotonic()
    stamp = machine_stamp(f'.venv/bin/python {shlex.join(["bench/run_all.py", *argv])}',
                          os.getloadavg(), args.page)
    if do_write:
        rewrite(args.page.read_text(), '')      # markers checked before an hour's work
    rows, notes, loads = [], [], []
    benches = [('bench_core.py', ['--quick'] if args.quick else [], 900),
               ('bench_sweep.py', ['--quick'] if args.quick else [], 900),
               ('bench_estimator.py', [], 900),
               ('bench_planner.py', [], 900),
               ('bench_identify.py', ['--seeds', '10', '--eq26-seeds', '3']
                if args.quick else [], 1800),
               ('bench_realtime.py', ['--duration', f'{duration:g}'], 4 * duration + 600),
               ('bench_fleet.py', ['--duration', f'{duration:g}',
                                   *(['--rods', '3', '--large-rods', '10']
                                     if args.quick else [])],
                10 * duration + 900)]
    with tempfile.TemporaryDirectory(prefix='rotrod-bench-') as tmp:
        tmp = Path(tmp)
        for script, bench_args, timeout in benches:
            load1 = os.getloadavg()[0]
            with OtherLoad() as other:
                rows += run_bench(script, bench_args, tmp / f'{script}.json', timeout)
            loads.append(f'{script}: load {load1:.2f} at start, {other.describe()}')
        rt = json.loads((tmp / 'bench_realtime.py.json').read_text())
        notes.append(f"real-time bench: {duration:g} s run; simulator node run from "
                     f"`{Path(rt['simulator_code']).parent}`, {rt['rmw']}, DDS isolation "
                     f"{rt['isolation']}")
    notes.append('per bench, the 1-min load average as it started and the CPU used by '
                 'other processes and the kernel while it ran, in % of one core: '
                 + '; '.join(loads) + '; load average at the end: '
                 + ', '.join(f'{x:.2f}' for x in os.getloadavg()))
    if args.quick:
        notes.append('quick run (`--quick`): shorter runs; the batch target is not judged')
    stamp['run time'] = format_duration(time.monotonic() - t_start)
    block = build_block(rows, stamp, tuple(notes))
    print(block)
    if args.json:
        args.json.write_text(json.dumps({'stamp': stamp, 'notes': notes,
                                         'rows': [results.to_dict(r) for r in rows]},
                                        indent=1))
    if do_write:
        rewrite_file(args.page, block)
        print(f'run_all: rewrote the block in {args.page}', file=sys.stderr)
    return 1 if any(r.met is False for r in rows) else 0


if __name__ == '__main__':
    try:
        sys.exit(main())
    except (RuntimeError, ValueError, OSError, subprocess.TimeoutExpired) as exc:
        print(f'run_all: {exc}', file=sys.stderr)
        sys.exit(2)
