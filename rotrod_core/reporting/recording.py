"""Rerun recordings of a rotrod run: writing in batches, and reading back (no ROS import).

Used by the ROS Rerun logger (live runs) and by ``rotrod reproduce`` (offline runs).
rerun-sdk is imported when a recording is written or read, not with this module, so
the numerical core does not need it.

Entities (SI units; time on the timeline ``time``, from the message stamps, and, once
the hub has first moved, on ``profile time``, 0 at the profile's start):

    timeseries/deflection/u, .../v        tip deflection in the rotating frame, m
    timeseries/deflection/magnitude       |r| = sqrt(u^2 + v^2), m
    timeseries/deflection/limit           the critical deflection (deflection_limit), m
    timeseries/deflection/critical, .../peak   markers: the first crossing of the
                                          critical deflection, and that excursion's peak
    timeseries/hub/omega                  hub angular velocity, rad/s
    timeseries/hub/torque                 hub torque, N m
    timeseries/hub/stage                  markers: a new stage (spin-up, hold, ...) starts
    timeseries/frequencies/model          [f1, f2], Hz (Eq. 28 / eigen analysis)
    timeseries/frequencies/estimate       [f1, f2], Hz, estimated from the motion
    rotating/tip                          (u, v) m: the latest point
    rotating/path/<stage>                 (u, v) m: the paper's Figs. 4-8, by stage
    inertial/tip                          (x, y, z) m: the mass in the world frame
    mechanism/...                         the disk, rod and mass in 3D (recording_scene)
    events                                TextLog: stages, the critical deflection, halts

Samples are buffered and sent as columns (one call per entity per batch): logging
them one by one costs ~40 us each in rerun-sdk 0.41, columns ~0.1 us.
"""

from __future__ import annotations

import math
import uuid
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from rotrod_core.analysis.run_events import CriticalDeflectionWatch, Event, StageTracker

from . import recording_scene as scene3d
from .recording_layout import EVENTS, PROFILE_TIMELINE, TIMELINE
from .recording_layout import blueprint as _layout
from .recording_scene import Mechanism

U, V = 'timeseries/deflection/u', 'timeseries/deflection/v'
MAGNITUDE, LIMIT = 'timeseries/deflection/magnitude', 'timeseries/deflection/limit'
CRITICAL, PEAK = 'timeseries/deflection/critical', 'timeseries/deflection/peak'
OMEGA, TORQUE = 'timeseries/hub/omega', 'timeseries/hub/torque'
STAGE = 'timeseries/hub/stage'
F_MODEL, F_ESTIMATE = 'timeseries/frequencies/model', 'timeseries/frequencies/estimate'
ROTATING_TIP, INERTIAL_TIP = 'rotating/tip', 'inertial/tip'
IMU_ACCELERATION = 'timeseries/imu/linear_acceleration'
IMU_ANGULAR_VELOCITY = 'timeseries/imu/angular_velocity'
"""The tip IMU's readings (tip/imu), each three scalars: x, y, z of the sensor's frame."""
EPOCH_THRESHOLD = 1e9
"""Stamps above this many seconds are wall-clock (epoch) times, below it simulated time."""

SERIES_STYLE = {
    U: ('u [m]', [31, 119, 180]), V: ('v [m]', [214, 39, 40]),
    MAGNITUDE: ('|r| [m]', [120, 120, 120]),
    LIMIT: ('critical deflection [m]', [230, 80, 80]),
    OMEGA: ('omega [rad/s]', [44, 160, 44]), TORQUE: ('hub torque [N m]', [148, 103, 189]),
}
MARKER_STYLE: dict[str, tuple[str, list[int], Any]] = {
    CRITICAL: ('critical deflection first crossed', [230, 80, 80], 'Diamond'),
    PEAK: ('peak deflection beyond it', [230, 80, 80], 'Up'),
    STAGE: ('a stage starts', [255, 200, 0], 'Diamond'),
}
_EVENT_ENTITY = {'stage': STAGE, 'critical': CRITICAL, 'peak': PEAK}

# buffers: one per kind of message, rows of floats, the stamp first
_STATE, _POSE, _DEFLECTION, _POSITION = 'state', 'pose', 'deflection', 'position'
_F_MODEL, _F_ESTIMATE = 'f_model', 'f_estimate'
_IMU = 'imu'
IMU_STYLE = {
    IMU_ACCELERATION: ([f'specific force {a} [m/s^2]' for a in 'xyz'],
                       [[31, 119, 180], [214, 39, 40], [44, 160, 44]]),
    IMU_ANGULAR_VELOCITY: ([f'angular velocity {a} [rad/s]' for a in 'xyz'],
                           [[140, 86, 75], [227, 119, 194], [127, 127, 127]]),
}


def blueprint(mech: Mechanism | None = None, timeline: str = TIMELINE, imu: bool = False):
    """The default layout, a ``rerun.blueprint.Blueprint`` (see recording_layout)."""
    return _layout(mech or Mechanism(), timeline, imu)


class RecordingWriter:
    """Writes a rotrod run to a .rrd file (and optionally serves it on 127.0.0.1).

    Call the ``add_*`` methods per message, :meth:`flush` periodically, :meth:`close`
    at the end (also on a signal): it sends what is buffered and, with ``footer``,
    writes the footer. A file without footer (``footer=False``, or a process killed
    without :meth:`close`: SIGKILL) holds everything flushed: :func:`read_series`
    (``RrdReader(path).stream()``) and the viewer read it, ``rerun rrd verify`` refuses
    it, and ``rerun rrd optimize FILE -o COPY`` writes a complete copy.

    ``footer``: rerun's file sink keeps a manifest entry of every chunk written in
    memory until the end, for the footer (each :meth:`flush` writes a chunk per entity
    that has new data): memory grows with the length of the run. ``footer=False`` keeps
    it flat, rerun's advice for long streaming sessions (the live logger's default).

    With ``pretrigger`` (s), the writer starts armed, as an oscilloscope: it keeps
    only the last ``pretrigger`` seconds of stamp time and writes nothing until
    :meth:`trigger` (or the hub's first motion); from then on it records everything,
    that prefix first. So a recording can begin just before something happens (a
    commanded profile) rather than when the logger started.

    ``mechanism``: the rod and drawing settings of the 3D scene and of the critical
    deflection. ``origin`` (s of stamp time): the profile's start, if known (an offline
    run: 0); otherwise it is the stamp of the last sample before the hub first moved
    (w first differs from its first value), the profile's start to one sample.
    Samples sent once it is known are also on the ``profile time`` timeline.
    """

    def __init__(self, path: str | Path, *, application_id: str = 'rotrod',
                 serve_port: int | None = None, pretrigger: float | None = None,
                 mechanism: Mechanism | None = None, origin: float | None = None,
                 footer: bool = True, imu: bool = False):
        if pretrigger is not None and not (math.isfinite(pretrigger) and pretrigger >= 0):
            raise ValueError(f'pretrigger must be a finite number of seconds >= 0, got '
                             f'{pretrigger!r}')
        self.pretrigger = pretrigger
        self.armed = pretrigger is not None
        """Waiting for :meth:`trigger`: nothing older than ``pretrigger`` is kept."""
        self.mechanism = mechanism or Mechanism()
        self.origin = origin
        """The profile's start, s of stamp time (None: the hub has not moved yet)."""
        import rerun as rr
        self._rr = rr
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.rec = rr.RecordingStream(application_id, recording_id=uuid.uuid4())
        sinks: list = [rr.FileSink(str(self.path), write_footer=footer)]
        self.serve_uri = None
        if serve_port is not None:
            server = rr.GrpcServerSink(bind_ip='127.0.0.1', port=int(serve_port))
            sinks.append(server)
            self.serve_uri = server.uri
        # the profile's timeline where every sample will be on it
        timeline = PROFILE_TIMELINE if (origin is not None or self.armed) else TIMELINE
        self.rec.set_sinks(*sinks, default_blueprint=blueprint(self.mechanism, timeline, imu))
        for entity, (name, color) in SERIES_STYLE.items():
            self.rec.log(entity, rr.SeriesLines(names=name, colors=[color]), static=True)
        for entity, (name, color, marker) in MARKER_STYLE.items():
            self.rec.log(entity, rr.SeriesPoints(names=name, colors=[color], markers=marker,
                                                 marker_sizes=6.0), static=True)
        for entity in (F_MODEL, F_ESTIMATE):
            suffix = ' (estimate)' if entity == F_ESTIMATE else ''
            self.rec.log(entity, rr.SeriesLines(names=[f'f1 [Hz]{suffix}', f'f2 [Hz]{suffix}'],
                                                colors=[[255, 127, 14], [23, 190, 207]]),
                         static=True)
        self.rec.log(ROTATING_TIP, rr.Points2D.from_fields(radii=-4.0, colors=[[255, 255, 255]]),
                     static=True)
        if imu:
            for entity, (names, colors) in IMU_STYLE.items():
                self.rec.log(entity, rr.SeriesLines(names=names, colors=colors), static=True)
        scene3d.log_static(self.rec, rr, self.mechanism)
        self._buffers: dict[str, list] = {k: [] for k in (
            _STATE, _POSE, _DEFLECTION, _POSITION, _F_MODEL, _F_ESTIMATE, _IMU)}
        self._events: list[tuple[float, str, str]] = []     # (t, level, text), unsent
        self._markers: dict[str, list] = {e: [] for e in MARKER_STYLE}
        self._path_rows: list = []        # arrays of (t, u, v) rows waiting for their stage
        self._new_omega: list = []        # (t, w) not yet given to the stage tracker
        self._first_omega: float | None = None
        self._last_rest: float | None = None
        self.stages = StageTracker()
        self.critical = CriticalDeflectionWatch(self.mechanism.deflection_limit)
        self.epoch_time: bool | None = None
        self.samples = 0
        self.last_time: float | None = None
        self.closed = False

    def _stamp(self, t: float) -> None:
        if self.epoch_time is None:
            self.epoch_time = t > EPOCH_THRESHOLD
        if self.last_time is None or t > self.last_time:
            self.last_time = t

    def add_state(self, t: float, omega: float, torque: float) -> None:
        """Hub angular velocity (rad/s) and torque (N m) at stamp time ``t`` (s).

        The first change of w from its first value is the hub's first motion: it sets
        ``origin`` (if not given) and triggers an armed writer.
        """
        self._stamp(t)
        self._buffers[_STATE].append((t, omega, torque))
        self._new_omega.append((t, omega))
        if self._first_omega is None:
            self._first_omega = omega
        if omega == self._first_omega:
            self._last_rest = t
        elif self.origin is None:
            self.origin = self._last_rest if self._last_rest is not None else t
            self.event(self.origin, 'the profile starts: the hub first moves after stamp '
                                    f'{self.origin:.3f} s (t = 0 on "{PROFILE_TIMELINE}")')
            self.trigger()

    def add_pose(self, t: float, theta: float, u: float, v: float) -> None:
        """The mechanism at stamp time ``t`` (s), for the 3D scene.

        ``theta`` the hub angle (rad), (u, v) the tip's true deflection (m, rotating frame).
        """
        self._stamp(t)
        self._buffers[_POSE].append((t, theta, u, v))

    def trigger(self) -> None:
        """Start recording (armed writers): the kept pretrigger seconds are written first."""
        if self.armed:
            self._trim()
        self.armed = False

    def _trim(self) -> None:
        """Drop what is older than ``pretrigger`` before the latest stamp (armed)."""
        last, keep = self.last_time, self.pretrigger or 0.0
        oldest = last - keep if last is not None else 0.0
        for rows in self._buffers.values():
            rows[:] = [r for r in rows if r[0] >= oldest]
        self._path_rows = [a[a[:, 0] >= oldest] for a in self._path_rows]
        self._events = [e for e in self._events if e[0] >= oldest]
        for rows in self._markers.values():
            rows[:] = [r for r in rows if r[0] >= oldest]

    def add_deflection(self, t: float, u: float, v: float) -> None:
        """Tip deflection (m) in the rotating frame at stamp time ``t`` (s)."""
        self._stamp(t)
        self._buffers[_DEFLECTION].append((t, u, v))

    def add_position(self, t: float, x: float, y: float, z: float) -> None:
        """Mass position (m) in the inertial frame at stamp time ``t`` (s)."""
        self._stamp(t)
        self._buffers[_POSITION].append((t, x, y, z))

    def add_frequencies(self, t: float, f1: float, f2: float, estimate: bool = False) -> None:
        """Dynamic frequencies (Hz), from the model or estimated, at time ``t`` (s)."""
        self._stamp(t)
        self._buffers[_F_ESTIMATE if estimate else _F_MODEL].append((t, f1, f2))

    def add_imu(self, t: float, acceleration, angular_velocity) -> None:
        """The tip IMU's reading at stamp time ``t`` (s).

        The specific force (m/s^2) and the angular velocity (rad/s), each (x, y, z) in
        the sensor's frame.
        """
        self._stamp(t)
        self._buffers[_IMU].append((t, *acceleration, *angular_velocity))

    def event(self, t: float, text: str, level: str = 'INFO') -> None:
        """A text entry in ``events`` at stamp time ``t`` (s) (e.g. a halt: 'ERROR')."""
        self._events.append((t, level, text))

    def _take_events(self, events: list[Event]) -> None:
        for e in events:
            shown = e.time - self.origin if self.origin is not None else e.time
            self.event(e.time, e.text.format(t=f'{shown:.3f} s'),
                       'WARN' if e.kind in ('critical', 'peak') else 'INFO')
            self._markers[_EVENT_ENTITY[e.kind]].append((e.time, e.value))

    def flush(self, timeout: float | None = 10.0) -> None:
        """Send everything buffered to the sinks (one column batch per entity).

        Then wait (up to ``timeout`` s; None: do not wait) until the sinks have it: in
        the file, so a process killed after this returns has lost nothing flushed (the
        file lacks only its footer). rerun-sdk writes to the file from a thread of its
        own, which was measured a few batches behind right after ``send_columns``.
        Raises if the sinks do not catch up within ``timeout``.
        """
        self._send()
        if timeout is not None:
            self.rec.flush(timeout_sec=timeout)

    def _analyse(self, final: bool) -> None:
        """Feed the new samples to the stage tracker and the critical-deflection watch.

        Each sample once: the deflections just before they are sent.
        """
        if self._new_omega:
            w = np.array(self._new_omega, dtype=float)
            self._new_omega.clear()
            self._take_events(self.stages.push(w[:, 0], w[:, 1]))
        if final:
            self.stages.finish()
        if self.armed:
            return
        rows = self._buffers[_DEFLECTION]
        if rows:
            d = np.array(rows, dtype=float)
            self._take_events(self.critical.push(d[:, 0], d[:, 1], d[:, 2]))
        if final:
            self._take_events(self.critical.finish())

    def _index(self, t: np.ndarray) -> list:
        rr = self._rr
        kind = 'timestamp' if self.epoch_time else 'duration'
        index = [rr.TimeColumn(TIMELINE, **{kind: t})]
        if self.origin is not None:
            index.append(rr.TimeColumn(PROFILE_TIMELINE, duration=t - self.origin))
        return index

    def _send_rows(self, entity: str, index: list, columns) -> None:
        self.rec.send_columns(entity, indexes=index, columns=columns)

    def _send(self, final: bool = False) -> None:
        self._analyse(final)
        if self.armed:
            self._trim()
            return
        rr, b, send = self._rr, self._buffers, self._send_rows
        if b[_STATE]:
            a = np.array(b[_STATE], dtype=float)
            self.samples += len(a)
            index = self._index(a[:, 0])
            send(OMEGA, index, rr.Scalars.columns(scalars=a[:, 1]))
            send(TORQUE, index, rr.Scalars.columns(scalars=a[:, 2]))
        if b[_DEFLECTION]:
            a = np.array(b[_DEFLECTION], dtype=float)
            t, n = a[:, 0], len(a)
            index = self._index(t)
            send(U, index, rr.Scalars.columns(scalars=a[:, 1]))
            send(V, index, rr.Scalars.columns(scalars=a[:, 2]))
            send(MAGNITUDE, index, rr.Scalars.columns(scalars=np.hypot(a[:, 1], a[:, 2])))
            send(ROTATING_TIP, index, rr.Points2D.columns(
                positions=a[:, 1:3]).partition(np.ones(n, dtype=np.int32)))
            if self.mechanism.deflection_limit > 0:
                send(LIMIT, self._index(t[[0, -1]]), rr.Scalars.columns(
                    scalars=np.full(2, self.mechanism.deflection_limit)))
            self._path_rows.append(a)
        self._send_path()
        if b[_POSE]:
            a = np.array(b[_POSE], dtype=float)
            index = self._index(a[:, 0])
            for entity, columns in scene3d.pose_columns(rr, self.mechanism, a[:, 1], a[:, 2],
                                                        a[:, 3]).items():
                send(entity, index, columns)
        if b[_POSITION]:
            a = np.array(b[_POSITION], dtype=float)
            send(INERTIAL_TIP, self._index(a[:, 0]), rr.Points3D.columns(
                positions=a[:, 1:4]).partition(np.ones(len(a), dtype=np.int32)))
        for key, entity in ((_F_MODEL, F_MODEL), (_F_ESTIMATE, F_ESTIMATE)):
            if b[key]:
                a = np.array(b[key], dtype=float)
                send(entity, self._index(a[:, 0]), rr.Scalars.columns(
                    scalars=a[:, 1:3]).partition(np.full(len(a), 2, dtype=np.int32)))
        if b[_IMU]:
            a = np.array(b[_IMU], dtype=float)
            index, three = self._index(a[:, 0]), np.full(len(a), 3, dtype=np.int32)
            send(IMU_ACCELERATION, index,
                 rr.Scalars.columns(scalars=a[:, 1:4]).partition(three))
            send(IMU_ANGULAR_VELOCITY, index,
                 rr.Scalars.columns(scalars=a[:, 4:7]).partition(three))
        for rows in b.values():
            rows.clear()
        for entity, marks in self._markers.items():
            if marks:
                a = np.array(sorted(marks), dtype=float)
                send(entity, self._index(a[:, 0]), rr.Scalars.columns(scalars=a[:, 1]))
                marks.clear()
        if self._events:
            self._events.sort()
            t = np.array([e[0] for e in self._events], dtype=float)
            send(EVENTS, self._index(t), rr.TextLog.columns(
                text=[e[2] for e in self._events], level=[e[1] for e in self._events]))
            self._events.clear()

    def _send_path(self) -> None:
        """The rotating-frame path of the samples whose stage is decided, by stage."""
        if not self._path_rows:
            return
        a = np.concatenate(self._path_rows)
        ready = a[:, 0] < self.stages.decided_until
        self._path_rows = [a[~ready]] if not ready.all() else []
        a = a[ready]
        if not len(a):
            return
        which = np.maximum(self.stages.stage_index(a[:, 0]), 0)
        for k in np.unique(which):
            rows = a[which == k]
            stage = self.stages.stages[int(k)] if self.stages.stages else 'rest'
            self._send_rows(scene3d.path_entity(stage), self._index(rows[:, 0]),
                            self._rr.Points2D.columns(positions=rows[:, 1:3]).partition(
                                np.ones(len(rows), dtype=np.int32)))

    def close(self, timeout: float = 10.0) -> None:
        """Flush, wait for the sinks, and close the file (writes its footer)."""
        if self.closed:
            return
        self.closed = True
        self._send(final=True)
        self.flush(timeout)
        self.rec.disconnect()


def write_run(path: str | Path, run, *, sample_interval: float = 0.01,
              application_id: str = 'rotrod', mechanism: Mechanism | None = None) -> int:
    """Write an offline run (:class:`~rotrod_core.offline.result.SimulationResult`) to .rrd.

    The same entities as a live recording: u, v, omega, hub torque, the model's
    dynamic frequencies f1, f2 (Hz) at each sample's omega, the tip in the rotating
    and inertial frames, and the mechanism in 3D (``mechanism``: by default the run's
    rod with the markers' drawing settings). The run's t = 0 is the profile's start.
    Samples are taken every ``sample_interval`` seconds of the run (at least every
    sample). Returns the number of samples written.
    """
    from rotrod_core.analysis.modes import dynamic_frequencies

    dt = float(run.t[1] - run.t[0]) if len(run.t) > 1 else sample_interval
    every = max(1, int(round(sample_interval / dt)))
    keep = np.arange(0, len(run.t), every)
    if keep[-1] != len(run.t) - 1:
        keep = np.append(keep, len(run.t) - 1)
    f1, f2 = dynamic_frequencies(run.params, run.omega[keep])
    height = float(run.params.rod_length)
    writer = RecordingWriter(path, application_id=application_id, origin=float(run.t[0]),
                             mechanism=mechanism or Mechanism.from_params(run.params))
    try:
        for j, i in enumerate(keep):
            t = float(run.t[i])
            writer.add_state(t, float(run.omega[i]), float(run.torque[i]))
            writer.add_pose(t, float(run.theta[i]), float(run.u[i]), float(run.v[i]))
            writer.add_deflection(t, float(run.u[i]), float(run.v[i]))
            writer.add_position(t, float(run.x[i]), float(run.y[i]), height)
            writer.add_frequencies(t, float(f1[j]), float(f2[j]))
    finally:
        writer.close()
    return len(keep)


def _chunks(path: str | Path):
    """The chunks of a recording, in file order, with or without its footer.

    Without footer (the live logger's default) ``RrdReader`` warns that ``store()`` is
    not available; only ``stream()`` is used here.
    """
    from rerun.chunk import RrdReader
    with warnings.catch_warnings():
        warnings.filterwarnings('ignore', message='RRD file has no footer')
        reader = RrdReader(str(path))
    return reader.stream()


def entity_paths(path: str | Path) -> list[str]:
    """Entity paths in a recording, in the order first written (with or without footer)."""
    seen: dict[str, None] = {}
    for chunk in _chunks(path):
        seen.setdefault(str(chunk.entity_path))
    return list(seen)


def read_series(path: str | Path, entity: str) -> tuple[np.ndarray, np.ndarray]:
    """(t, values) of an entity, sorted by time: t in s, values (N,) or (N, k) floats.

    Reads the chunks directly (works also without a footer, e.g. after a kill).
    """
    import pyarrow as pa
    import pyarrow.compute as pc
    entity = '/' + entity.strip('/')
    times, values = [], []
    for chunk in _chunks(path):
        if str(chunk.entity_path) != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if TIMELINE not in names:
            continue
        data_name = next(n for n in names if n.endswith((':scalars', ':positions')))
        t = batch.column(TIMELINE).cast(pa.int64()).to_numpy() / 1e9
        col = batch.column(data_name)
        flat = pc.list_flatten(col)
        if data_name.endswith(':positions'):
            flat = pc.list_flatten(flat)
        arr = np.asarray(flat.to_numpy(zero_copy_only=False), dtype=float)
        width = len(arr) // len(t) if len(t) else 1
        times.append(t)
        values.append(arr.reshape(len(t), width) if width > 1 else arr)
    if not times:
        raise KeyError(f'no time series {entity!r} in {path}')
    t = np.concatenate(times)
    v = np.concatenate(values)
    order = np.argsort(t, kind='stable')
    return t[order], v[order]


def read_component(path: str | Path, entity: str, column: str,
                   timeline: str = TIMELINE) -> tuple[np.ndarray, list]:
    """(t, rows) of one component of an entity, sorted by time on ``timeline`` (s).

    ``column`` as Rerun names it, e.g. ``'Transform3D:quaternion'`` or
    ``'LineStrips3D:strips'``; each row is that sample's value as a float array (text
    components: the strings).
    """
    import pyarrow as pa
    entity = '/' + entity.strip('/')
    times: list = []
    rows: list = []
    for chunk in _chunks(path):
        if str(chunk.entity_path) != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        if timeline not in batch.schema.names or column not in batch.schema.names:
            continue
        times.append(batch.column(timeline).cast(pa.int64()).to_numpy() / 1e9)
        for value in batch.column(column).to_pylist():
            rows.append(value if value and isinstance(value[0], str)
                        else np.asarray(value, dtype=float))
    if not times:
        raise KeyError(f'no {column!r} of {entity!r} on {timeline!r} in {path}')
    t = np.concatenate(times)
    order = np.argsort(t, kind='stable')
    return t[order], [rows[i] for i in order]
