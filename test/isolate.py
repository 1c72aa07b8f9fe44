"""Run a command with ROS 2 / DDS traffic confined to this machine.

Usage::

    python test/isolate.py CMD [ARGS...]

``run.sh test`` calls it as ``.venv/bin/python test/isolate.py .venv/bin/python -m pytest ...``.

What it does:

1. Unless it is already inside the namespace it created (``ROTROD_NETNS=1``), it re-executes
   itself through ``unshare --net`` (as root) or ``unshare -rn`` (otherwise: a user namespace
   mapping the caller to root, which owns the new network namespace). The new namespace has
   only a loopback interface, so no DDS packet can leave the machine whatever the DDS
   configuration says.
2. Inside, it brings ``lo`` up with an ``ioctl`` (``SIOCGIFFLAGS``/``SIOCSIFFLAGS``), so
   iproute2 is not needed; ``ip link set lo up`` is only a fallback.
3. If the kernel or container does not permit ``unshare``, it prints one line to stderr and
   runs the command directly; the tests then rely on ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``
   (set here and again by ``test/conftest.py``) and a per-run ``ROS_DOMAIN_ID``.

In every case ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` is exported, and
``ROTROD_ISOLATION`` is set to ``netns`` or ``localhost`` so tests and the pytest header can
say which protection applies. The command replaces this process (``exec``), so its exit status
(including death by a signal) is exactly the exit status seen by the caller. Exit status 127
means CMD was not found, 126 that it could not be executed, 70 that the namespace was
created but its loopback could not be brought up.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import socket
import struct
import subprocess
import sys

ENV_INSIDE = 'ROTROD_NETNS'
ENV_MODE = 'ROTROD_ISOLATION'

# <linux/sockios.h>, <net/if.h>
SIOCGIFFLAGS = 0x8913
SIOCSIFFLAGS = 0x8914
IFF_UP = 0x1
IFNAMSIZ = 16
IFREQ_SIZE = 40  # sizeof(struct ifreq) on 64-bit Linux; larger than needed on 32-bit


def _say(msg: str) -> None:
    print(f'isolate.py: {msg}', file=sys.stderr, flush=True)


def _unshare_argv() -> list[str] | None:
    """Return the ``unshare`` prefix for a private network namespace, or None."""
    exe = shutil.which('unshare')
    if exe is None:
        return None
    if os.geteuid() == 0:
        return [exe, '--net']
    return [exe, '--map-root-user', '--net']


def _unshare_works(prefix: list[str]) -> tuple[bool, str]:
    """Check that ``unshare`` is permitted here (a failure of CMD must not look like one)."""
    try:
        proc = subprocess.run(
            [*prefix, '--', 'true'], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE, text=True, timeout=20, check=False)
    except (OSError, subprocess.SubprocessError) as exc:
        return False, str(exc)
    return proc.returncode == 0, proc.stderr.strip()


def _loopback_up_ioctl() -> None:
    """Set IFF_UP on ``lo`` through SIOCGIFFLAGS/SIOCSIFFLAGS (raises OSError on failure)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        req = struct.pack(f'{IFNAMSIZ}sH', b'lo', 0).ljust(IFREQ_SIZE, b'\0')
        res = fcntl.ioctl(sock.fileno(), SIOCGIFFLAGS, req)
        flags = struct.unpack_from('H', res, IFNAMSIZ)[0]
        if flags & IFF_UP:
            return
        req = struct.pack(f'{IFNAMSIZ}sH', b'lo', flags | IFF_UP).ljust(IFREQ_SIZE, b'\0')
        fcntl.ioctl(sock.fileno(), SIOCSIFFLAGS, req)


def _loopback_is_up() -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        req = struct.pack(f'{IFNAMSIZ}sH', b'lo', 0).ljust(IFREQ_SIZE, b'\0')
        res = fcntl.ioctl(sock.fileno(), SIOCGIFFLAGS, req)
        return bool(struct.unpack_from('H', res, IFNAMSIZ)[0] & IFF_UP)


def _bring_loopback_up() -> bool:
    try:
        _loopback_up_ioctl()
    except OSError as exc:
        ip = shutil.which('ip') or next(
            (p for p in ('/usr/sbin/ip', '/sbin/ip') if os.access(p, os.X_OK)), None)
        if ip is None:
            _say(f'cannot bring lo up: ioctl failed ({exc}) and iproute2 is not installed')
            return False
        proc = subprocess.run([ip, 'link', 'set', 'lo', 'up'], check=False)
        if proc.returncode != 0:
            _say(f'cannot bring lo up: ioctl failed ({exc}), `ip link set lo up` failed')
            return False
    try:
        return _loopback_is_up()
    except OSError as exc:
        _say(f'cannot read the flags of lo: {exc}')
        return False


def _only_loopback() -> bool:
    """Whether this network namespace has no interface but ``lo``."""
    try:
        return [name for _, name in socket.if_nameindex()] == ['lo']
    except OSError:
        return False


def _exec(cmd: list[str], env: dict[str, str]) -> None:
    """Replace this process by CMD (never returns)."""
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        os.execvpe(cmd[0], cmd, env)
    except FileNotFoundError:
        _say(f'command not found: {cmd[0]}')
        os._exit(127)
    except OSError as exc:
        _say(f'cannot execute {cmd[0]}: {exc}')
        os._exit(126)


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ('-h', '--help'):
        print(__doc__.strip().splitlines()[0], file=sys.stderr)
        print('usage: python test/isolate.py CMD [ARGS...]', file=sys.stderr)
        return 2
    env = dict(os.environ)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'

    if env.get(ENV_INSIDE) == '1' and _only_loopback():
        # Second stage, inside the new network namespace (an inherited or stray
        # ROTROD_NETNS=1 in a namespace with other interfaces does not count).
        if not _bring_loopback_up():
            return 70
        env[ENV_MODE] = 'netns'
        _exec(argv, env)

    prefix = _unshare_argv()
    if prefix is None:
        ok, why = False, '`unshare` (util-linux) is not installed'
    else:
        ok, why = _unshare_works(prefix)
    if ok:
        env[ENV_INSIDE] = '1'
        _exec([*prefix, '--', sys.executable, os.path.abspath(__file__), *argv], env)

    _say('private network namespace unavailable (%s); ROS tests rely on '
         'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and a per-run ROS_DOMAIN_ID'
         % (why.splitlines()[-1] if why else 'unshare failed'))
    env[ENV_MODE] = 'localhost'
    env.pop(ENV_INSIDE, None)
    _exec(argv, env)
    return 1  # not reached


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
