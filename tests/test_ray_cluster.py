"""``--ray`` on a real Ray cluster on this machine, set up as current Ray sets one up: a
head with token authentication on and a second node, each a ``ray start`` of its own
(tests/raycluster.py; one cluster for the module). A client without the cluster's token
gets one line at once, saying so; with it, a batch runs across both nodes and gives the
table of the missions flown one by one here, row for row, also when Ray workers are killed
mid-batch."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from batchtools import (
    MISSIONS,
    assert_killer_table,
    rows_one_by_one,
    write_killer_spec,
    write_spec,
)
from clitools import assert_user_error
from raycluster import client_environment, ray_cluster

from quadnav.batch.table import read_rows, same_row

ray = pytest.importorskip("ray", reason="Ray is an optional extra: pip install 'quadnav[ray]'")
pytest.importorskip("ray._private.authentication",
                    reason="a Ray without token authentication (before 2.52)")
#: One cluster for the whole file: its tests run on one xdist worker (--dist loadgroup).
pytestmark = pytest.mark.xdist_group("ray-cluster")

#: Seconds a quadnav command may take here before the test gives up on it.
COMMAND_TIMEOUT = 300


@pytest.fixture(scope="module")
def cluster() -> Iterator[tuple[str, str, Path]]:
    """The head's address, the cluster's token and the folder of the nodes."""
    with ray_cluster(nodes=2) as started:
        yield started


def quadnav(home: Path, *args: str | Path, **ray_variables: str
            ) -> subprocess.CompletedProcess:
    """``python -m quadnav args`` as a client whose HOME is ``home`` (no token file), with
    ``ray_variables`` (RAY_AUTH_MODE, RAY_AUTH_TOKEN) its only ``RAY_AUTH_*``."""
    return subprocess.run([sys.executable, "-m", "quadnav", *map(str, args)],
                          env=client_environment(home, **ray_variables), capture_output=True,
                          text=True, timeout=COMMAND_TIMEOUT)


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
    address = cluster[0]
    result = quadnav(tmp_path, "batch", "empty", "--seeds", "1", "--ray", address, "-o",
                     tmp_path / "out", **ray_variables)

    assert_user_error(result, f"--ray {address}: {problem}", "RAY_AUTH_TOKEN",
                      "~/.ray/auth_token", "RAY_AUTH_TOKEN_PATH", "ray get-auth-token")
    assert not (tmp_path / "out").exists()


def test_a_batch_across_two_nodes_gives_the_table_of_the_missions_flown_here(
        cluster, tmp_path):
    address, token, folder = cluster
    spec = write_spec(tmp_path / "spec")

    result = quadnav(tmp_path, "batch", spec, "--ray", address, "--quiet", "-o",
                     tmp_path / "out", RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=token)

    assert result.returncode == 0, result.stderr
    assert f"flying {MISSIONS} on 2 CPUs of the Ray cluster at {address} x 1 numba thread" \
        in result.stdout
    rows = read_rows(tmp_path / "out" / "results.csv")
    assert len(rows) == MISSIONS
    assert all(same_row(a, b) for a, b in zip(rows, rows_one_by_one(spec), strict=True))
    # each node's workers name every task they ran in their log (Ray's own marker)
    marker = ray._private.ray_constants.LOG_PREFIX_TASK_NAME + "_ray_job"
    ran = {node: sum(log.read_text().splitlines().count(marker)
                     for log in (folder / node).glob("ray/session_latest/logs/worker-*.out"))
           for node in ("head", "node1")}
    assert ran["head"] >= 1 and ran["node1"] >= 1, ran
    assert sum(ran.values()) == MISSIONS


def test_a_killed_worker_of_the_cluster_loses_no_mission_and_one_killed_every_time_is_given_up(
        cluster, tmp_path):
    address, token, _ = cluster
    spec = write_killer_spec(tmp_path / "spec")

    result = quadnav(tmp_path, "batch", spec, "--ray", address, "--quiet", "-o",
                     tmp_path / "out", RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=token)

    assert result.returncode == 0, result.stderr
    assert "; 2 flown again after the worker process flying them died" in result.stdout
    assert_killer_table(spec, tmp_path / "out",
                        "its worker process died 3 times (WorkerCrashedError); given up")


def test_each_ray_task_runs_numba_on_one_thread(cluster, tmp_path):
    address, token, _ = cluster
    script = ("from batchtools import numba_threads_in_worker\n"
              "from quadnav.batch.executor import open_executor\n"
              f"with open_executor(None, ray=True, address={address!r}) as executor:\n"
              "    print(sorted(set(dict(executor.map_unordered(numba_threads_in_worker, "
              "range(4))).values())))\n")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env=client_environment(tmp_path, RAY_AUTH_MODE="token",
                                                   RAY_AUTH_TOKEN=token),
                            timeout=COMMAND_TIMEOUT)

    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[1]"
