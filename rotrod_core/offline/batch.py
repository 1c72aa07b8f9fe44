"""The same simulation over many parameter sets at once (vectorized RK4).

Each :class:`~rotrod_core.model.params.RodParams` field may be an array; all systems share
the drive (profile or torque) and advance together, one numpy operation per term
over the whole batch. Large batches are split over worker processes (one per core:
threads would contend for the GIL between the many short numpy calls).
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import threading
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np

import rotrod_core.model.equations as model
from rotrod_core.command.profiles import Profile
from rotrod_core.model.equations import Coefficients, check_coupling, make_state
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import NonFiniteStateError
from rotrod_core.numerics.rk4 import rk4_step
from rotrod_core.offline.simulate import _torque_function, time_grid


@dataclass
class BatchResult:
    """Outcome of a batch run; arrays have the batch's flat size as first axis.

    Attributes:
        peak_deflection: largest |r| = sqrt(u^2 + v^2) over the run, m.
        peak_time: time of that peak, s.
        final: the state at t_end (arrays).
        t: recorded times (every ``record_every`` steps), s; empty if not recorded.
        u, v, omega: recorded histories, shape (batch, len(t)).
    """

    peak_deflection: np.ndarray
    peak_time: np.ndarray
    final: model.State
    t: np.ndarray = field(default_factory=lambda: np.empty(0))
    u: np.ndarray | None = None
    v: np.ndarray | None = None
    omega: np.ndarray | None = None
    shape: tuple = ()


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
            state = list(rk4_step(torque_rates, tuple(state), h, q(t[k]), q(tm[k]), q(t[k + 1])))
        d2 = state[0] * state[0] + state[1] * state[1]
        if not np.all(np.isfinite(d2)):
            raise NonFiniteStateError(f'batch run became non-finite at t={t[k + 1]} s')
        higher = d2 > peak2
        peak2 = np.where(higher, d2, peak2)
        peak_t = np.where(higher, t[k + 1], peak_t)
        record(k + 1, state)
    return state, np.sqrt(peak2), peak_t, rec


def simulate_batch(params: RodParams, profile: Profile | None = None,
                   t_end: float | None = None, dt: float = 1e-3, *, torque=None,
                   coupling: str = 'exact', initial: dict | None = None,
                   record_every: int | None = None, workers: int | None = None) -> BatchResult:
    """Run every system of a batch of parameters under the same drive.

    Args:
        params: RodParams whose fields may be arrays (broadcast together).
        profile: angular-velocity profile (velocity drive), or
        torque: hub torque, N m or callable t -> N m (torque drive).
        t_end: duration, s.
        dt: integration step, s (classical RK4).
        coupling: ``'exact'`` or ``'paper'`` (torque drive; also the reported physics).
        initial: initial state by name (scalars or arrays broadcast to the batch).
        record_every: keep u, v, omega every this many steps (None: keep none).
        workers: processes (default: one per core, up to 2, for batches of >= 4000
            systems; else 1). A torque function that cannot be pickled, or a
            multi-threaded caller (e.g. a ROS node), runs in one.

    Returns:
        :class:`BatchResult` with peak deflection, its time, the final state and the
        optional histories, flattened over the batch shape (``result.shape``).
    """
    if not isinstance(params, RodParams):
        raise ValueError(f'params must be RodParams, got {type(params).__name__}')
    if (profile is None) == (torque is None):
        raise ValueError('give exactly one of profile (velocity drive) or torque')
    if torque is not None:
        check_coupling_batch(params, coupling)
    elif not isinstance(profile, Profile):
        raise ValueError(f'profile must be a rotrod_core Profile, got {profile!r}')
    if t_end is None:
        raise ValueError('t_end is required')
    if profile is not None and initial and 'omega' in initial:
        raise ValueError('in velocity drive omega comes from the profile')
    if record_every is not None and (not isinstance(record_every, int) or record_every < 1):
        raise ValueError(f'record_every must be a positive integer, got {record_every!r}')
    t = time_grid(t_end, dt)
    shape = params.shape
    n = int(np.prod(shape)) if shape else 1
    flat = {name: np.broadcast_to(value, shape).ravel() if shape else value
            for name, value in params._numeric().items()}
    co_all = Coefficients.from_params(params.replace(**flat)) if shape else \
        Coefficients.from_params(params)
    init = {k: np.broadcast_to(np.asarray(v, dtype=float), shape).ravel() if shape
            else v for k, v in (initial or {}).items()}
    if workers is None:
        workers = min(2, os.cpu_count() or 1) if n >= 4000 else 1
    if workers > 1 and not _can_fork(torque):
        workers = 1
    bounds = np.linspace(0, n, max(1, min(int(workers), n)) + 1).astype(int)
    jobs = []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        co = Coefficients(**{k: (v[lo:hi] if np.ndim(v) else v)
                             for k, v in vars(co_all).items()})
        ini = {k: (v[lo:hi] if np.ndim(v) else v) for k, v in init.items()}
        jobs.append((co, hi - lo, t, profile, torque, coupling, ini, record_every))
    if len(jobs) > 1:
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
                       u=rec.get('u'), v=rec.get('v'), omega=rec.get('omega'), shape=shape)


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


__all__ = ['BatchResult', 'simulate_batch']
