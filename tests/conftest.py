"""Shared test set-up: deterministic hypothesis, the public map corpus in ../shared/maps, and
a headless browser for the pages."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import pytest
from hypothesis import settings
from installed import main_kernels_installed

# Property tests draw the same examples on every run, so a CI result can be reproduced.
settings.register_profile("quadnav", derandomize=True, database=None)
settings.load_profile("quadnav")

# Figures are drawn off-screen, as the quadnav command draws them.
os.environ.setdefault("MPLBACKEND", "Agg")

SHARED_MAPS = Path(__file__).resolve().parents[2] / "shared" / "maps"

#: Commands that compile (or load from numba's cache) the kernels most tests share, in two
#: chains run side by side: planning, refinement and the trajectory stage; the closed loop
#: with each controller (the loop is compiled once per controller), and the step every
#: plain-Python controller flies by.
WARM_UP = (
    (("plan", "--first", "--quiet", "-o", "{tmp}/plan"),
     ("traj", "forest", "--path", "{tmp}/plan/path.csv", "-o", "{tmp}/plan")),
    (("track", "hover:duration=1", "--no-figures", "--quiet", "-o", "{tmp}/track"),
     ("track", "hover:duration=1", "--controller", "se3", "--no-figures", "--quiet", "-o",
      "{tmp}/se3"),
     ("track", "hover:duration=1", "--controller", "quadnav.cli.precompile:Follow",
      "--no-figures", "--quiet", "-o", "{tmp}/plain")),
)


def pytest_configure(config: pytest.Config) -> None:
    """Before the xdist workers start, compile the shared kernels once, on both cores.

    On a fresh install numba has nothing cached, and every worker would compile the same
    kernels for its first tests at the same time (about 40 s of CPU each). Compiled here
    once, in two processes side by side, the workers load them from the cache instead. A
    warm cache makes this a few seconds of loading. It is a speed-up only: a failure here
    is ignored, and the tests that need the kernels compile them themselves. A package
    installed from a wheel that carries them compiled (``pip install .``: setup.py) needs
    none of it."""
    if hasattr(config, "workerinput"):
        _one_numba_thread()
        return
    if not config.getoption("numprocesses", None) or main_kernels_installed():
        return
    with tempfile.TemporaryDirectory() as tmp:
        chains = [threading.Thread(target=_run_chain, args=(chain, tmp)) for chain in WARM_UP]
        for chain in chains:
            chain.start()
        for chain in chains:
            chain.join()


def _one_numba_thread() -> None:
    """Run this xdist worker's numba kernels on one thread, as a batch's workers do: three
    workers on two cores, each spinning up numba's threads for every parallel kernel, fought
    each other (a test of parallel kernels took ten times as long beside the others)."""
    import numba

    numba.set_num_threads(1)


def _run_chain(chain: tuple[tuple[str, ...], ...], tmp: str) -> None:
    """Run each ``quadnav`` command of ``chain`` in turn, output discarded."""
    for command in chain:
        subprocess.run([sys.executable, "-m", "quadnav", *(arg.format(tmp=tmp) for arg in command)],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)


@pytest.fixture
def shared_maps() -> Path:
    """The folder of real public map files beside the checkout, or skip."""
    if not SHARED_MAPS.is_dir():
        pytest.skip(f"public map corpus not found at {SHARED_MAPS}")
    return SHARED_MAPS


@pytest.fixture
def optional_shared_maps() -> Path | None:
    """The public map corpus folder, or None when it is absent (for tests that need not skip)."""
    return SHARED_MAPS if SHARED_MAPS.is_dir() else None


@pytest.fixture
def course_server(shared_maps):
    """The base URL of a loopback HTTP server of the public course maps, laid out as
    ``quadnav maps fetch`` downloads them (tests/coursemaps.py); skips without the corpus."""
    from coursemaps import course_files, serving

    with serving(course_files(shared_maps)) as url:
        yield url


@pytest.fixture
def fetched_course_maps(course_server, tmp_path, monkeypatch) -> Path:
    """Every public course map fetched from ``course_server`` into an empty cache of this
    test (``QUADNAV_CACHE_DIR``), so ``course:NAME`` reads them; returns the cache."""
    from quadnav.world.courses import CACHE_ENV, URL_ENV, catalogue
    from quadnav.world.download import fetch

    cache = tmp_path / "course-cache"
    monkeypatch.setenv(CACHE_ENV, str(cache))
    monkeypatch.setenv(URL_ENV, course_server)
    for entry in catalogue().values():
        if entry.shipped is None:
            fetch(entry)
    return cache


@pytest.fixture(scope="module")
def client_ns():
    """The network namespace holding this process's djitellopy sockets (Tello tests)."""
    import logging

    from djitellopy import Tello

    from quadnav.hardware.emulator.server import djitellopy_namespace

    Tello.LOGGER.setLevel(logging.WARNING)
    namespace = djitellopy_namespace()
    yield namespace
    namespace.close()


@pytest.fixture
def course(shared_maps):
    """The RBE595 Tello course map, its start and goal, and their planned flight
    (:func:`tellotools.planned_course`); skips without the corpus."""
    from tellotools import planned_course

    return planned_course(shared_maps)


@pytest.fixture
def registrations_forgotten():
    """The names registered during the test (by it or by an example it runs) in every
    registry of plug-ins are forgotten after it."""
    from quadnav.control import CONTROLLERS
    from quadnav.planning.registry import PLANNERS
    from quadnav.sim.wind import WINDS
    from quadnav.trajectory import METHODS
    from quadnav.trajectory.references.builtin import REFERENCES
    from quadnav.vehicle import PRESETS
    from quadnav.world.builtin import WORLDS

    registries = [(registry, set(registry.names())) for registry in
                  (PLANNERS, METHODS, REFERENCES, CONTROLLERS, WINDS, WORLDS, PRESETS)]
    yield
    for registry, names in registries:
        for name in set(registry.names()) - names:
            registry.unregister(name)


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures a test drew (pyplot keeps every open figure)."""
    yield
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close("all")


@pytest.fixture(scope="module")
def browser():
    """Headless chromium driven by selenium, logging the console; skips without them."""
    chromium, driver_path = shutil.which("chromium"), shutil.which("chromedriver")
    if not (chromium and driver_path):
        pytest.skip("needs chromium and chromedriver on PATH "
                    "(Debian: apt-get install chromium chromium-driver)")
    webdriver = pytest.importorskip("selenium.webdriver",
                                    reason="needs selenium (pip install selenium)")
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    # WebGL without a GPU: chromium's software renderer, which it runs only when asked.
    for argument in ("--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader",
                     "--disable-dev-shm-usage", "--window-size=1280,860"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=webdriver.ChromeService(executable_path=driver_path),
                              options=options)
    yield driver
    driver.quit()


#: Modules of tests that take many seconds each (a batch on a local Ray, a tuning study,
#: killed, stopped and resumed runs, the documentation's commands, the examples): they
#: start first, so that the run does not end with one worker finishing one of them while
#: the others wait.
LONG_TESTS_FIRST = ("test_batch_ray.py", "test_tune.py", "test_run_folders.py",
                    "test_batch_resume.py", "test_batch_retry.py", "test_examples.py",
                    "test_doc_commands.py", "test_flight_figures.py", "test_free_volume.py")


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Start the modules of :data:`LONG_TESTS_FIRST` first (xdist hands out the groups of
    ``xdist_group`` first, the most tests first, then single tests in this order), and make
    ``xdist_group`` marks group again: pytest-xdist 3.8 names a grouped test by
    setting ``item._nodeid`` (``...@group``), which pytest 9.2's ``nodeid`` no longer reads,
    so every group was scattered over the workers (and module fixtures such as the Ray
    cluster built on each). Carry the name over to the id pytest reads; older pytest reads
    ``_nodeid`` itself."""
    items.sort(key=lambda item: item.path.name not in LONG_TESTS_FIRST)
    try:
        from _pytest.nodeid import NodeId
    except ImportError:
        return
    for item in items:
        named = item.__dict__.get("_nodeid")
        if named is not None and named != item.nodeid:
            item._id = NodeId.parse(named)
