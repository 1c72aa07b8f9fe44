"""The Rerun viewer's own screenshot of a recording, headless (no ROS import).

``rerun --screenshot-to`` opens the recording in the real viewer, lets it load, saves
what the window shows and quits. Headless, it draws into a virtual X display (Xvfb)
with Mesa's software Vulkan (llvmpipe): on Debian the packages ``xvfb`` and
``mesa-vulkan-drivers`` (:data:`DEBIAN_PACKAGES`). It needs a private
``XDG_RUNTIME_DIR`` (without one it creates no window). This module starts its own
Xvfb on a free display number, runs the viewer with private XDG directories in which
its analytics are off, in a private network namespace where the kernel permits one
(else bound to 127.0.0.1), and stops both.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DEBIAN_PACKAGES = ('xvfb', 'mesa-vulkan-drivers')
"""What the headless viewer needs on Debian (apt-get install --no-install-recommends)."""
WINDOW = (1600, 1000)
"""The viewer's window, logical points (the screenshot has twice as many pixels)."""
SCREEN_HEIGHT = 40
"""Height of the virtual screen, px. The pointer starts at the screen's centre; on so
low a screen that is the viewer's top bar, so no hover tooltip covers a view."""
VULKAN_DRIVER = Path('/usr/share/vulkan/icd.d')
TIMEOUT = 150.0
"""Longest wait for the viewer's screenshot, s."""


class ViewerUnavailable(RuntimeError):
    """The viewer cannot run here (what is missing, or its output)."""


def missing() -> list[str]:
    """What the headless viewer lacks here: Debian packages and executables (empty: none)."""
    out = []
    if shutil.which('Xvfb') is None:
        out.append('xvfb')
    if not any(VULKAN_DRIVER.glob('lvp_icd*.json')):
        out.append('mesa-vulkan-drivers')
    if rerun_executable() is None:
        out.append('rerun (pip install rerun-sdk)')
    return out


def rerun_executable() -> str | None:
    """The ``rerun`` of this Python's environment (rerun-sdk's), else the one on PATH."""
    here = Path(sys.executable).parent / 'rerun'
    return str(here) if here.exists() else shutil.which('rerun')


def _free_display() -> int:
    for n in range(90, 400):
        if not (Path(f'/tmp/.X{n}-lock').exists() or Path(f'/tmp/.X11-unix/X{n}').exists()):
            return n
    raise ViewerUnavailable('no free X display number in 90..399')


def _no_network_prefix() -> list[str]:
    """``unshare`` into a network namespace with only loopback down, where permitted."""
    exe = shutil.which('unshare')
    if exe is None:
        return []
    prefix = [exe, '--net'] if os.geteuid() == 0 else [exe, '--map-root-user', '--net']
    ok = subprocess.run([*prefix, 'true'], capture_output=True, timeout=20).returncode == 0
    return prefix if ok else []


def _start_xvfb(workdir: Path, width: int) -> tuple[subprocess.Popen, int]:
    for _ in range(5):
        n = _free_display()
        log = open(workdir / f'xvfb{n}.log', 'w')
        proc = subprocess.Popen(['Xvfb', f':{n}', '-screen', '0', f'{width}x{SCREEN_HEIGHT}x24',
                                 '-nolisten', 'tcp'], stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)
        log.close()
        deadline = time.monotonic() + 10.0
        while proc.poll() is None and time.monotonic() < deadline:
            if Path(f'/tmp/.X11-unix/X{n}').exists():
                return proc, n
            time.sleep(0.05)
        if proc.poll() is None:
            _stop(proc)
    raise ViewerUnavailable('Xvfb did not start: '
                            + (workdir / f'xvfb{n}.log').read_text(errors='replace')[-2000:])


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def screenshot(recording: str | Path, png: str | Path, *, window: tuple = WINDOW,
               timeout: float = TIMEOUT) -> Path:
    """Open ``recording`` in the Rerun viewer headless and save its screenshot to ``png``.

    Raises :class:`ViewerUnavailable` when the tools are missing or the viewer fails.
    """
    lacking = missing()
    if lacking:
        raise ViewerUnavailable(f'the headless viewer needs: {", ".join(lacking)} (Debian: '
                                f'apt-get install {" ".join(DEBIAN_PACKAGES)})')
    recording, png = Path(recording).resolve(), Path(png).resolve()
    if not recording.is_file():
        raise FileNotFoundError(recording)
    png.parent.mkdir(parents=True, exist_ok=True)
    if png.exists():
        png.unlink()
    work = Path(tempfile.mkdtemp(prefix='rotrod-viewer-'))
    xvfb = None
    try:
        runtime = work / 'runtime'
        runtime.mkdir(mode=0o700)
        config = work / 'config'
        (config / 'rerun').mkdir(parents=True)
        (config / 'rerun' / 'analytics.json').write_text(json.dumps(
            {'analytics_id': '00000000000000000000000000000000', 'analytics_enabled': False,
             'metadata': {}}))
        xvfb, display = _start_xvfb(work, window[0])
        env = {**os.environ, 'DISPLAY': f':{display}', 'XDG_RUNTIME_DIR': str(runtime),
               'XDG_CONFIG_HOME': str(config), 'XDG_DATA_HOME': str(work / 'data'),
               'XDG_CACHE_HOME': str(work / 'cache')}
        env.pop('WAYLAND_DISPLAY', None)
        cmd = [*_no_network_prefix(), str(rerun_executable()), '--new', '--bind', '127.0.0.1',
               '--window-size', f'{window[0]}x{window[1]}', '--screenshot-to', str(png),
               str(recording)]
        try:
            out = subprocess.run(cmd, env=env, cwd=work, capture_output=True, text=True,
                                 timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            raise ViewerUnavailable(f'the viewer took over {timeout:g} s: '
                                    f'{str(exc.stderr or "")[-2000:]}') from None
        if out.returncode != 0 or not png.is_file():
            raise ViewerUnavailable(f'the viewer failed (exit {out.returncode}): '
                                    f'{(out.stdout + out.stderr)[-3000:]}')
        return png
    finally:
        if xvfb is not None:
            _stop(xvfb)
        shutil.rmtree(work, ignore_errors=True)


def compact(png: str | Path) -> Path:
    """Shrink a screenshot for the documentation, in place.

    Half its pixels each way (the viewer saves at twice its window's size) and a
    256-colour palette: a tenth of the bytes, for docs/figures (kept small).
    """
    from PIL import Image
    png = Path(png)
    with Image.open(png) as image:
        rgb = image.convert('RGB')
    half = rgb.resize((rgb.width // 2, rgb.height // 2), Image.Resampling.LANCZOS)
    half.quantize(colors=256, method=Image.Quantize.FASTOCTREE,
                  dither=Image.Dither.NONE).save(png, optimize=True)
    return png
