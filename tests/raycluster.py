"""A real Ray cluster on this machine for the ``--ray`` tests: a head with token
authentication on (as ``ray start --head`` sets it up where a token is found) and worker
nodes, each a ``ray start --block`` process of its own, in its own folder of a short
temporary one (Ray's socket paths must stay under 108 bytes), on ports free when asked (none
of Ray's defaults, so that another Ray on the machine is left alone).

Each node is stopped by ending its own ``ray start`` process (which stops the processes it
started), never by ``ray stop``, which would stop every Ray of the user on the machine.
"""

from __future__ import annotations

import os
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

#: The ``ray`` command beside this Python.
RAY = str(Path(sys.executable).with_name("ray"))
#: Seconds a node may take to start.
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


@contextmanager
def _node(arguments: list[str], folder: Path, environment: dict[str, str]) -> Iterator[None]:
    """``ray start --block arguments`` until it says the node runs; stopped on leaving."""
    folder.mkdir(parents=True)
    log = (folder / "node.log").open("w")
    process = subprocess.Popen([RAY, "start", "--block", "--disable-usage-stats",
                                "--temp-dir", str(folder / "ray"), *arguments],
                               stdout=subprocess.PIPE, stderr=log, text=True,
                               env=environment, start_new_session=True)
    try:
        assert process.stdout is not None
        for line in process.stdout:  # ends when the command fails
            if "Ray runtime started" in line:
                break
        else:
            raise RuntimeError(f"ray start failed: {(folder / 'node.log').read_text()[-2000:]}")
        yield
    finally:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(START_TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)  # its own session: the node's processes
            process.wait()
        log.close()


@contextmanager
def ray_cluster(nodes: int = 1) -> Iterator[tuple[str, str, Path]]:
    """A head of one CPU with token authentication on, and ``nodes - 1`` worker nodes of
    one CPU each; yields the head's ``HOST:PORT``, the cluster's token and the folder that
    holds the nodes' folders, ``head`` and ``node1`` ... (each with Ray's ``ray`` folder)."""
    token = secrets.token_hex(32)
    address = f"127.0.0.1:{free_port()}"
    with ExitStack() as stack:
        folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="quadnav-ray-")))
        environment = client_environment(folder / "home", RAY_AUTH_MODE="token",
                                          RAY_AUTH_TOKEN=token)
        stack.enter_context(_node(
            ["--head", "--port", address.rpartition(":")[2], "--node-ip-address", "127.0.0.1",
             "--num-cpus", "1", "--include-dashboard", "false",
             "--dashboard-port", str(free_port()),
             "--ray-client-server-port", str(free_port()), *_node_ports()],
            folder / "head", environment))
        for k in range(1, nodes):
            stack.enter_context(_node(
                ["--address", address, "--node-ip-address", "127.0.0.1", "--num-cpus", "1",
                 *_node_ports()], folder / f"node{k}", environment))
        yield address, token, folder
