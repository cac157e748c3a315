"""A real Ray cluster on this machine for the ``--ray`` tests: a head with token
authentication on (as ``ray start --head`` sets it up where a token is found) and worker
nodes, each a ``ray start --block`` process of its own, in its own folder of a short
temporary one (Ray's socket paths must stay under 108 bytes), on ports free when asked (none
of Ray's defaults, so that another Ray on the machine is left alone).

Each node is stopped by ending its own ``ray start`` process (which stops the processes it
started), never by ``ray stop``, which would stop every Ray of the user on the machine. A
test may kill a node instead, every process of it at once with SIGKILL as when its machine
fails (:meth:`RayNode.kill`), and start it again (:meth:`RayNode.start`).
"""

from __future__ import annotations

import os
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path

#: The ``ray`` command beside this Python.
RAY = str(Path(sys.executable).with_name("ray"))
#: Seconds a node may take to start, to stop or to die.
START_TIMEOUT = 120
SRC = Path(__file__).resolve().parents[1] / "src"
TESTS = Path(__file__).resolve().parent


def free_port() -> int:
    """A TCP port nothing listens on now."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def client_environment(home: Path, **ray_variables: str) -> dict[str, str]:
    """This process's environment with ``home`` as HOME (so that no ``~/.ray/auth_token``
    of the user's is found), no ``RAY_AUTH_*`` but ``ray_variables``, and quadnav's sources
    and these tests importable."""
    environment = {key: value for key, value in os.environ.items()
                   if not key.startswith("RAY_AUTH")}
    paths = [str(SRC), str(TESTS), environment.get("PYTHONPATH", "")]
    return environment | {"HOME": str(home), "PYTHONPATH": os.pathsep.join(filter(None, paths))
                          } | ray_variables


def _node_ports() -> list[str]:
    return ["--node-manager-port", str(free_port()), "--object-manager-port", str(free_port()),
            "--dashboard-agent-grpc-port", str(free_port()),
            "--dashboard-agent-listen-port", str(free_port()),
            "--runtime-env-agent-port", str(free_port()),
            "--metrics-export-port", str(free_port())]


#: The variable that names, in the environment of a node's processes (its Ray workers'
#: too), the node's folder: ``head``, ``node1`` ...
NODE_VARIABLE = "QUADNAV_TEST_NODE"


def _running_in_session(session: int) -> list[int]:
    """The ids of the processes of ``session`` that have not ended (Linux's ``/proc``)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with suppress(OSError):  # ended meanwhile
                state = (entry / "stat").read_text().rpartition(")")[2].split()[0]
                if os.getsid(int(entry.name)) == session and state != "Z":
                    found.append(int(entry.name))
    return found


class RayNode:
    """A node of the cluster: ``ray start --block arguments`` on ports free when it starts,
    with its Ray folder ``ray`` and its log ``node.log`` in ``folder``, and
    :data:`NODE_VARIABLE` naming the folder.
    The ``ray start`` process leads a session of its own, which holds all the node's
    processes: the raylet and agents it starts, and Ray's workers (each in a process group
    of its own)."""

    def __init__(self, folder: Path, arguments: list[str], environment: dict[str, str]
                 ) -> None:
        self.folder = folder
        self.arguments = arguments
        self.environment = environment | {NODE_VARIABLE: folder.name}
        self.process: subprocess.Popen | None = None

    @property
    def running(self) -> bool:
        """Whether its ``ray start`` runs."""
        return self.process is not None and self.process.poll() is None

    def start(self) -> None:
        """Start it (again, after :meth:`kill`: in the same Ray folder, as a new node of
        the cluster), returning once it says it runs."""
        self.folder.mkdir(parents=True, exist_ok=True)
        with (self.folder / "node.log").open("a") as log:
            self.process = subprocess.Popen(
                [RAY, "start", "--block", "--disable-usage-stats", "--temp-dir",
                 str(self.folder / "ray"), *self.arguments, *_node_ports()],
                stdout=subprocess.PIPE, stderr=log, text=True, env=self.environment,
                start_new_session=True)
        assert self.process.stdout is not None
        for line in self.process.stdout:  # ends when the command fails
            if "Ray runtime started" in line:
                return
        self.stop()
        raise RuntimeError(f"ray start failed: {(self.folder / 'node.log').read_text()[-2000:]}")

    def processes(self) -> list[int]:
        """The ids of its processes running now."""
        assert self.process is not None
        return _running_in_session(self.process.pid)

    def kill(self) -> None:
        """Kill all its processes with SIGKILL, as when its machine fails (none says
        goodbye to the cluster); returns once none is left."""
        deadline = time.monotonic() + START_TIMEOUT
        while running := self.processes():
            if time.monotonic() > deadline:
                raise RuntimeError(f"the Ray node in {self.folder} outlived SIGKILL: {running}")
            for pid in running:
                with suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            time.sleep(0.1)
        self._ended()

    def stop(self) -> None:
        """Stop it by ending its ``ray start``, which stops the processes it started."""
        assert self.process is not None
        self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(START_TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)  # its own session: the node's
        self._ended()

    def _ended(self) -> None:
        """Wait for its ``ray start``, which has ended or been killed, and close its output."""
        assert self.process is not None and self.process.stdout is not None
        self.process.wait()
        self.process.stdout.close()


#: A Ray client that waits until the cluster at ``sys.argv[1]`` counts ``sys.argv[2]``
#: nodes alive.
_AWAIT_ALIVE = """\
import sys
import time

import ray

ray.init(address=sys.argv[1], logging_level="ERROR")
while sum(node["Alive"] for node in ray.nodes()) != int(sys.argv[2]):
    time.sleep(0.1)
"""
#: How often the head checks that each node is alive, ms (Ray's default, 3000, takes a
#: node for dead 15 s after it dies: 5 failed checks).
HEALTH_CHECK_PERIOD = 500


@dataclass
class RayCluster:
    """A Ray cluster of :func:`ray_cluster`.

    Attributes:
        address: the head's ``HOST:PORT``.
        token: the cluster's authentication token.
        folder: the folder of the nodes' folders.
        nodes: the nodes by their folder's name, ``head``, ``node1`` ...
    """

    address: str
    token: str
    folder: Path
    nodes: dict[str, RayNode] = field(default_factory=dict)

    @property
    def environment(self) -> dict[str, str]:
        """The environment of its nodes and of a client of it."""
        return client_environment(self.folder / "home", RAY_AUTH_MODE="token",
                                  RAY_AUTH_TOKEN=self.token,
                                  RAY_health_check_period_ms=str(HEALTH_CHECK_PERIOD))

    @contextmanager
    def node(self, name: str, arguments: list[str]) -> Iterator[RayNode]:
        """Start node ``name`` with ``arguments``; stopped on leaving."""
        node = self.nodes[name] = RayNode(self.folder / name, arguments, self.environment)
        node.start()
        try:
            yield node
        finally:
            if node.running:
                node.stop()

    def kill(self, name: str) -> None:
        """Kill node ``name`` (:meth:`RayNode.kill`); returns once the head counts it dead
        too (a node started after is then not counted twice)."""
        self.nodes[name].kill()
        subprocess.run([sys.executable, "-c", _AWAIT_ALIVE, self.address,
                        str(sum(node.running for node in self.nodes.values()))],
                       env=self.environment, capture_output=True, timeout=START_TIMEOUT,
                       check=True)


@contextmanager
def ray_cluster(nodes: int = 1) -> Iterator[RayCluster]:
    """A head of one CPU with token authentication on, and ``nodes - 1`` worker nodes of
    one CPU each (``node1`` ...)."""
    with ExitStack() as stack:
        cluster = RayCluster(
            f"127.0.0.1:{free_port()}", secrets.token_hex(32),
            Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="quadnav-ray-"))))
        stack.enter_context(cluster.node("head", [
            "--head", "--port", cluster.address.rpartition(":")[2], "--node-ip-address",
            "127.0.0.1", "--num-cpus", "1", "--include-dashboard", "false",
            "--dashboard-port", str(free_port()), "--ray-client-server-port", str(free_port())]))
        for k in range(1, nodes):
            stack.enter_context(cluster.node(f"node{k}", [
                "--address", cluster.address, "--node-ip-address", "127.0.0.1",
                "--num-cpus", "1"]))
        yield cluster
