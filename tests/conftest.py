import contextlib
import glob
import hashlib
import os
import tempfile

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _station_key_in_tmp(tmp_path_factory, monkeypatch):
    """Every test signs and checks commands with a station key of its own,
    never the one in the user's config folder."""
    d = tmp_path_factory.mktemp("station-key")
    monkeypatch.setenv("STATION_PATROL_KEY_FILE", str(d / "station.key"))


@pytest.fixture(autouse=True, scope="session")
def _data_dir_in_tmp(tmp_path_factory):
    """No test writes the archive, routes, profiles, logs, caches or the desk's settings
    (QSettings, under $XDG_CONFIG_HOME on Linux) into the user's folders."""
    from app.core.paths import CACHE_ENV, DATA_ENV, LOG_ENV

    folder = tmp_path_factory.mktemp("station-patrol-data")
    old = {k: os.environ.get(k) for k in (CACHE_ENV, DATA_ENV, LOG_ENV, "XDG_CONFIG_HOME")}
    # the cache (e.g. the OPC UA servers' standard address space) is the run's, one for
    # both xdist workers: made by the first server that starts, loaded by the others
    base = tmp_path_factory.getbasetemp()
    os.environ[CACHE_ENV] = str((base.parent if os.environ.get("PYTEST_XDIST_WORKER")
                                 else base) / "station-patrol-cache")
    os.environ[DATA_ENV] = str(folder)
    os.environ[LOG_ENV] = str(folder / "log")
    os.environ["XDG_CONFIG_HOME"] = str(folder / "config")
    yield folder
    for k, v in old.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.fixture(autouse=True)
def _desk_logging_undone():
    """A test that starts the desk installs its console and file log handlers on the
    root logger; they go with the test (and so does their folder), so later threads
    do not write into other tests' output and a later test's log folder is its own."""
    from app.logs import stop_logging

    yield
    stop_logging()


@pytest.fixture(autouse=True)
def _qt_objects_die_on_the_main_thread(request):
    """Once a test process has a Qt application, Python's garbage collector runs on the
    main thread only (app/gui_gc, as in the desk): a window, desk session or plot
    item a test left in a reference cycle is deleted there, never by a collection
    that the archive writer or a pool job happened to start (deleting its timers off
    the GUI thread crashed the event loop). After each test: its pool jobs are done,
    and what is due is collected, here, between tests."""
    from PySide6.QtCore import QCoreApplication, QThreadPool

    from app.gui_gc import collect_on_gui_thread

    if QCoreApplication.instance() is None and {"qtbot", "qapp"} & set(request.fixturenames):
        request.getfixturevalue("qapp")
    collector = None
    if QCoreApplication.instance() is not None:
        collector = collect_on_gui_thread()
    yield
    if collector is None and QCoreApplication.instance() is not None:
        collector = collect_on_gui_thread()  # the test made the application itself
    if collector is not None:
        QThreadPool.globalInstance().waitForDone(10000)
        collector.collect_due()


# Tests that start a simulated robot (in this process or as a sim_robot process):
# they name one of these, use one of these fixtures, or are marked e2e.
ROBOT_STARTERS = ("SimRobot", "SimRobotProcess", "FwsSim")
ROBOT_FIXTURES = ("robot", "sim_robot", "desk_factory")
# wall seconds the compile may take (over 300 s on a fresh clone at load 13 here)
COMPILE_TIMEOUT_S = float(os.environ.get("STATION_PATROL_COMPILE_TIMEOUT_S", "1800"))
# The skid-steer robot's, then the 4WS robot's (its any-angle planner's, also the stages
# a long path across the station reaches): ≈ 35 + 27 s of CPU here from an empty cache.
_COMPILE = """
import numpy as np
from app.core.localisation.ekf import OdometryEkf
OdometryEkf(track_m=0.3).advance(0.05, 0.01, 0.012, 0.01)  # the EKF's kernels
from sim_robot.config import SimConfig
from sim_robot.fws_robot import FwsSim
from sim_robot.sim import SimRobot
robot = SimRobot(SimConfig(video=False))  # builds the localiser (its kernels)
try:
    robot.relay.nav.warm_up()  # the planner's kernels, as a start does (raising here)
finally:
    robot.close()
robot = FwsSim(SimConfig(video=False))
try:
    robot.relay.nav.warm_up()
    fws = robot.relay.fws_nav
    free = np.argwhere(~fws.inflated.blocked)
    rng = np.random.default_rng(0)
    for _ in range(6):
        a, b = free[rng.integers(len(free), size=2)]
        fws.plan(fws.grid.cell_to_world(*a), fws.grid.cell_to_world(*b))
finally:
    robot.close()
"""
# The coverage planner's kernels (tests of the planner and of the climber), compiled
# the same way: ≈ 55 s of CPU from an empty cache here, several minutes at load 10.
_COMPILE_COVERAGE = """
import numpy as np
from app.core.planner import coverage_path
rng = np.random.default_rng(0)
for density in (0.0, 0.15, 0.3):
    blocked = rng.random((24, 30)) < density
    blocked[0, 0] = False
    coverage_path(blocked, (0, 0))
"""
COVERAGE_TESTS = ("coverage", "climber")  # in a test module's name
_compiled: dict[str, str | None] = {}  # why a compile failed, by fixture (None: it did not)


def pytest_collection_modifyitems(items):
    """Every test that starts a robot asks for :func:`robot_kernels` first."""
    for item in items:
        module = getattr(item, "module", None)
        if any(hasattr(module, name) for name in ROBOT_STARTERS) or \
                set(ROBOT_FIXTURES) & set(getattr(item, "fixturenames", ())) or \
                item.get_closest_marker("e2e") is not None:
            item.fixturenames.insert(0, "robot_kernels")
        if any(part in getattr(module, "__name__", "") for part in COVERAGE_TESTS):
            item.fixturenames.insert(0, "coverage_kernels")
    _slow_modules_first(items)


def _slow_modules_first(items):
    """Whole modules, the dearest first: those marked ``slow(seconds)`` by
    their cost, then the rest by their number of tests (pytest-xdist's own
    order, turned off in the Makefile by --no-loadscope-reorder, which put
    modules of one or two long tests last, so one worker ran them alone at
    the end while the other was idle). Each worker runs this alike, so they
    all collect the same order."""
    modules: dict[str, list] = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::", 1)[0], []).append(item)

    def cost(group):
        mark = group[0].get_closest_marker("slow")
        return (-(mark.args[0] if mark else 0), -len(group))

    items[:] = [item for group in sorted(modules.values(), key=cost) for item in group]


def pytest_collection_finish(session):
    """Before the first test, when any test starts a robot: compile (or load) the
    patrol robot's kernels — localisation and planner — in a process of its own.

    In a fresh clone the first robot compiles them (over 100 s of wall time on a
    loaded machine: the desk soak's robot took 111 s to start; over 300 s here
    at load 13), which ate the robot's start timeout or the whole test's
    timeout, in whichever test came first. numba keeps them in its cache beside
    the sources, so the robots the tests start, in this process or in their own,
    load them. Done here, outside any test, so the per-test timeout does not
    count it; a compile that fails fails every test that starts a robot."""
    if session.config.option.collectonly:
        return
    sets = (("robot_kernels", _COMPILE), ("coverage_kernels", _COMPILE_COVERAGE))
    jobs = [(f, s) for f, s in sets
            if any(f in getattr(i, "fixturenames", ()) for i in session.items)]
    # pytest-xdist's workers start with different sets (gw1 with the second), each set
    # under a lock the workers share: the two sets compile side by side, one per core
    # (they were compiled twice, both cores at once, ≈ 50 s), and a worker that reaches a
    # set another one holds waits for it, then reads its outcome from the file left
    # beside the lock (loading it again in a process of its own took 6-9 s)
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    k = int(worker[2:]) % len(jobs) if worker[2:].isdigit() and jobs else 0
    run = getattr(session.config, "workerinput", {}).get("testrunuid")
    for fixture, script in jobs[k:] + jobs[:k]:
        with _shared_lock(session, fixture) as lock_path:
            done = f"{lock_path}.{run}.done" if lock_path and run else None
            if done and os.path.exists(done):
                with open(done, encoding="utf-8") as fh:
                    _compiled[fixture] = fh.read() or None
                continue
            _compiled[fixture] = _compile(script)
            if done:
                for old in glob.glob(f"{glob.escape(lock_path)}.*.done"):  # earlier runs'
                    with contextlib.suppress(OSError):
                        os.remove(old)
                with open(done, "w", encoding="utf-8") as fh:
                    fh.write(_compiled[fixture] or "")


@contextlib.contextmanager
def _shared_lock(session, name: str):
    """An exclusive lock on a file of this run's root, held across the workers; yields
    the lock file's path (None where fcntl is missing: each worker then compiles
    alone, as before)."""
    try:
        import fcntl
    except ImportError:
        yield None
        return
    root = session.config.rootpath
    digest = hashlib.sha1(str(root).encode()).hexdigest()[:12]
    path = os.path.join(tempfile.gettempdir(), f"station-patrol-{name}-{digest}.lock")
    with open(path, "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield path
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _compile(script: str) -> str | None:
    """Run ``script`` in a process of its own; why it failed, or None."""
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory(prefix="kernels-") as tmp:
        # the robot writes no key or map into the user's folders
        env = {**os.environ, "STATION_PATROL_KEY_FILE": os.path.join(tmp, "station.key"),
               "STATION_PATROL_DATA_DIR": tmp, "XDG_CONFIG_HOME": tmp}
        try:
            out = subprocess.run([sys.executable, "-c", script], capture_output=True,
                                 text=True, timeout=COMPILE_TIMEOUT_S, env=env,
                                 cwd=os.path.dirname(os.path.dirname(__file__)))
        except subprocess.TimeoutExpired:
            return f"not done within {COMPILE_TIMEOUT_S:.0f} s"
    return None if out.returncode == 0 else f"exit {out.returncode}:\n{out.stderr[-3000:]}"


@pytest.fixture(scope="session")
def robot_kernels():
    """The robot's kernels are compiled (see :func:`pytest_collection_finish`)."""
    error = _compiled.get("robot_kernels")
    if error:
        pytest.fail(f"the simulated robot's kernels did not compile: {error}")


@pytest.fixture(scope="session")
def coverage_kernels():
    """The coverage planner's kernels are compiled (see :func:`pytest_collection_finish`)."""
    error = _compiled.get("coverage_kernels")
    if error:
        pytest.fail(f"the coverage planner's kernels did not compile: {error}")
