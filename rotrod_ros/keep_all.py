"""Publishing where a KEEP_ALL subscriber that falls behind holds the publisher up.

On a topic with reliable KEEP_ALL history on both sides (:func:`rotrod_ros.interfaces.qos`),
rmw blocks a publication while a subscriber's history is full (rmw_fastrtps: 100 ms), then
fails. :meth:`KeepAllPublishing.send` then either waits for the subscriber, publishing
again for as long as asked (nothing is lost), or drops the publication and counts it;
:meth:`KeepAllPublishing.flush` waits at the end for the subscribers to acknowledge what
was published.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from rclpy._rclpy_pybind11 import RCLError
from rclpy.duration import Duration
from rclpy.impl.rcutils_logger import RcutilsLogger
from rclpy.publisher import Publisher


class KeepAllPublishing:
    """Publications a KEEP_ALL subscriber may hold up: waited for or dropped, counted.

    Args:
        publishers: the node's publishers by topic name.
        logger: the node's logger.
        ok: whether the node's context is up (an error while it shuts down is raised).
        running: whether the publisher's source is still running. Once it is not, waits
            go on for ``stop_grace`` wall seconds in all, so that the sample being
            published when the source is stopped is published whole, then end.
        stop_grace: see ``running``, s.
        phase: where in the period of :meth:`look` this publisher's looks fall, as a
            fraction of it in [0, 1): the rods of a world look at different instants
            (a hundred rods' looks together cost a publication ~3 ms).
    """

    def __init__(self, publishers: Mapping[str, Publisher], logger: RcutilsLogger,
                 ok: Callable[[], bool], running: Callable[[], bool],
                 stop_grace: float = 0.0, phase: float = 0.0) -> None:
        if not 0.0 <= phase < 1.0:
            raise ValueError(f'phase must be in [0, 1), got {phase!r}')
        self._publishers = publishers
        self._phase = phase
        self._logger = logger
        self._ok = ok
        self._running = running
        self._stop_grace = stop_grace
        self._stop_deadline: float | None = None
        self._subscribed: dict[str, bool] = {}
        self._next_look = 0.0
        self.held_up = 0
        """Publications a KEEP_ALL subscriber held up (rmw blocked them, then failed)."""
        self.dropped = 0
        """Publications a KEEP_ALL subscriber held up beyond rmw's blocking time and
        not waited for (dropped rather than delay the clock)."""

    def send(self, name: str, msg: Any, wait: bool) -> None:
        """Publish ``msg`` on ``name``; if a KEEP_ALL subscriber holds it up, wait or drop.

        ``wait``: publish again until it goes through (while the context is up, and the
        source runs or was stopped less than ``stop_grace`` ago); otherwise the
        publication is dropped and counted.
        """
        publisher = self._publishers[name]
        try:
            publisher.publish(msg)
            return
        except RCLError:
            if not self._ok():
                raise
        self.held_up += 1
        while wait and self._ok() and self._may_wait():
            self._logger.info(f'{name}: a KEEP_ALL subscriber is behind; waiting for it',
                              throttle_duration_sec=5.0)
            try:
                publisher.publish(msg)
                return
            except RCLError:
                pass
        self.dropped += 1
        self._logger.warning(f'{name}: a KEEP_ALL subscriber is behind: '
                             f'{self.dropped} publications dropped so far',
                             throttle_duration_sec=1.0)

    def subscribed(self, name: str) -> bool:
        """Whether ``name`` had a subscriber at the last :meth:`look` (DDS's matched count).

        A sample topic nobody subscribes to is neither built nor sent, as Gazebo's lazy
        sensors and image_transport do: publishing into no subscriber still costs
        rclpy and DDS about 10 us a message, which a world of rods pays four times per
        rod per sample.
        """
        return self._subscribed.get(name, True)

    def look(self, names: Iterable[str], every: float) -> None:
        """Read the subscriber counts of ``names`` if ``every`` wall seconds went by.

        ``every`` 0: now. Reading one costs ~2 us; a subscriber that
        matches meanwhile gets the publications from the next look on. The first look
        is at once, the second ``phase`` of a period late, so that publishers made
        together look apart.
        """
        now = time.monotonic()
        if every and now < self._next_look:
            return
        self._next_look = now + every * (1.0 + (self._phase if not self._subscribed else 0.0))
        self._subscribed = {n: self._publishers[n].get_subscription_count() > 0
                            for n in names}

    def _may_wait(self) -> bool:
        """Whether the source runs, or was stopped less than ``stop_grace`` s ago."""
        if self._running():
            return True
        if self._stop_deadline is None:
            self._stop_deadline = time.monotonic() + self._stop_grace
        return time.monotonic() < self._stop_deadline

    def flush(self, names: Iterable[str], timeout: float) -> None:
        """Wait for the subscribers of ``names`` to acknowledge every publication.

        Up to ``timeout`` wall seconds in all (rmw sends acknowledgement requests
        periodically); a warning names each topic not acknowledged in time. Nothing if
        the context is down.
        """
        if not self._ok():
            return
        deadline = time.monotonic() + timeout
        for name in names:
            left = max(0.0, deadline - time.monotonic())
            if not self._publishers[name].wait_for_all_acked(Duration(seconds=left)):
                self._logger.warning(f'{name}: not every publication acknowledged '
                                     f'within {timeout:g} s')
