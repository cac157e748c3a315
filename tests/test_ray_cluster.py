"""``--ray`` on a real Ray cluster on this machine, set up as current Ray sets one up: a
head with token authentication on and a second node, each a ``ray start`` of its own
(tests/raycluster.py; one cluster for the module). A client without the cluster's token
gets one line at once, saying so; with it, a batch runs across both nodes and gives the
table of the missions flown one by one here, row for row, also when Ray workers are killed
mid-batch, or the second node while it flies a mission (it is started again after)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest
from batchtools import (
    MISSIONS,
    assert_killer_table,
    rows_one_by_one,
    write_killer_spec,
    write_spec,
    write_staller_spec,
)
from clitools import assert_user_error
from raycluster import RayCluster, RayNode, client_environment, ray_cluster

from quadnav.batch.grid import read_spec
from quadnav.batch.table import read_rows, same_row

ray = pytest.importorskip("ray", reason="Ray is an optional extra: pip install 'quadnav[ray]'")
pytest.importorskip("ray._private.authentication",
                    reason="a Ray without token authentication (before 2.52)")
#: One cluster for the whole file: its tests run on one xdist worker (--dist loadgroup).
pytestmark = pytest.mark.xdist_group("ray-cluster")

#: Seconds a quadnav command may take here before the test gives up on it.
COMMAND_TIMEOUT = 300


@pytest.fixture(scope="module")
def cluster() -> Iterator[RayCluster]:
    """A head and a second node, ``node1``."""
    with ray_cluster(nodes=2) as started:
        yield started


@pytest.fixture
def second_node(cluster) -> Iterator[RayNode]:
    """The cluster's second node, started again after the test when it killed it."""
    node = cluster.nodes["node1"]
    yield node
    if not node.running:
        node.start()


def quadnav_command(home: Path, *args: str | Path, **ray_variables: str) -> dict:
    """The arguments of :class:`subprocess.Popen` for ``python -m quadnav args`` as a client
    whose HOME is ``home`` (no token file), with ``ray_variables`` (RAY_AUTH_MODE,
    RAY_AUTH_TOKEN) its only ``RAY_AUTH_*``, its output captured as text."""
    return {"args": [sys.executable, "-m", "quadnav", *map(str, args)],
            "env": client_environment(home, **ray_variables), "stdout": subprocess.PIPE,
            "stderr": subprocess.PIPE, "text": True}


def quadnav(home: Path, *args: str | Path, **ray_variables: str
            ) -> subprocess.CompletedProcess:
    """:func:`quadnav_command` run to its end."""
    return subprocess.run(**quadnav_command(home, *args, **ray_variables),
                          timeout=COMMAND_TIMEOUT)


def tasks_ran(cluster: RayCluster) -> Counter[str]:
    """The Ray tasks of quadnav's executor each node has run so far, counted in its
    workers' logs, which name every task they run (Ray's own marker)."""
    marker = ray._private.ray_constants.LOG_PREFIX_TASK_NAME + "_ray_job"
    return Counter({name: sum(log.read_text().splitlines().count(marker) for log in
                              node.folder.glob("ray/session_latest/logs/worker-*.out"))
                    for name, node in cluster.nodes.items()})


@pytest.mark.parametrize(("ray_variables", "problem"), [
    ({}, "the Ray cluster asks for an authentication token and RAY_AUTH_MODE is not token "
         "here: set RAY_AUTH_MODE=token and put the cluster's token"),
    ({"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": "0" * 64},
     "the Ray cluster refused this client's authentication token (not the cluster's): put "
     "the cluster's token"),
    ({"RAY_AUTH_MODE": "token"},
     "RAY_AUTH_MODE is token but no authentication token was found: put the cluster's token"),
], ids=["no-token", "another-token", "token-mode-without-a-token"])
def test_a_client_without_the_clusters_token_gets_one_line_saying_so(
        cluster, tmp_path, ray_variables, problem):
    address = cluster.address
    result = quadnav(tmp_path, "batch", "empty", "--seeds", "1", "--ray", address, "-o",
                     tmp_path / "out", **ray_variables)

    assert_user_error(result, f"--ray {address}: {problem}", "RAY_AUTH_TOKEN",
                      "~/.ray/auth_token", "RAY_AUTH_TOKEN_PATH", "ray get-auth-token")
    assert not (tmp_path / "out").exists()


def test_a_batch_across_two_nodes_gives_the_table_of_the_missions_flown_here(
        cluster, tmp_path):
    spec = write_spec(tmp_path / "spec")
    ran_before = tasks_ran(cluster)

    result = quadnav(tmp_path, "batch", spec, "--ray", cluster.address, "--quiet", "-o",
                     tmp_path / "out", RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=cluster.token)

    assert result.returncode == 0, result.stderr
    assert (f"flying {MISSIONS} on 2 CPUs of the Ray cluster at {cluster.address} x 1 "
            "numba thread") in result.stdout
    rows = read_rows(tmp_path / "out" / "results.csv")
    assert len(rows) == MISSIONS
    assert all(same_row(a, b) for a, b in zip(rows, rows_one_by_one(spec), strict=True))
    ran = tasks_ran(cluster) - ran_before  # this batch's: other tests may have run before
    assert ran["head"] >= 1 and ran["node1"] >= 1, ran
    assert ran.total() == MISSIONS


def test_a_killed_worker_of_the_cluster_loses_no_mission_and_one_killed_every_time_is_given_up(
        cluster, tmp_path):
    spec = write_killer_spec(tmp_path / "spec")

    result = quadnav(tmp_path, "batch", spec, "--ray", cluster.address, "--quiet", "-o",
                     tmp_path / "out", RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=cluster.token)

    assert result.returncode == 0, result.stderr
    assert "; 2 flown again after the worker process flying them died" in result.stdout
    assert_killer_table(spec, tmp_path / "out",
                        "its worker process died 3 times (WorkerCrashedError); given up")


def test_each_ray_task_runs_numba_on_one_thread(cluster, tmp_path):
    script = ("from batchtools import numba_threads_in_worker\n"
              "from quadnav.batch.executor import open_executor\n"
              f"with open_executor(None, ray=True, address={cluster.address!r}) as executor:\n"
              "    print(sorted(set(dict(executor.map_unordered(numba_threads_in_worker, "
              "range(4))).values())))\n")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env=client_environment(tmp_path, RAY_AUTH_MODE="token",
                                                   RAY_AUTH_TOKEN=cluster.token),
                            timeout=COMMAND_TIMEOUT)

    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[1]"


@pytest.mark.skipif(not Path("/proc").is_dir(),
                    reason="a node's processes are found in Linux's /proc")
def test_a_node_killed_while_it_flies_a_mission_loses_none_and_the_summary_counts_it(
        cluster, second_node, tmp_path):
    spec = write_staller_spec(tmp_path / "spec", "node1")
    stalled = tmp_path / "spec" / "stalled"
    batch = subprocess.Popen(**quadnav_command(
        tmp_path, "batch", spec, "--ray", cluster.address, "--quiet", "-o", tmp_path / "out",
        RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=cluster.token))
    try:
        deadline = time.monotonic() + COMMAND_TIMEOUT
        while not stalled.exists() and batch.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        # a mission stalled on node1 (in a process of it) holds the batch until node1 dies
        assert stalled.exists() and batch.poll() is None, "no mission stalled on node1"
        node, pid = stalled.read_text().split()
        assert node == "node1" and int(pid) in second_node.processes()
        cluster.kill("node1")  # returns once no process of it is left and the head knows
        stdout, stderr = batch.communicate(timeout=COMMAND_TIMEOUT)
    finally:
        batch.kill()
        batch.wait()

    assert batch.returncode == 0, stderr
    # node1's one CPU flies one mission at a time: the stalled one is the one flown again
    assert "; 1 flown again after the worker process flying it died" in stdout
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert (summary["retried"], summary["errors"], summary["complete"]) == (1, 0, True)
    rows = read_rows(tmp_path / "out" / "results.csv")
    assert [row["mission_key"] for row in rows] == [m.key for m in read_spec(spec).missions()]
    assert all(same_row(a, b) for a, b in zip(rows, rows_one_by_one(spec), strict=True))
