"""Linux network namespaces, so an emulated drone and djitellopy can share one computer.

The clash: djitellopy 2.5 binds UDP ``("", 8889)`` and ``("", 8890)`` (every address)
without ``SO_REUSEADDR``, and a Tello answers on port 8889 of its own address. Linux
refuses to bind a specific address on a port that a wildcard socket without
``SO_REUSEADDR`` holds, and the reverse, so no socket option on the emulator's side
helps: binding ``127.0.0.2:8889`` with ``SO_REUSEADDR``, ``SO_REUSEPORT`` (or both, or
``SO_BINDTODEVICE``, or as an IPv4-mapped IPv6 address), before or after djitellopy,
fails with ``EADDRINUSE`` every time.

The fix: the emulator gets a network stack of its own — a network namespace — joined to
the client's by a virtual Ethernet pair, as a real drone is joined by Wi-Fi. Inside its
namespace it binds ``0.0.0.0:8889`` like the firmware and talks from its own address;
djitellopy, unmodified, only gets ``host=`` that address. Nothing is configured on the
host beyond one interface, which is removed with the emulator (and by the kernel with
the namespace, should the process die).

How: a namespace is made by ``unshare(CLONE_NEWNET)`` in a short-lived thread and kept
alive by a file descriptor; :meth:`NetNamespace.call` runs a function in a thread that
has entered it (``setns``), and sockets and child processes made there belong to it for
good. The link is made with iproute2's ``ip`` (Debian package ``iproute2``). Creating
namespaces needs ``CAP_SYS_ADMIN`` and ``CAP_NET_ADMIN``: root, or a user namespace
(``unshare -rn``) in which the client runs too.
"""

from __future__ import annotations

import ctypes
import fcntl
import ipaddress
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from functools import cache
from typing import TypeVar

from quadnav.errors import QuadnavError

#: ``unshare``/``setns`` flag of the network namespace.
_CLONE_NEWNET = 0x40000000
#: ``ioctl`` that opens the network namespace of a socket (Linux 4.9+).
_SIOCGSKNS = 0x894C
#: Seconds a new link may take to carry datagrams, and to wait for each probe.
LINK_TIMEOUT = 5.0
_PROBE_WAIT = 0.02
_T = TypeVar("_T")


@cache
def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def _check(result: int, what: str) -> None:
    if result != 0:
        errno = ctypes.get_errno()
        raise OSError(errno, f"{what}: {os.strerror(errno)}")


def _own_namespace_fd() -> int:
    """A new descriptor of the calling thread's network namespace."""
    return os.open(f"/proc/self/task/{threading.get_native_id()}/ns/net", os.O_RDONLY)


def _in_thread(function: Callable[[], _T]) -> _T:
    """Run ``function`` in a new thread and return its result (or raise its error)."""
    outcome: dict[str, object] = {}

    def run() -> None:
        try:
            outcome["value"] = function()
        except BaseException as error:  # re-raised in the caller
            outcome["error"] = error

    thread = threading.Thread(target=run, name="quadnav-netns")
    thread.start()
    thread.join()
    if "error" in outcome:
        raise outcome["error"]  # type: ignore[misc]
    return outcome["value"]  # type: ignore[return-value]


class NetNamespace:
    """A Linux network namespace, alive while this object is open (or a socket in it).

    Make a fresh one with :meth:`create` (only a down loopback inside until set up), or
    refer to the caller's own with :meth:`current`.
    """

    def __init__(self, fd: int) -> None:
        self._fd = fd

    @classmethod
    def create(cls) -> NetNamespace:
        """A new, empty network namespace with its loopback up.

        Raises:
            QuadnavError: the system does not allow it (see :func:`unavailable_reason`).
        """
        reason = unavailable_reason()
        if reason:
            raise QuadnavError(reason)

        def make() -> int:
            _check(_libc().unshare(_CLONE_NEWNET), "unshare(CLONE_NEWNET)")
            return _own_namespace_fd()

        namespace = cls(_in_thread(make))
        namespace.ip("link", "set", "lo", "up")
        return namespace

    @classmethod
    def current(cls) -> NetNamespace:
        """The calling thread's network namespace."""
        return cls(_own_namespace_fd())

    @classmethod
    def of_socket(cls, sock: socket.socket) -> NetNamespace:
        """The network namespace ``sock`` belongs to (``SIOCGSKNS``)."""
        return cls(fcntl.ioctl(sock.fileno(), _SIOCGSKNS))

    @property
    def fd(self) -> int:
        """The open descriptor that keeps the namespace alive."""
        return self._fd

    def call(self, function: Callable[[], _T]) -> _T:
        """``function()`` run in a thread inside this namespace: sockets it makes (and
        threads and processes it starts) live in this namespace."""
        def entered() -> _T:
            _check(_libc().setns(self._fd, _CLONE_NEWNET), "setns")
            return function()
        return _in_thread(entered)

    def ip(self, *args: str, other: NetNamespace | None = None) -> None:
        """Run ``ip ARGS`` inside this namespace; ``other``'s namespace can be named in
        ARGS as :meth:`path_for_ip`. Raises QuadnavError with ip's message on failure."""
        fds = (other.fd,) if other is not None else ()
        result = self.call(lambda: subprocess.run(
            ["ip", *args], capture_output=True, text=True, pass_fds=fds, check=False))
        if result.returncode != 0:
            raise QuadnavError(f"ip {' '.join(args)}: {result.stderr.strip()}")

    def path_for_ip(self) -> str:
        """How an ``ip`` run by :meth:`ip` with ``other=self`` names this namespace."""
        return f"/proc/self/fd/{self._fd}"

    def close(self) -> None:
        """Let go of the namespace (the kernel removes it once nothing else uses it)."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> NetNamespace:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def unavailable_reason() -> str | None:
    """Why network namespaces cannot be made here, or None when they can."""
    if not sys.platform.startswith("linux"):
        return "the Tello emulator needs Linux network namespaces"
    if shutil.which("ip") is None:
        return "the Tello emulator needs the 'ip' command (Debian/Ubuntu package iproute2)"
    return _probe()


@cache
def _probe() -> str | None:
    """Try once to make a namespace: None if that works, else why not."""
    def make() -> None:
        _check(_libc().unshare(_CLONE_NEWNET), "unshare(CLONE_NEWNET)")
    try:
        _in_thread(make)
    except OSError as error:
        return (f"the Tello emulator cannot create a network namespace ({error.strerror}); "
                "run as root, or inside a user namespace: unshare -rn")
    return None


def peer_address(host: str) -> str:
    """The client's address on a link to the drone at ``host``: the other address of
    ``host``'s /31 pair (its last bit flipped)."""
    return str(ipaddress.IPv4Address(int(ipaddress.IPv4Address(host)) ^ 1))


class Link:
    """A virtual Ethernet pair from the client's namespace to the drone's.

    The drone's end is ``tello0`` with address ``host``; the client's end is named after
    ``host`` (``qt`` and its 8 hex digits) with :func:`peer_address`; each end routes
    only the other's address (point to point), so nothing else on the client changes.
    """

    DRONE_INTERFACE = "tello0"

    def __init__(self, client: NetNamespace, drone: NetNamespace, host: str) -> None:
        self.host = host
        self.client_address = peer_address(host)
        self.interface = f"qt{int(ipaddress.IPv4Address(host)):08x}"
        self._client = client
        try:
            client.ip("link", "add", self.interface, "type", "veth", "peer", "name",
                      self.DRONE_INTERFACE, "netns", drone.path_for_ip(), other=drone)
        except QuadnavError as error:
            raise QuadnavError(f"cannot link the emulated drone at {host}: {error} "
                               "(is another emulator using this address?)") from None
        try:
            client.ip("addr", "add", self.client_address, "peer", f"{host}/32",
                      "dev", self.interface)
            client.ip("link", "set", self.interface, "up")
            drone.ip("addr", "add", host, "peer", f"{self.client_address}/32",
                     "dev", self.DRONE_INTERFACE)
            drone.ip("link", "set", self.DRONE_INTERFACE, "up")
            self._wait_until_carrying(client, drone)
        except QuadnavError:
            self.close()
            raise

    def _wait_until_carrying(self, client: NetNamespace, drone: NetNamespace) -> None:
        """Return once a datagram has crossed the link both ways. The kernel starts a
        new link's queues a moment after it is up (asynchronously, later on a busy
        machine) and drops what is sent before."""
        ends = [ns.call(lambda: socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
                for ns in (client, drone)]
        with ends[0] as near, ends[1] as far:
            near.bind((self.client_address, 0))
            far.bind((self.host, 0))
            near.settimeout(_PROBE_WAIT)
            far.settimeout(_PROBE_WAIT)
            deadline = time.monotonic() + LINK_TIMEOUT
            while time.monotonic() < deadline:
                try:
                    near.sendto(b"ping", far.getsockname())
                    _, source = far.recvfrom(16)
                    far.sendto(b"pong", source)
                    near.recvfrom(16)
                    return
                except TimeoutError:
                    continue
        raise QuadnavError(f"the link to the emulated drone at {self.host} carried nothing "
                           f"for {LINK_TIMEOUT:g} s")

    def close(self) -> None:
        """Remove the pair (both ends go together)."""
        if self._client is not None:
            try:
                self._client.ip("link", "del", self.interface)
            finally:
                self._client = None
