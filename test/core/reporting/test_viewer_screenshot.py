"""The headless viewer's screenshot: what it needs, and how it says what is missing.

The screenshot itself, of the demo's recording, is taken in
test/acceptance/test_main_job.py."""

import pytest

from rotrod_core.reporting import viewer_screenshot
from rotrod_core.reporting.viewer_screenshot import ViewerUnavailable, screenshot


def test_without_xvfb_it_names_the_debian_packages(monkeypatch, tmp_path):
    real = viewer_screenshot.shutil.which
    monkeypatch.setattr(viewer_screenshot.shutil, 'which',
                        lambda name: None if name == 'Xvfb' else real(name))
    assert 'xvfb' in viewer_screenshot.missing()
    with pytest.raises(ViewerUnavailable, match='apt-get install xvfb mesa-vulkan-drivers'):
        screenshot(tmp_path / 'x.rrd', tmp_path / 'x.png')


def test_a_missing_recording_is_refused_before_anything_starts(tmp_path):
    if viewer_screenshot.missing():
        pytest.skip(f'no headless viewer here: {viewer_screenshot.missing()}')
    with pytest.raises(FileNotFoundError):
        screenshot(tmp_path / 'nothing.rrd', tmp_path / 'x.png')
    assert not (tmp_path / 'x.png').exists()
