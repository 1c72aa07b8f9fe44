"""The main job (``rotrod demo``: simulator, profile publisher and Rerun logger) as real
processes."""

import os
import subprocess
import sys

import numpy as np
import pytest

from rotrod_core import Eq26Profile, RodParams, simulate
from rotrod_core.analysis.alignment import profile_delay
from rotrod_core.reporting import recording, viewer_screenshot
from rotrod_ros.install import executable

pytestmark = pytest.mark.ros


def verify(path) -> str:
    """``rerun rrd verify``: exit 0 and one file verified (a truncated file says 0)."""
    rerun = executable('rerun')
    out = subprocess.run([*rerun, 'rrd', 'verify', str(path)], capture_output=True,
                         text=True, timeout=60)
    text = out.stdout + out.stderr
    assert out.returncode == 0 and '1 file verified without error' in text, text
    return text


@pytest.fixture(scope='module')
def demo(tmp_path_factory):
    """``rotrod demo``: (its recording, the completed process).

    Eq. 26 goes to the simulator as one trajectory, executed on the simulator's clock:
    the machine's hiccups delay the nodes, not the profile's timing on the rod (a
    stream was re-gridded on its arrivals: on CI the hub once followed it 0.14 s after
    its first motion).
    """
    out = tmp_path_factory.mktemp('demo') / 'rotrod.rrd'
    run = subprocess.run([*executable('rotrod'), 'demo', '-o', str(out)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    return out, run


def test_the_main_job_end_to_end(demo):
    """``rotrod demo``: Eq. 26 through the three nodes; the recording is read back."""
    out, run = demo
    for stage in ('spin-up', 'hold', 'spin-down', 'rest'):
        assert stage in run.stdout
    assert f'recording: {out}' in run.stdout
    verify(out)
    paths = set(recording.entity_paths(out))
    for entity in (recording.U, recording.V, recording.OMEGA, recording.TORQUE,
                   recording.F_MODEL, recording.ROTATING_TIP, recording.INERTIAL_TIP):
        assert '/' + entity in paths
    t, w = recording.read_series(out, recording.OMEGA)
    tu, u = recording.read_series(out, recording.U)
    _, v = recording.read_series(out, recording.V)
    profile = Eq26Profile()
    shift = profile_delay(t, w, profile)
    keep = (tu - shift >= 0) & (tu - shift <= 40.0)
    tt = tu[keep] - shift
    assert tt[-1] - tt[0] > 39.5                       # the whole 40 s are recorded
    # the recording begins at most 1 s before the profile (it began up to 15 s before)
    assert 0 <= shift - min(t[0], tu[0]) <= 1.0, (shift, t[0], tu[0])
    assert 'the profile starts' in run.stdout
    offline = simulate(RodParams(), profile, 40.0, dt=1e-3)
    du = np.max(np.abs(u[keep] - np.interp(tt, offline.t, offline.u)))
    dv = np.max(np.abs(v[keep] - np.interp(tt, offline.t, offline.v)))
    # the simulator issue's tolerances (the demo's report, if they fail, in the message)
    assert du <= 0.01 * np.max(offline.u), run.stdout
    assert dv <= 0.05 * np.max(np.abs(offline.v)), run.stdout
    _, f = recording.read_series(out, recording.F_MODEL)
    assert f.shape[1] == 2
    # the estimate from the motion, stamped at the middle of its 1 s window, tracks
    # Eq. 28 there during the spin-up once the window has filled (issue 6: 2 %)
    te, fe = recording.read_series(out, recording.F_ESTIMATE)
    middle = te - shift
    spin_up = (middle >= 0.5) & (middle <= 14.5)
    w0 = RodParams().natural_frequency
    w_mid = profile.omega(middle[spin_up])
    model = np.column_stack(((w0 - w_mid) / (2 * np.pi), (w0 + w_mid) / (2 * np.pi)))
    given = np.isfinite(fe[spin_up])
    # NaN where a window is not stationary: the spin-up's own whirls are ~0.1 um (a
    # streamed w's small corrections, at delivery hiccups, started new ones: then 30 %
    # of the windows were given; the trajectory's w has none: 100 % here)
    print(f"estimates given in {given.mean():.0%} of the spin-up windows")
    assert given.mean() >= 0.2, given.mean()
    # A correction inside a window is not in the estimator's model of steady
    # whirls: its split-window check and its misfit rule for a pair drop the whirls it
    # moves (a window was once published 2.9 % off, before them; test_whirl.py keeps
    # 37 such windows)
    error = np.abs(fe[spin_up][given] / model[given] - 1)
    print(f'error of the estimates: median {np.median(error):.2%}, max {error.max():.2%}')
    assert error.max() <= 0.02
    # time zero at the profile's start: the stamp before the hub first moved, which is
    # the profile's start (found by fitting w to Eq. 26) to two samples
    tp, _ = recording.read_component(out, recording.OMEGA, 'Scalars:scalars',
                                     recording.PROFILE_TIMELINE)
    origin = float(np.median(t - tp))
    assert abs(origin - shift) <= 0.02 + 1e-9, (origin, shift)
    # the tip IMU beside it: its gyroscope's z is the hub's w turned by the rod's small
    # tilt (cos a cos b w, a, b < 0.02 rad at 3 mm: 2e-4 of w) plus the tilt's own rates
    ti, gyro = recording.read_series(out, recording.IMU_ANGULAR_VELOCITY)
    assert gyro.shape[1] == 3 and len(ti) >= 0.9 * len(t)
    w_at = dict(zip(np.round(t, 6), w))
    paired = [(w_at[k], g) for k, g in zip(np.round(ti, 6), gyro[:, 2]) if k in w_at]
    assert len(paired) >= 0.9 * len(ti)
    assert max(abs(g - wk) for wk, g in paired) <= 1e-3


def share(pixels, condition) -> float:
    """Share of the (N, 3) RGB pixels (0..1) for which condition(r, g, b) holds."""
    return float(np.mean(condition(pixels[:, 0], pixels[:, 1], pixels[:, 2])))


def orange(r, g, b):    # the mass (scene.MASS_COLOR, shaded)
    return (r > 0.6) & (g > 0.1) & (g < 0.5) & (b < 0.35)


def blue(r, g, b):      # the rod; the spin-up path
    return (b > 0.5) & (r < 0.4) & (b - r > 0.3)


def light_grey(r, g, b):    # the disk (the grid is dark grey)
    low, high = np.minimum(np.minimum(r, g), b), np.maximum(np.maximum(r, g), b)
    return (low > 0.45) & (high - low < 0.12)


def red(r, g, b):       # the critical-deflection circle; the spin-down path
    return (r > 0.7) & (g < 0.45) & (b < 0.45)


def test_the_recording_opens_on_the_mechanism_and_the_whole_path(demo, tmp_path):
    """The real viewer, headless, opens the demo's recording without any user action on
    the disk, rod and mass (3D, upper left) and on the whole path in the rotating frame
    with the critical-deflection circle (2D, lower left): each panel draws more than
    its grid. In CI (CI=true) a viewer that cannot run fails the test."""
    lacking = viewer_screenshot.missing()
    if lacking:
        message = (f'the headless viewer needs {", ".join(lacking)} (apt-get install '
                   f'{" ".join(viewer_screenshot.DEBIAN_PACKAGES)})')
        if os.environ.get('CI') == 'true':
            pytest.fail(message)
        pytest.skip(message)
    import matplotlib.image
    try:
        png = viewer_screenshot.screenshot(demo[0], tmp_path / 'dashboard.png')
    except viewer_screenshot.ViewerUnavailable as exc:   # once more: a busy shared machine
        print(f'the viewer failed once: {exc}')
        png = viewer_screenshot.screenshot(demo[0], tmp_path / 'dashboard.png')
    print(f'screenshot: {png}')
    image = matplotlib.image.imread(png)[:, :, :3]
    height, width = image.shape[:2]

    def panel(x0, x1, y0, y1):
        return image[int(y0 * height):int(y1 * height),
                     int(x0 * width):int(x1 * width)].reshape(-1, 3)
    mechanism, path = panel(0.02, 0.48, 0.06, 0.48), panel(0.02, 0.48, 0.56, 0.94)
    found = {'disk': share(mechanism, light_grey), 'rod': share(mechanism, blue),
             'mass': share(mechanism, orange), 'circle': share(path, red),
             'spin-up path': share(path, blue)}
    print('share of the panel\'s pixels: ' + ', '.join(f'{k} {v:.3%}' for k, v in found.items()))
    assert found['disk'] > 0.01 and found['rod'] > 3e-4 and found['mass'] > 3e-4, found
    assert found['circle'] > 1e-3 and found['spin-up path'] > 5e-4, found


def test_demo_is_a_module_too():
    out = subprocess.run([sys.executable, '-m', 'rotrod_ros.demo', '--help'],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and '--real-time' in out.stdout
