"""Parameter sweeps: a grid or a table of parameter sets, run in chunks on Dask.

A sweep is a table of parameter sets (columns named after the numeric
:class:`~rotrod_core.model.params.RodParams` fields, one row per run) over a base
RodParams, all under one angular-velocity profile (velocity drive). Rows are cut into
chunks; every chunk is validated here, then runs as one task
(:func:`rotrod_core.offline.batch.velocity_chunk`) on a ``dask.distributed`` client,
or in this process without one. Each finished chunk is handed to ``on_chunk`` at once,
in the order the chunks finish, so a writer can store it (``docs/sweeps.md``).

Failure semantics: a worker that dies takes its tasks with it and the scheduler runs
them again elsewhere (Dask's ``allowed-failures``, 3 by default); the sweep goes on.
Rows whose parameters are invalid never run: they come back with ``status`` = the
reason and NaN results, and the other rows of their chunk run. A chunk whose task
fails (its run became non-finite, or it failed on the workers too often) comes back
with ``status`` = the error for each of its rows. Nothing else stops the sweep.

Dask is imported only here, inside the functions that need it.
"""

from __future__ import annotations

import csv
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

import rotrod_core.offline.batch_velocity as velocity
from rotrod_core.command.profiles import Profile
from rotrod_core.model.params import FIELD_UNITS, RodParams
from rotrod_core.offline.batch import (
    BLOCK,
    DEFAULT_TOLERANCE,
    flat_coefficients,
    velocity_chunk,
)

if TYPE_CHECKING:
    from distributed import Client, LocalCluster

MAX_RUNS = 10_000_000
"""Largest number of parameter sets a sweep accepts."""

RESULT_UNITS = {
    'peak_deflection': 'm', 'peak_time': 's', 'final_u': 'm', 'final_v': 'm',
    'final_du': 'm/s', 'final_dv': 'm/s', 'final_theta': 'rad', 'final_omega': 'rad/s',
}
"""The per-run summary of a sweep and its units."""


def column_name(name: str, unit: str) -> str:
    """``name`` with its unit as a suffix: eccentricity_m, hub_inertia_kg_m2, final_du_m_s."""
    if unit in ('', '-', '1'):          # dimensionless (RodParams says '1')
        return name
    return name + '_' + unit.replace('^', '').replace('/', '_').replace(' ', '_')


PARAMETER_COLUMNS = {name: column_name(name, unit) for name, unit in FIELD_UNITS.items()}
RESULT_COLUMNS = {name: column_name(name, unit) for name, unit in RESULT_UNITS.items()}


# -- the table of parameter sets -------------------------------------------------------------

def _parameter(name: str) -> str:
    """The RodParams field for a column or grid name (with or without its unit suffix)."""
    for field_name, column in PARAMETER_COLUMNS.items():
        if name in (field_name, column):
            return field_name
    raise ValueError(f'unknown parameter {name!r}; expected one of '
                     f'{", ".join(FIELD_UNITS)} (optionally with the unit suffix, '
                     f'e.g. {PARAMETER_COLUMNS["eccentricity"]})')


def _number(text: str, where: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f'{where}: not a number: {text!r}') from None
    if not math.isfinite(x):
        raise ValueError(f'{where}: not a finite number: {text!r}')
    return x


def parse_axis(spec: str) -> tuple[str, np.ndarray]:
    """One grid axis ``NAME=START:STOP:COUNT`` or ``NAME=V1,V2,...`` -> (field, values).

    START:STOP:COUNT is COUNT evenly spaced values from START to STOP, both included
    (numpy.linspace); a list gives its values in order; a single value is one point.
    """
    name, sep, values = spec.partition('=')
    if not sep or not name.strip() or not values.strip():
        raise ValueError(f'grid axis must read NAME=START:STOP:COUNT or NAME=V1,V2,..., '
                         f'got {spec!r}')
    field_name = _parameter(name.strip())
    where = f'grid axis {spec!r}'
    if ':' in values:
        parts = values.split(':')
        if len(parts) != 3:
            raise ValueError(f'{where}: a range reads START:STOP:COUNT')
        start, stop = _number(parts[0], where), _number(parts[1], where)
        count = _number(parts[2], where)
        if count != int(count) or count < 1:
            raise ValueError(f'{where}: COUNT must be a whole number >= 1, got {parts[2]!r}')
        if count > MAX_RUNS:
            raise ValueError(f'{where}: COUNT {int(count)} exceeds {MAX_RUNS}')
        return field_name, np.linspace(start, stop, int(count))
    return field_name, np.array([_number(v, where) for v in values.split(',')])


def grid_table(specs) -> dict[str, np.ndarray]:
    """The Cartesian product of grid axes: {field: values of every run}, first axis slowest."""
    axes = [parse_axis(s) for s in specs]
    if not axes:
        raise ValueError('a grid needs at least one axis NAME=...')
    names = [a[0] for a in axes]
    if len(set(names)) != len(names):
        raise ValueError(f'a parameter appears twice in the grid: {names}')
    total = math.prod(len(a[1]) for a in axes)
    if total > MAX_RUNS:
        raise ValueError(f'the grid has {total} parameter sets (> {MAX_RUNS})')
    mesh = np.meshgrid(*(a[1] for a in axes), indexing='ij')
    return {name: m.ravel() for name, m in zip(names, mesh)}


def read_table(path) -> dict[str, np.ndarray]:
    """Parameter sets from a CSV file: a header of parameter names, one row per run."""
    path = Path(path)
    with path.open(newline='') as f:
        rows = list(csv.reader(f))
    rows = [r for r in rows if any(c.strip() for c in r)]
    if len(rows) < 2:
        raise ValueError(f'{path}: needs a header row and at least one parameter set')
    names = [_parameter(c.strip()) for c in rows[0]]
    if len(set(names)) != len(names):
        raise ValueError(f'{path}: a parameter appears twice in the header: {names}')
    if len(rows) - 1 > MAX_RUNS:
        raise ValueError(f'{path}: {len(rows) - 1} parameter sets (> {MAX_RUNS})')
    values = np.empty((len(rows) - 1, len(names)))
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(names):
            raise ValueError(f'{path}, line {i}: {len(row)} values for {len(names)} columns')
        values[i - 2] = [_number(c.strip(), f'{path}, line {i}') for c in row]
    return {name: values[:, k] for k, name in enumerate(names)}


def table_size(table: dict) -> int:
    """Number of parameter sets (rows) of a table; ValueError if the columns disagree."""
    sizes = {len(np.atleast_1d(v)) for v in table.values()}
    if len(sizes) != 1:
        raise ValueError(f'the parameter columns have different lengths: {sorted(sizes)}')
    return sizes.pop()


# -- chunks ------------------------------------------------------------------------------------

@dataclass
class ChunkResult:
    """The rows of one chunk, finished: parameters, results and status per row.

    Attributes:
        index: the rows' positions in the sweep's table.
        parameters: {RodParams field: values} of these rows (every numeric field).
        results: {result name (:data:`RESULT_UNITS`): values}, NaN where not run.
        status: 'ok', or why the row has no result.
    """

    index: np.ndarray
    parameters: dict[str, np.ndarray]
    results: dict[str, np.ndarray]
    status: list[str]

    def columns(self) -> dict[str, np.ndarray | list[str]]:
        """The rows as columns named with their units (run_index first, status last)."""
        out: dict[str, np.ndarray | list[str]] = {'run_index': self.index}
        out.update({PARAMETER_COLUMNS[k]: v for k, v in self.parameters.items()})
        out.update({RESULT_COLUMNS[k]: v for k, v in self.results.items()})
        out['status'] = self.status
        return out


@dataclass
class SweepSummary:
    """What a sweep did: counts, the rows without results (index, parameters, reason)."""

    runs: int
    ok: int = 0
    problems: list = field(default_factory=list)
    chunks: int = 0
    elapsed: float = 0.0


def _parameters_of(params: RodParams, n: int) -> dict:
    return {name: np.broadcast_to(np.asarray(value, float), params.shape).ravel()
            if params.shape else np.full(n, float(value))
            for name, value in params._numeric().items()}


def _validate(base: RodParams, table: dict, rows: np.ndarray):
    """(RodParams of the valid rows or None, their positions in ``rows``, {row: reason})."""
    changes = {k: np.asarray(v, float)[rows] for k, v in table.items()}
    try:
        return base.replace(**changes), np.arange(len(rows)), {}
    except ValueError:
        pass
    reasons, valid = {}, []
    for pos, row in enumerate(rows):
        try:
            base.replace(**{k: float(v[pos]) for k, v in changes.items()})
            valid.append(pos)
        except ValueError as exc:
            reasons[int(row)] = str(exc)
    good = np.array(valid, dtype=int)
    if good.size == 0:
        return None, good, reasons
    return base.replace(**{k: v[good] for k, v in changes.items()}), good, reasons


def _empty_results(n: int) -> dict:
    return {k: np.full(n, np.nan) for k in RESULT_UNITS}


def _results_of(out: dict, theta0: float, theta_end: float, omega_end: float) -> dict:
    n = len(out['peak'])
    return {'peak_deflection': out['peak'], 'peak_time': out['peak_time'],
            'final_u': out['z'].real, 'final_v': out['z'].imag, 'final_du': out['p'].real,
            'final_dv': out['p'].imag, 'final_theta': np.full(n, theta0 + theta_end),
            'final_omega': np.full(n, omega_end)}


def run_sweep(table: dict, profile: Profile, t_end: float, *, base: RodParams | None = None,
              tolerance: float = DEFAULT_TOLERANCE, client=None, chunk_size: int = BLOCK,
              on_chunk: Callable[[ChunkResult], None] | None = None) -> SweepSummary:
    """Run every parameter set of ``table`` (velocity drive, from rest) in chunks.

    Args:
        table: {RodParams field: values}, equal lengths (:func:`grid_table`,
            :func:`read_table`).
        profile: the angular-velocity profile of every run.
        t_end: duration of each run, s.
        base: the parameters not in the table (default: Table 1).
        tolerance: accuracy of u and v along each run, m (see ``simulate_batch``).
        client: a ``dask.distributed.Client``; None runs the chunks in this process.
        chunk_size: parameter sets per task.
        on_chunk: called with each :class:`ChunkResult` as it finishes (any order).

    Returns:
        :class:`SweepSummary`. Chunk results go to ``on_chunk`` only.
    """
    if not isinstance(profile, Profile):
        raise ValueError(f'profile must be a rotrod_core Profile, got {profile!r}')
    base = RodParams() if base is None else base
    if base.is_batch:
        raise ValueError('the base parameters must describe one system')
    table = {_parameter(k): np.atleast_1d(np.asarray(v, float)) for k, v in table.items()}
    n = table_size(table)
    if isinstance(chunk_size, bool) or int(chunk_size) != chunk_size or chunk_size < 1:
        raise ValueError(f'chunk_size must be a positive integer, got {chunk_size!r}')
    chunk_size = int(chunk_size)
    started = time.perf_counter()
    summary = SweepSummary(runs=n)
    emit = on_chunk or (lambda chunk: None)
    # validate every chunk, and plan the grids once for all valid sets
    chunks = []
    for lo in range(0, n, chunk_size):
        rows = np.arange(lo, min(lo + chunk_size, n))
        params, good, reasons = _validate(base, table, rows)
        chunks.append((rows, params, good, reasons))
    valid = [c for c in chunks if c[1] is not None]
    the_plan = None
    if valid:
        co_all = flat_coefficients(_concatenate([c[1] for c in valid], base))
        the_plan = velocity.plan(co_all, profile, t_end, tolerance)
    theta_end, omega_end = float(profile.angle(t_end)), float(profile.omega(t_end))

    def chunk_result(rows, params, good, reasons, out=None, error=None):
        given = base._numeric()
        full = {k: np.full(len(rows), float(given.get(k, np.nan))) for k in FIELD_UNITS}
        if params is not None:
            for k, v in _parameters_of(params, len(good)).items():
                full[k][good] = v
        for k, v in table.items():          # the given values, also for invalid rows
            full[k] = v[rows]
        results = _empty_results(len(rows))
        status = ['ok'] * len(rows)
        if out is not None:
            for k, v in _results_of(out, 0.0, theta_end, omega_end).items():
                results[k][good] = v
        if error is not None:
            for pos in good:
                status[pos] = f'failed: {error}'
        for row, reason in reasons.items():
            status[int(row - rows[0])] = f'invalid: {reason}'
        return ChunkResult(rows, full, results, status)

    def finish(result: ChunkResult):
        summary.chunks += 1
        for i, s in zip(result.index, result.status):
            if s == 'ok':
                summary.ok += 1
            else:
                summary.problems.append((int(i), {k: float(v[int(i)])
                                                  for k, v in table.items()}, s))
        emit(result)

    pending = []
    for rows, params, good, reasons in chunks:
        if params is None:
            finish(chunk_result(rows, None, good, reasons))
            continue
        co = flat_coefficients(params)
        zeros = np.zeros(len(good), complex)
        job = (co, profile, the_plan, zeros, zeros, 1)
        if client is None:
            try:
                out = velocity_chunk(*job)
                finish(chunk_result(rows, params, good, reasons, out=out))
            except (ValueError, FloatingPointError) as exc:
                finish(chunk_result(rows, params, good, reasons, error=exc))
        else:
            future = client.submit(velocity_chunk, *job, pure=False)
            pending.append((future, (rows, params, good, reasons)))
    if pending:
        from distributed import as_completed
        context = {f.key: c for f, c in pending}
        for future in as_completed([f for f, _ in pending]):
            rows, params, good, reasons = context[future.key]
            try:
                out = future.result()
            except Exception as exc:  # noqa: BLE001 - any task failure is reported per row
                finish(chunk_result(rows, params, good, reasons,
                                    error=f'{type(exc).__name__}: {exc}'))
            else:
                finish(chunk_result(rows, params, good, reasons, out=out))
            future.release()
    summary.elapsed = time.perf_counter() - started
    summary.problems.sort(key=lambda p: p[0])
    return summary


def _concatenate(batches: list, base: RodParams) -> RodParams:
    """One RodParams holding every system of ``batches`` (flat)."""
    fields = {}
    for name in base._numeric():
        fields[name] = np.concatenate([
            np.broadcast_to(np.asarray(getattr(b, name), float), b.shape).ravel()
            if b.shape else np.atleast_1d(float(getattr(b, name))) for b in batches])
    return base.replace(**fields)


# -- the Dask client -------------------------------------------------------------------------

NANNY_MALLOC_KEY = 'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_'
"""The Dask setting that the local cluster unsets (see :class:`SweepClient`)."""


class SweepClient:
    """A ``dask.distributed.Client``: to a scheduler's address, or to a local cluster.

    ``with SweepClient(None, workers=2) as client:`` starts an in-process LocalCluster
    of ``workers`` worker processes (one thread each) that listen on 127.0.0.1 only,
    with no dashboard; ``SweepClient('tcp://host:8786')`` connects to a running
    scheduler (``docs/sweeps.md``). Both close on leaving the block.
    """

    def __init__(self, scheduler: str | None = None, workers: int | None = None,
                 processes: bool = True):
        self.scheduler, self.processes = scheduler, processes
        self.workers = workers if workers is not None else (os.cpu_count() or 1)
        if isinstance(self.workers, bool) or int(self.workers) != self.workers \
                or self.workers < 1:
            raise ValueError(f'workers must be a positive integer, got {workers!r}')
        self.cluster: LocalCluster | None = None
        self.client: Client | None = None

    def __enter__(self):
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ValueError('sweeps need dask.distributed: pip install "dask[distributed]" '
                             '(pinned in constraints.txt)') from None
        if self.scheduler:
            self.client = Client(self.scheduler, timeout='20s')
            return self.client
        import dask
        options: dict[str, Any] = {'n_workers': int(self.workers), 'threads_per_worker': 1,
                   'processes': self.processes, 'dashboard_address': None}
        if self.processes:
            options['host'] = '127.0.0.1'
        # Dask's nannies start workers with MALLOC_TRIM_THRESHOLD_=65536, which makes
        # glibc map and fault in every array over 128 KiB afresh: the batch's blocks
        # run 2-5x slower. The local cluster's workers keep glibc's own behaviour.
        with dask.config.set({NANNY_MALLOC_KEY: None}):
            self.cluster = LocalCluster(**options)
        self.client = Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        return False


__all__ = ['ChunkResult', 'SweepClient', 'SweepSummary', 'grid_table', 'parse_axis',
           'read_table', 'run_sweep', 'table_size']
