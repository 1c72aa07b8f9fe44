"""The same simulation over many parameter sets at once.

Each :class:`~rotrod_core.model.params.RodParams` field may be an array; all systems share
the drive (profile or torque).

Velocity drive (a profile): the exponential integrators of
:mod:`rotrod_core.offline.batch_velocity`, vectorised over the systems. The user asks
for an accuracy (``tolerance``, m, on u and v along the run; default 1e-10 m) and,
for histories, an ``output_interval``; the step is chosen for the tolerance. Undamped
isotropic systems (the paper's) are exact to rounding; the others use a sixth-order
Magnus step chosen by step doubling (the module's docstring). ``method='rk4'`` keeps
the previous fixed-step RK4 (``dt``) for comparison.

Torque drive: classical RK4 at the fixed step ``dt`` (default 1 ms), vectorised over
the systems: its error is O(dt^4); for the paper's rod at 1 ms it is ~1e-14 m in
the deflection over 40 s of a velocity-drive run (``bench/bench_core.py``) and the
exact coupling conserves angular momentum to 1e-10 relative or better
(``test/core/offline/test_batch.py``). Check a torque-drive batch by halving ``dt``.

Parallelism: locally, blocks of systems run on ``workers`` forked processes (from a
single-threaded caller; otherwise in this process): velocity drive writes into shared
memory, RK4 returns its chunks. With a ``dask.distributed.Client`` the chunks of
systems run as tasks on its workers and come back as one result in input order
(``docs/sweeps.md``).
"""

from __future__ import annotations

import math
import mmap
import multiprocessing
import os
import pickle
import threading
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np

import rotrod_core.model.equations as model
import rotrod_core.offline.batch_velocity as velocity
from rotrod_core.command.profiles import Profile
from rotrod_core.model.equations import Coefficients, check_coupling, make_state
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.blas import one_blas_thread
from rotrod_core.numerics.checks import NonFiniteStateError, finite_number
from rotrod_core.numerics.rk4 import rk4_step
from rotrod_core.offline.simulate import _torque_function, time_grid

METHODS = ('exponential', 'rk4')
DEFAULT_TOLERANCE = 1e-10
"""Default accuracy of a velocity-drive batch: largest error of u and v, m."""
BLOCK = 1024
"""Systems per block of the local velocity-drive run (keeps its arrays in ~16 MB)."""


@dataclass
class BatchResult:
    """Outcome of a batch run; arrays have the batch's flat size as first axis.

    Attributes:
        peak_deflection: largest |r| = sqrt(u^2 + v^2) over the run, m (velocity
            drive: between samples too, refined by Newton's method; RK4: over its steps).
        peak_time: time of that peak, s.
        final: the state at t_end (arrays).
        t: recorded times, s; empty if not recorded.
        u, v, omega, du, dv: recorded histories, shape (batch, len(t)) (du, dv in
            velocity drive with the exponential integrators; omega is the profile's).
        shape: the batch shape of the parameters.
        method: 'exponential' or 'rk4'.
        info: how the run was made (integrators, steps, error estimates).
    """

    peak_deflection: np.ndarray
    peak_time: np.ndarray
    final: model.State
    t: np.ndarray = field(default_factory=lambda: np.empty(0))
    u: np.ndarray | None = None
    v: np.ndarray | None = None
    omega: np.ndarray | None = None
    shape: tuple = ()
    du: np.ndarray | None = None
    dv: np.ndarray | None = None
    method: str = 'rk4'
    info: dict = field(default_factory=dict)


def _prescribed_rates(co, y, arg):
    u, v, du, dv = y
    omega, omega_dot = arg
    ddu, ddv = model.deflection_accelerations(co, u, v, du, dv, omega, omega_dot)
    return du, dv, ddu, ddv


def _run_chunk(co, n, t, profile, torque, coupling, init, record_every):
    zeros = np.zeros(n)
    y0 = make_state(init)
    state = [np.broadcast_to(np.asarray(c, dtype=float), (n,)).copy() for c in y0]
    if profile is not None:
        w0 = profile.omega(t[0])
        state[5] = zeros + w0
        jumps = {float(tj): (after - before) for tj, before, after in profile.jumps()}
    peak2 = state[0]**2 + state[1]**2
    peak_t = zeros.copy()
    nrec = (len(t) - 1) // record_every + 1 if record_every else 0
    rec = {k: np.empty((n, nrec)) for k in ('u', 'v', 'omega')} if nrec else {}

    def record(k, s):
        if nrec and k % record_every == 0:
            j = k // record_every
            rec['u'][:, j], rec['v'][:, j], rec['omega'][:, j] = s[0], s[1], s[5]

    record(0, state)
    q = _torque_function(torque) if torque is not None else None
    torque_rates = (lambda y, qq: model.torque_drive_rates(co, y, qq, coupling))  # noqa: E731
    prescribed = (lambda y, a: _prescribed_rates(co, y, a))  # noqa: E731
    tm = 0.5 * (t[:-1] + t[1:])
    if profile is not None:
        # the profile at every stage time, evaluated once (vectorized)
        w_k, wd_k = profile.omega(t).tolist(), profile.omega_dot(t).tolist()
        w_m, wd_m = profile.omega(tm).tolist(), profile.omega_dot(tm).tolist()
    for k in range(len(t) - 1):
        h = t[k + 1] - t[k]
        if profile is not None:
            args = ((w_k[k], wd_k[k]), (w_m[k], wd_m[k]), (w_k[k + 1], wd_k[k + 1]))
            u, v, du, dv = rk4_step(prescribed, tuple(state[:4]), h, *args)
            state = [u, v, du, dv, state[4], zeros + w_k[k + 1]]
            for tj, dw in jumps.items():
                if t[k] < tj <= t[k + 1]:
                    state = list(model.omega_jump(co, model.State(*state), state[5] + dw))
                    state[5] = zeros + profile.omega(t[k + 1])
        else:
            assert q is not None        # torque drive: exactly one of profile and torque
            state = list(rk4_step(torque_rates, tuple(state), h, q(t[k]), q(tm[k]), q(t[k + 1])))
        d2 = state[0] * state[0] + state[1] * state[1]
        if not np.all(np.isfinite(d2)):
            raise NonFiniteStateError(f'batch run became non-finite at t={t[k + 1]} s')
        higher = d2 > peak2
        peak2 = np.where(higher, d2, peak2)
        peak_t = np.where(higher, t[k + 1], peak_t)
        record(k + 1, state)
    return state, np.sqrt(peak2), peak_t, rec


def flat_coefficients(params: RodParams) -> Coefficients:
    """The Coefficients of every system of ``params``, each field an array (n,)."""
    return velocity.as_arrays(Coefficients.from_params(params), params.shape)


def _flat_batch(params: RodParams, initial: dict | None):
    """(n, shape, Coefficients of the flat batch, initial values flattened)."""
    shape = params.shape
    n = int(np.prod(shape)) if shape else 1
    co = flat_coefficients(params)
    init = {}
    for k, v in (initial or {}).items():
        arr = np.asarray(v, dtype=float)
        try:
            init[k] = np.broadcast_to(arr, shape if shape else (1,)).ravel()
        except ValueError:
            raise ValueError(f'initial {k!r} of shape {arr.shape} does not broadcast to the '
                             f'batch shape {shape}') from None
    return n, shape, co, init


def _output_times(t_end, dt, output_interval, record_every):
    if output_interval is not None:
        if record_every is not None:
            raise ValueError('give output_interval or record_every, not both')
        finite_number('output_interval', output_interval, positive=True)
        return time_grid(t_end, output_interval)
    if record_every is not None:
        return time_grid(t_end, 1e-3 if dt is None else dt)[::record_every]
    return None


def _shared_array(shape: tuple, dtype) -> np.ndarray:
    """A zeroed array in anonymous shared memory (forked children write into it)."""
    nbytes = max(1, int(np.prod(shape)) * np.dtype(dtype).itemsize)
    return np.frombuffer(mmap.mmap(-1, nbytes), dtype=dtype,
                         count=int(np.prod(shape))).reshape(shape)


# what forked children of velocity_chunk read (set before the fork):
# (co, profile, the_plan, z0, p0, out)
_FORKED_JOB: tuple[Coefficients, Profile, velocity.VelocityPlan, np.ndarray, np.ndarray,
                   dict[str, np.ndarray]] | None = None


def _run_blocks(blocks):
    assert _FORKED_JOB is not None, 'velocity_chunk sets _FORKED_JOB before the fork'
    co, profile, the_plan, z0, p0, out = _FORKED_JOB
    with one_blas_thread():
        for b in blocks:
            part = velocity.run(velocity.subset(co, b), profile, the_plan, z0[b], p0[b])
            for k, v in part.items():
                out[k][b] = v


def velocity_chunk(co, profile, the_plan, z0, p0, workers=1, block=BLOCK):
    """Run a chunk of velocity-drive systems on a plan, in blocks of ``block`` systems.

    With ``workers`` > 1 and a single-threaded caller the blocks are shared among
    forked processes writing into shared memory (threads would serialise on the GIL and
    on page faults); otherwise they run here one after the other. Returns
    :func:`rotrod_core.offline.batch_velocity.run`'s dict for the chunk. A task of
    :func:`simulate_batch` on a client and of the sweeps.
    """
    n = np.size(co.w1sq)
    blocks = [slice(i, min(i + block, n)) for i in range(0, n, block)]
    if workers <= 1 or len(blocks) < 2 or not _can_fork(None):
        out = {}
        with one_blas_thread():
            for b in blocks:
                part = velocity.run(velocity.subset(co, b), profile, the_plan, z0[b], p0[b])
                for k, v in part.items():
                    if k not in out:
                        out[k] = np.empty((n,) + v.shape[1:], v.dtype)
                    out[k][b] = v
        return out
    global _FORKED_JOB
    nout = 0 if the_plan.output_times is None else len(the_plan.output_times)
    out = {'z': _shared_array((n,), complex), 'p': _shared_array((n,), complex),
           'peak': _shared_array((n,), float), 'peak_time': _shared_array((n,), float)}
    if the_plan.output_times is not None:
        out.update({k: _shared_array((n, nout), float) for k in ('u', 'v', 'du', 'dv')})
    _FORKED_JOB = (co, profile, the_plan, z0, p0, out)
    try:
        groups = [list(g) for g in np.array_split(np.array(blocks, dtype=object),
                                                  min(workers, len(blocks)))]
        ctx = multiprocessing.get_context('fork')
        with ProcessPoolExecutor(len(groups), mp_context=ctx) as pool:
            list(pool.map(_run_blocks, groups))
    finally:
        _FORKED_JOB = None
    return out


def _chunks(n: int, size: int) -> list:
    size = max(1, int(size))
    return [(lo, min(lo + size, n)) for lo in range(0, n, size)]


def _cut(co: Coefficients, init: dict, lo: int, hi: int):
    sub = Coefficients(**{k: (v[lo:hi] if np.ndim(v) else v) for k, v in vars(co).items()})
    return sub, {k: (v[lo:hi] if np.ndim(v) else v) for k, v in init.items()}


def _on_client(client, fn, jobs: list) -> list:
    """Run ``fn(*job)`` for every job as Dask tasks; results in the order of ``jobs``."""
    futures = [client.submit(fn, *job, pure=False) for job in jobs]
    return client.gather(futures)


def default_chunk_size(n: int, client) -> int:
    """Systems per Dask task: two tasks per worker, in whole blocks of :data:`BLOCK`.

    Whole blocks make a run on a client equal, bit for bit, to the same run without one.
    """
    nworkers = max(1, len(client.scheduler_info().get('workers', {})))
    return BLOCK * max(1, math.ceil(n / (2 * nworkers * BLOCK)))


def simulate_batch(params: RodParams, profile: Profile | None = None,
                   t_end: float | None = None, dt: float | None = None, *, torque=None,
                   coupling: str = 'exact', initial: dict | None = None,
                   tolerance: float = DEFAULT_TOLERANCE, output_interval: float | None = None,
                   record_every: int | None = None, method: str | None = None,
                   workers: int | None = None, client=None,
                   chunk_size: int | None = None) -> BatchResult:
    """Run every system of a batch of parameters under the same drive.

    Args:
        params: RodParams whose fields may be arrays (broadcast together).
        profile: angular-velocity profile (velocity drive), or
        torque: hub torque, N m or callable t -> N m (torque drive).
        t_end: duration, s.
        dt: RK4's step, s (torque drive or ``method='rk4'``; default 1e-3). With the
            exponential integrators only an upper bound on their step (they choose it
            for ``tolerance``).
        coupling: ``'exact'`` or ``'paper'`` (torque drive; also the reported physics).
        initial: initial state by name (scalars or arrays broadcast to the batch).
        tolerance: velocity drive, exponential integrators: the largest error of u and
            v wanted along the whole run, m (default 1e-10).
        output_interval: record u, v, du, dv and omega every this many seconds (and at
            t_end); None: record none.
        record_every: (RK4, and for compatibility) record every this many steps of
            ``dt``; with the exponential integrators, the same times as
            ``output_interval = record_every * dt``.
        method: ``'exponential'`` (velocity drive's default) or ``'rk4'`` (torque drive,
            always; in velocity drive the previous fixed-step integrator).
        workers: local parallelism: forked processes (exponential: batches of more than
            one block of :data:`BLOCK` systems; RK4: of >= 4000 systems); default one per
            core, up to 2. A multi-threaded caller (a ROS node, a Dask worker), or a
            torque function that cannot be pickled, keeps the run in one process.
        client: a ``dask.distributed.Client``: chunks of systems run as tasks on its
            workers (the torque, profile and rotrod_core must be importable there).
        chunk_size: systems per Dask task (default :func:`default_chunk_size`; a size
            that is not a multiple of :data:`BLOCK` changes results by rounding only).

    Returns:
        :class:`BatchResult` with peak deflection, its time, the final state and the
        optional histories, flattened over the batch shape (``result.shape``), in the
        input order also when run on a client.
    """
    if not isinstance(params, RodParams):
        raise ValueError(f'params must be RodParams, got {type(params).__name__}')
    if (profile is None) == (torque is None):
        raise ValueError('give exactly one of profile (velocity drive) or torque')
    if torque is not None:
        check_coupling_batch(params, coupling)
    elif not isinstance(profile, Profile):
        raise ValueError(f'profile must be a rotrod_core Profile, got {profile!r}')
    else:
        model.coupling_name(coupling)
    if t_end is None:
        raise ValueError('t_end is required')
    if profile is not None and initial and 'omega' in initial:
        raise ValueError('in velocity drive omega comes from the profile')
    if record_every is not None and (isinstance(record_every, bool)
                                     or not isinstance(record_every, (int, np.integer))
                                     or record_every < 1):
        raise ValueError(f'record_every must be a positive integer, got {record_every!r}')
    if method is None:
        method = 'exponential' if profile is not None else 'rk4'
    if method not in METHODS:
        raise ValueError(f'method must be one of {METHODS}, got {method!r}')
    if method == 'exponential' and profile is None:
        raise ValueError("torque drive runs RK4 (method='rk4')")
    finite_number('tolerance', tolerance, positive=True)
    if dt is not None:
        finite_number('dt', dt, positive=True)
    time_grid(t_end, dt if dt is not None else min(1e-3, t_end))      # checks t_end, dt
    if chunk_size is not None and (isinstance(chunk_size, bool) or int(chunk_size) != chunk_size
                                   or chunk_size < 1):
        raise ValueError(f'chunk_size must be a positive integer, got {chunk_size!r}')
    make_state(initial)                                                 # checks names, values
    n, shape, co_all, init = _flat_batch(params, initial)
    if workers is None:
        workers = min(2, os.cpu_count() or 1)
    if client is not None and chunk_size is None:
        chunk_size = default_chunk_size(n, client)
    if method == 'exponential':
        return _velocity_batch(co_all, n, shape, profile, t_end, dt, init, tolerance,
                               _output_times(t_end, dt, output_interval, record_every),
                               workers, client, chunk_size)
    if output_interval is not None:
        dt_rk4 = 1e-3 if dt is None else dt
        every = output_interval / dt_rk4
        if abs(every - round(every)) > 1e-9 * every or round(every) < 1:
            raise ValueError(f'with RK4 output_interval ({output_interval} s) must be a '
                             f'multiple of dt ({dt_rk4} s)')
        record_every = int(round(every))
    return _rk4_batch(co_all, n, shape, profile, torque, t_end, 1e-3 if dt is None else dt,
                      coupling, init, record_every, workers, client, chunk_size)


def _velocity_batch(co_all, n, shape, profile, t_end, dt, init, tolerance, output_times,
                    workers, client, chunk_size) -> BatchResult:
    zeros = np.zeros(n)

    def value(name):
        return np.broadcast_to(np.asarray(init.get(name, 0.0), float), (n,))
    z0 = value('u') + 1j * value('v')
    p0 = value('du') + 1j * value('dv')
    the_plan = velocity.plan(co_all, profile, t_end, tolerance, output_times, max_step=dt,
                             z0=z0, p0=p0)
    if client is None:
        out = velocity_chunk(co_all, profile, the_plan, z0, p0, workers)
    else:
        jobs = []
        for lo, hi in _chunks(n, chunk_size):
            sub, _ = _cut(co_all, {}, lo, hi)
            jobs.append((sub, profile, the_plan, z0[lo:hi], p0[lo:hi], 1))
        parts = _on_client(client, velocity_chunk, jobs)
        out = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    theta = value('theta') + float(profile.angle(t_end))
    final = model.State(out['z'].real.copy(), out['z'].imag.copy(), out['p'].real.copy(),
                        out['p'].imag.copy(), theta, zeros + float(profile.omega(t_end)))
    info = {'integrators': {velocity.KINDS[k]: {'systems': int(np.sum(
        velocity.system_kinds(co_all) == k)), 'nodes': len(nodes),
        'step_s': the_plan.steps[k], 'estimated_error_m': the_plan.estimates[k]}
        for k, nodes in enumerate(the_plan.nodes) if nodes is not None}, 'tolerance_m': tolerance}
    result = BatchResult(peak_deflection=out['peak'], peak_time=out['peak_time'], final=final,
                         shape=shape, method='exponential', info=info)
    if output_times is not None:
        result.t = output_times
        result.u, result.v, result.du, result.dv = out['u'], out['v'], out['du'], out['dv']
        result.omega = np.broadcast_to(profile.omega(output_times), (n, len(output_times)))
    return result


def _rk4_batch(co_all, n, shape, profile, torque, t_end, dt, coupling, init, record_every,
               workers, client, chunk_size) -> BatchResult:
    t = time_grid(t_end, dt)
    if client is not None:
        bounds = _chunks(n, chunk_size)
    else:
        if not (n >= 4000) or not _can_fork(torque):
            workers = 1
        edges = np.linspace(0, n, max(1, min(int(workers), n)) + 1).astype(int)
        bounds = list(zip(edges[:-1], edges[1:]))
    jobs = []
    for lo, hi in bounds:
        co, ini = _cut(co_all, init, lo, hi)
        jobs.append((co, hi - lo, t, profile, torque, coupling, ini, record_every))
    if client is not None:
        parts = _on_client(client, _run_chunk, jobs)
    elif len(jobs) > 1:
        ctx = multiprocessing.get_context('fork')
        with ProcessPoolExecutor(len(jobs), mp_context=ctx) as pool:
            parts = list(pool.map(_run_chunk, *zip(*jobs)))
    else:
        parts = [_run_chunk(*jobs[0])]
    final = model.State(*(np.concatenate([p[0][i] for p in parts]) for i in range(6)))
    rec = {k: np.concatenate([p[3][k] for p in parts]) for k in parts[0][3]}
    return BatchResult(peak_deflection=np.concatenate([p[1] for p in parts]),
                       peak_time=np.concatenate([p[2] for p in parts]), final=final,
                       t=t[::record_every] if record_every else np.empty(0),
                       u=rec.get('u'), v=rec.get('v'), omega=rec.get('omega'), shape=shape,
                       method='rk4', info={'dt_s': dt, 'steps': len(t) - 1})


def _can_fork(torque) -> bool:
    """Whether worker processes may be used.

    They are forked only from a single-threaded process (fork is unsafe with threads,
    and 'spawn' would re-import an unguarded __main__ script), and only when the
    torque can be sent to them.
    """
    if 'fork' not in multiprocessing.get_all_start_methods() or threading.active_count() > 1:
        return False
    try:
        pickle.dumps(torque)
    except Exception:  # noqa: BLE001 - any failure means: run in this process
        return False
    return True


def check_coupling_batch(params: RodParams, coupling: str) -> None:
    """:func:`check_coupling` for every system of a batch."""
    if coupling == 'exact' and np.any(np.asarray(params.hub_inertia) <= 0):
        raise ValueError('the exact coupling needs hub_inertia > 0 for every system')
    check_coupling(params.item(0) if params.is_batch else params, coupling)


__all__ = ['BatchResult', 'DEFAULT_TOLERANCE', 'simulate_batch']
