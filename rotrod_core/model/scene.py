"""The drawn scene: disk, spoke, rod, mass and trail as plain shapes (no ROS import).

The live node's ``markers`` (``rotrod_ros.messages.markers``) and the bag writer
(:mod:`rotrod_core.reporting.bag`) turn the same shapes into visualization_msgs/Marker,
so both draw alike. Positions in m, in the frame the markers are stamped with (the
inertial ``world``); colours RGBA in 0..1.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    import numpy as np

DISK_THICKNESS = 0.01
"""Thickness of the drawn disk, m; its top face is at z = 0, where the rod stands."""
SPOKE_WIDTH = 0.004
"""Width of the line from the axis to the disk's rim through the rod's root, m."""
MIN_ROD_WIDTH = 0.002
"""Narrowest drawn rod, m (a 0.1 mm wire would be invisible)."""
TRAIL_WIDTH = 0.002
"""Width of the tip's trail, m."""

DISK_COLOR = (0.6, 0.6, 0.65, 1.0)
SPOKE_COLOR = (0.15, 0.15, 0.2, 1.0)
ROD_COLOR = (0.2, 0.4, 0.9, 1.0)
MASS_COLOR = (0.9, 0.3, 0.1, 1.0)
TRAIL_COLOR = (0.9, 0.6, 0.1, 0.8)
TRAIL_ID = 4
"""The trail's shape id (its points recur from one frame to the next)."""


class Shape(NamedTuple):
    """One marker's content (its header and namespace are the caller's)."""

    id: int
    kind: str
    """Marker type by name: 'cylinder', 'line_list', 'line_strip' or 'sphere'
    (visualization_msgs/Marker's constant of that name in upper case)."""
    position: tuple
    """Pose position (x, y, z), m (the orientation is the identity)."""
    scale: tuple
    """(x, y, z), m: diameters of a cylinder or sphere (z: a cylinder's height); x is
    the line width of a line."""
    color: tuple
    """(r, g, b, a) in 0..1."""
    points: tuple = ()
    """Vertices ((x, y, z), ...) of a line, m."""


def _xyz(p) -> tuple:
    return float(p[0]), float(p[1]), float(p[2])


def scene(*, disk_radius: float, theta: float, rod: Sequence[Sequence[float]] | np.ndarray,
          rod_diameter: float, mass_radius: float,
          trail: Iterable[Sequence[float]]) -> list:
    """The shapes of one frame: disk, spoke, rod, mass and (from two points on) trail.

    ``disk_radius`` m, ``theta`` the hub angle rad (the spoke turns with it), ``rod``
    the drawn centreline from root to tip (m), ``rod_diameter`` m, ``mass_radius`` m,
    ``trail`` the recent drawn tip positions (m).
    """
    d = 2.0 * float(disk_radius)
    shapes = [
        Shape(0, 'cylinder', (0.0, 0.0, -0.5 * DISK_THICKNESS), (d, d, DISK_THICKNESS),
              DISK_COLOR),
        Shape(1, 'line_list', (0.0, 0.0, 0.0), (SPOKE_WIDTH, 0.0, 0.0), SPOKE_COLOR,
              ((0.0, 0.0, 0.001), (disk_radius * math.cos(theta),
                                   disk_radius * math.sin(theta), 0.001))),
        Shape(2, 'line_strip', (0.0, 0.0, 0.0), (max(float(rod_diameter), MIN_ROD_WIDTH),
                                                 0.0, 0.0),
              ROD_COLOR, tuple(_xyz(p) for p in rod)),
        Shape(3, 'sphere', _xyz(rod[-1]), (2.0 * mass_radius,) * 3, MASS_COLOR),
    ]
    trail = tuple(_xyz(p) for p in trail)
    if len(trail) >= 2:
        shapes.append(Shape(TRAIL_ID, 'line_strip', (0.0, 0.0, 0.0), (TRAIL_WIDTH, 0.0, 0.0),
                            TRAIL_COLOR, trail))
    return shapes
