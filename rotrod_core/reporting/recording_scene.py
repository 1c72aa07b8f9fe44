"""The mechanism and the rotating-frame view of a Rerun recording (static parts, columns).

The 3D scene draws what the RViz markers draw (:mod:`rotrod_core.model.scene`: the
same colours, the rod's centreline of :func:`rotrod_core.model.geometry.rod_shapes`
and the same ``deflection_scale``), as Rerun entities, SI units (m, rad):

    mechanism/axis              the rotation axis (static)
    mechanism/hub               Transform3D per sample: rotation by the hub angle theta
                                about z (the rotating frame: x radial through the rod's
                                root, y tangential)
    mechanism/hub/disk          the disk (static)
    mechanism/hub/spoke         a line from the axis through the rod's root (static)
    mechanism/hub/rod           the rod's centreline per sample, deflection drawn
                                ``deflection_scale`` times
    mechanism/hub/mass          the mass (a static sphere), Transform3D per sample: the
                                drawn tip
    mechanism/trail             the drawn tip in the inertial frame per sample (the view
                                shows the last TRAIL_SECONDS)

The rotating-frame view (the paper's Figs. 4-8) holds the critical-deflection circle
and the axes (static), ``rotating/path/<stage>`` (the tip's (u, v) per sample, one
entity and colour per stage) and ``rotating/tip`` (the latest point).

Only the per-sample parts are sent per batch, as columns (:func:`pose_columns`).
rerun is imported by the caller and passed in, so this module needs no rerun-sdk.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrod_core.analysis.run_events import STAGES
from rotrod_core.model import scene
from rotrod_core.model.geometry import rod_shapes, sphere_radius
from rotrod_core.model.params import RodParams

MECHANISM = 'mechanism'
AXIS, HUB, DISK = 'mechanism/axis', 'mechanism/hub', 'mechanism/hub/disk'
SPOKE = 'mechanism/hub/spoke'
ROD, MASS, TRAIL = 'mechanism/hub/rod', 'mechanism/hub/mass', 'mechanism/trail'
ROTATING = 'rotating'
LIMIT_CIRCLE, ROTATING_AXES = 'rotating/critical_deflection', 'rotating/axes'
PATH = 'rotating/path'
ROTATING_TIP = 'rotating/tip'
ROD_POINTS = 12
"""Points of the drawn centreline (as the markers')."""
TRAIL_SECONDS = 5.0
"""The 3D view shows the tip's path over this many seconds before the time cursor."""
CIRCLE_POINTS = 181

STAGE_COLORS = {'rest': (127, 127, 127), 'spin-up': (31, 119, 180), 'hold': (44, 160, 44),
                'spin-down': (214, 39, 40)}
"""RGB of each stage's path."""
COLOR_NAMES = {'rest': 'grey', 'spin-up': 'blue', 'hold': 'green', 'spin-down': 'red'}


def path_entity(stage: str) -> str:
    """The entity of the tip's rotating-frame path during ``stage``."""
    return f'{PATH}/{stage.replace("-", "_")}'


def _rgb(color) -> list[int]:
    return [int(round(255 * c)) for c in color[:3]]


@dataclass(frozen=True)
class Mechanism:
    """What the recording draws with: the rod's geometry and the drawing's settings (SI)."""

    eccentricity: float = 0.1
    """r0, m: radius of the rod's root on the disk."""
    rod_length: float = 0.3
    """l, m."""
    rod_diameter: float = 0.003
    """d, m (drawn at least scene.MIN_ROD_WIDTH wide)."""
    mass_radius: float = sphere_radius(0.3)
    """Radius of the drawn mass, m (a steel sphere of the tip mass)."""
    disk_radius: float = 0.15
    """Radius of the drawn disk, m (the simulator's disk_radius)."""
    deflection_scale: float = 20.0
    """Drawn deflection / true deflection (the simulator's marker_deflection_scale)."""
    deflection_limit: float = 0.003
    """The critical deflection, m (the simulator's deflection_limit; 0: none)."""

    @classmethod
    def from_params(cls, params: RodParams, **settings) -> Mechanism:
        """The mechanism of ``params`` (a single rod), with the drawing ``settings``."""
        return cls(eccentricity=float(params.eccentricity),
                   rod_length=float(params.rod_length),
                   rod_diameter=float(params.rod_diameter),
                   mass_radius=sphere_radius(float(params.mass)), **settings)

    def __post_init__(self):
        for name in ('eccentricity', 'rod_length', 'rod_diameter', 'mass_radius',
                     'disk_radius', 'deflection_scale', 'deflection_limit'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f'{name} must be a finite number >= 0, got {value!r}')
        if not self.rod_length > 0 or not self.deflection_scale > 0:
            raise ValueError('rod_length and deflection_scale must be > 0')

    def shapes(self, u, v) -> np.ndarray:
        """The drawn rod in the rotating frame for each (u, v): (N, ROD_POINTS, 3) m."""
        return rod_shapes(u, v, eccentricity=self.eccentricity, rod_length=self.rod_length,
                          points=ROD_POINTS, scale=self.deflection_scale)


def log_static(rec, rr, mech: Mechanism) -> None:
    """Log the parts that never change, and the styles of the per-sample parts.

    The axis, disk, spoke, the mass's sphere, the critical-deflection circle and the
    rotating frame's axes.
    """
    top = 1.15 * mech.rod_length
    rec.log(AXIS, rr.LineStrips3D([[[0.0, 0.0, -0.05], [0.0, 0.0, top]]],
                                  radii=0.5 * scene.SPOKE_WIDTH,
                                  colors=[_rgb(scene.SPOKE_COLOR)]), static=True)
    rec.log(DISK, rr.Cylinders3D(lengths=[scene.DISK_THICKNESS], radii=[mech.disk_radius],
                                 centers=[[0.0, 0.0, -0.5 * scene.DISK_THICKNESS]],
                                 colors=[_rgb(scene.DISK_COLOR)], fill_mode='solid'),
            static=True)
    rec.log(SPOKE, rr.LineStrips3D([[[0.0, 0.0, 0.002], [mech.disk_radius, 0.0, 0.002]]],
                                   radii=scene.SPOKE_WIDTH, colors=[_rgb(scene.SPOKE_COLOR)]),
            static=True)
    rec.log(ROD, rr.LineStrips3D.from_fields(
        radii=0.5 * max(mech.rod_diameter, scene.MIN_ROD_WIDTH),
        colors=[_rgb(scene.ROD_COLOR)]), static=True)
    rec.log(MASS, rr.Ellipsoids3D(half_sizes=[[mech.mass_radius] * 3],
                                  colors=[_rgb(scene.MASS_COLOR)], fill_mode='solid'),
            static=True)
    rec.log(TRAIL, rr.Points3D.from_fields(radii=-1.5, colors=[_rgb(scene.TRAIL_COLOR)]),
            static=True)
    reach = 1.1 * max(mech.deflection_limit, 1e-3)
    rec.log(ROTATING_AXES, rr.LineStrips2D(
        [[[-reach, 0.0], [reach, 0.0]], [[0.0, -reach], [0.0, reach]]], radii=-0.5,
        colors=[[110, 110, 110]]), rr.Points2D(
        [[reach, 0.0], [0.0, reach]], radii=0.0, colors=[[160, 160, 160]],
        labels=['u, radial', 'v, tangential']), static=True)
    if mech.deflection_limit > 0:
        a = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS)
        circle = mech.deflection_limit * np.column_stack((np.cos(a), np.sin(a)))
        corner = mech.deflection_limit * np.sqrt(0.5)
        rec.log(LIMIT_CIRCLE, rr.LineStrips2D([circle], radii=-1.0, colors=[[230, 80, 80]]),
                rr.Points2D([[-corner, -corner]], radii=0.0, colors=[[230, 80, 80]],
                            labels=[f'critical deflection {1e3 * mech.deflection_limit:g} mm '
                                    '(deflection_limit)']), static=True)
    # the 2D view draws y downwards (images); v is drawn upwards, as in the paper
    for entity in (ROTATING_TIP, LIMIT_CIRCLE, ROTATING_AXES,
                   *(path_entity(stage) for stage in STAGES)):
        rec.log(entity, rr.Transform3D(scale=[1.0, -1.0, 1.0]), static=True)
    rec.log(MECHANISM, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for stage in STAGES:
        rec.log(path_entity(stage), rr.Points2D.from_fields(
            radii=-1.5, colors=[STAGE_COLORS[stage]]), static=True)


def pose_columns(rr, mech: Mechanism, theta, u, v) -> dict[str, object]:
    """The per-sample 3D parts: entity -> columns for ``send_columns``.

    For samples of hub angle ``theta`` (rad) and true tip deflection (u, v) (m).
    """
    theta = np.asarray(theta, dtype=float)
    n = len(theta)
    half = 0.5 * theta
    quaternions = np.column_stack((np.zeros(n), np.zeros(n), np.sin(half), np.cos(half)))
    shapes = mech.shapes(u, v)
    tips = shapes[:, -1, :]
    c, s = np.cos(theta), np.sin(theta)
    trail = np.column_stack((tips[:, 0] * c - tips[:, 1] * s, tips[:, 0] * s + tips[:, 1] * c,
                             tips[:, 2]))
    return {
        HUB: rr.Transform3D.columns(quaternion=quaternions),
        ROD: rr.LineStrips3D.columns(strips=shapes.astype(np.float32)),
        MASS: rr.Transform3D.columns(translation=tips),
        TRAIL: rr.Points3D.columns(positions=trail).partition(np.ones(n, dtype=np.int32)),
    }
