"""Structured results of the benchmarks: one :class:`Row` per measured quantity.

Every bench exposes a function returning a list of rows (``bench_core.measure``,
``bench_realtime.measure``, ``bench_estimator.measure``); ``--json FILE`` writes them
with :func:`dump`, and ``run_all.py`` reads them back with :func:`load`. Whether a
target is met and every comparison ratio are computed here from the measured numbers,
never given by hand.
"""

from __future__ import annotations

import json
import math
import operator
import os
import platform
import re
from dataclasses import asdict, dataclass
from datetime import datetime, timezone
from pathlib import Path

OPS = {'<=': operator.le, '>=': operator.ge}


def _number(x, what: str) -> float:
    """``x`` as a float; ValueError if it is missing (None, NaN, not a number)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise ValueError(f'{what}: expected a number, got {x!r}')
    if not math.isfinite(x):
        raise ValueError(f'{what}: {x} (not a finite number)')
    return float(x)


def short(x: float) -> str:
    """``x`` in %g form without exponent padding (1e-9, not 1e-09)."""
    return re.sub(r'e([+-])0*(\d)', lambda m: 'e' + m[1].replace('+', '') + m[2], f'{x:g}')


@dataclass(frozen=True)
class Target:
    """A bound from the issues: ``op limit unit`` on the row's value (or its ratio)."""

    op: str
    limit: float
    text: str = ''      # how to print it, when not 'op limit unit' (e.g. '<= 2 periods')
    on: str = 'value'   # 'value', or 'ratio' (the ratio of the row's first comparison)

    def describe(self, unit: str) -> str:
        return self.text or f'{self.op} {short(self.limit)} {unit}'.rstrip()


@dataclass(frozen=True)
class Comparison:
    """The same quantity for a baseline, measured in the same run."""

    label: str          # the baseline, e.g. 'solve_ivp DOP853 rtol 1e-9'
    baseline: float     # its value, in the row's unit (inf/NaN allowed only with a note)
    note: str = ''      # e.g. '74 of 200 NaN'


@dataclass(frozen=True)
class Row:
    """One measured quantity.

    ``better`` says which direction is an improvement ('lower' or 'higher'); a
    comparison's ratio is then how many times better the value is than the baseline
    (baseline / value, or value / baseline), > 1 meaning better.
    """

    bench: str
    name: str
    value: float
    unit: str
    target: Target | None = None
    better: str = 'lower'
    comparisons: tuple = ()
    note: str = ''      # context printed beside the value (median, p99, counts)
    fmt: str = '.3g'

    def __post_init__(self):
        object.__setattr__(self, 'comparisons', tuple(
            c if isinstance(c, Comparison) else Comparison(**c) for c in self.comparisons))
        if isinstance(self.target, dict):
            object.__setattr__(self, 'target', Target(**self.target))

    def ratio(self, comparison: Comparison) -> float | None:
        """How many times better the value is than the baseline (None if undefined)."""
        a, b = self.value, comparison.baseline
        if not (math.isfinite(a) and math.isfinite(b)) or a == 0 or b == 0:
            return None
        return b / a if self.better == 'lower' else a / b

    @property
    def met(self) -> bool | None:
        """Whether the target is met (None when the row has no target)."""
        if self.target is None:
            return None
        if self.target.on == 'ratio':
            r = self.ratio(self.comparisons[0]) if self.comparisons else None
            return r is not None and OPS[self.target.op](r, self.target.limit)
        return OPS[self.target.op](self.value, self.target.limit)

    def validate(self) -> None:
        """Raise ValueError if anything the table shows is missing or inconsistent."""
        where = f'{self.bench}: {self.name!r}'
        for text, what in ((self.bench, 'bench'), (self.name, 'name'), (self.unit, 'unit')):
            if not isinstance(text, str) or not text.strip():
                raise ValueError(f'{where}: missing {what}')
        _number(self.value, f'{where}: value')
        if self.better not in ('lower', 'higher'):
            raise ValueError(f'{where}: better must be lower or higher, not {self.better!r}')
        if self.target is not None:
            if self.target.op not in OPS:
                raise ValueError(f'{where}: target operator {self.target.op!r}')
            _number(self.target.limit, f'{where}: target limit')
            if self.target.on not in ('value', 'ratio'):
                raise ValueError(f'{where}: target on {self.target.on!r}')
            if self.target.on == 'ratio' and (
                    not self.comparisons or self.ratio(self.comparisons[0]) is None):
                raise ValueError(f'{where}: target on a ratio that was not measured')
        for c in self.comparisons:
            if not c.label.strip():
                raise ValueError(f'{where}: comparison without a label')
            b = c.baseline
            if isinstance(b, bool) or not isinstance(b, (int, float)):
                raise ValueError(f'{where}: comparison {c.label!r} has no value ({b!r})')
            if not math.isfinite(b) and not c.note.strip():
                raise ValueError(f'{where}: comparison {c.label!r} is {b} without a note '
                                 'saying why')

    # -- text ---------------------------------------------------------------------------

    def format_value(self, x: float | None = None) -> str:
        x = self.value if x is None else x
        if not math.isfinite(x):
            return 'NaN' if math.isnan(x) else ('inf' if x > 0 else '-inf')
        return f'{format(x, self.fmt)} {self.unit}'.rstrip()

    def value_cell(self) -> str:
        return self.format_value() + (f' ({self.note})' if self.note else '')

    def target_cell(self) -> str:
        return self.target.describe(self.unit) if self.target else ''

    def met_cell(self) -> str:
        return {None: '', True: 'yes', False: '**NO**'}[self.met]

    def comparison_cell(self) -> str:
        parts = []
        for c in self.comparisons:
            text = f'{c.label}: {self.format_value(c.baseline)}'
            if c.note:
                text += f' ({c.note})'
            r = self.ratio(c)
            if r is not None:
                text += f', ratio {r:.3g}'
            parts.append(text)
        return '; '.join(parts)


def to_dict(row: Row) -> dict:
    return asdict(row)


def from_dict(data: dict) -> Row:
    return Row(**data)


def dump(path: Path, rows: list, **extra) -> None:
    """Write rows (and any extra JSON-able results) as JSON."""
    for r in rows:
        r.validate()
    Path(path).write_text(json.dumps({'rows': [to_dict(r) for r in rows], **extra},
                                     indent=1, default=_json_default, allow_nan=True))


def load(path: Path) -> list:
    """The rows written by :func:`dump`."""
    return [from_dict(d) for d in json.loads(Path(path).read_text())['rows']]


def _json_default(x):
    if hasattr(x, 'item'):      # numpy scalars
        return x.item()
    raise TypeError(f'not JSON-able: {x!r}')


COLUMNS = ('measurement', 'value', 'target', 'met', 'compared in the same run')


def markdown(rows: list, *, bench_column: bool = True) -> str:
    """A Markdown table of rows (each validated first: ValueError if a value is missing)."""
    columns = (('bench',) if bench_column else ()) + COLUMNS
    lines = ['| ' + ' | '.join(columns) + ' |', '|---' * len(columns) + '|']
    for r in rows:
        r.validate()
        cells = [r.bench] if bench_column else []
        cells += [r.name, r.value_cell(), r.target_cell(), r.met_cell(), r.comparison_cell()]
        lines.append('| ' + ' | '.join(c.replace('|', '\\|') for c in cells) + ' |')
    return '\n'.join(lines)


RATIO_NOTE = ('ratio: how many times better the measured value is than the baseline '
              '(baseline / value where lower is better, value / baseline where higher is '
              'better); below 1 the baseline is better.')


def host(load: tuple | None = None) -> str:
    """This machine and interpreter and the time now (UTC), for a bench's header.

    ``load``: the load averages to show (taken when the caller chose), with the CPUs.
    """
    cpus = '' if load is None else (f', {os.cpu_count()} CPUs, load '
                                    + ', '.join(f'{x:.1f}' for x in load))
    return (f'{platform.node()} ({platform.machine()}{cpus}, '
            f'{platform.python_implementation()} {platform.python_version()}), '
            f'{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC')


def report(rows: list, json_path: Path | None = None, *, title: str = '',
           stamp: str = '', preface: str = '') -> int:
    """A standalone bench's output: ``title on stamp``, ``preface``, the table, and the rows
    as JSON if asked. Returns the exit status: 0 when no target is missed, else 1."""
    if title:
        print(f'{title} on {stamp}\n' if stamp else f'{title}\n')
    if preface:
        print(preface + '\n')
    print(markdown(rows, bench_column=False))
    if json_path:
        dump(json_path, rows, **({'stamp': stamp} if stamp else {}))
    return 0 if all(r.met is not False for r in rows) else 1
