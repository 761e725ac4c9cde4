import os

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
    """No test writes the archive, routes, profiles, logs or the desk's settings
    (QSettings, under $XDG_CONFIG_HOME on Linux) into the user's folders."""
    from app.core.paths import DATA_ENV, LOG_ENV

    folder = tmp_path_factory.mktemp("station-patrol-data")
    old = {k: os.environ.get(k) for k in (DATA_ENV, LOG_ENV, "XDG_CONFIG_HOME")}
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


# Tests that start a simulated robot (in this process or as a sim_robot process):
# they name one of these, use one of these fixtures, or are marked e2e.
ROBOT_STARTERS = ("SimRobot", "SimRobotProcess", "FwsSim")
ROBOT_FIXTURES = ("robot", "sim_robot", "desk_factory")


@pytest.fixture(scope="session")
def robot_kernels():
    """The patrol robot's compiled kernels (localisation and planner), loaded or
    compiled once in this process before the first test that starts a robot.

    In a fresh clone the first robot compiles them (over 100 s of wall time on a
    loaded machine: the desk soak's robot took 111 s to start), which ate the
    start timeout and the first steps of whichever test came first; numba keeps
    them in its cache beside the sources, so the robots the tests start, in this
    process or in their own, load them. Nothing is skipped: a kernel that does
    not compile fails here, in the test that asked for it."""
    from sim_robot.config import SimConfig
    from sim_robot.sim import SimRobot

    robot = SimRobot(SimConfig(video=False))  # builds the localiser (its kernels)
    try:
        robot.relay.prepare()  # the planner's kernels, as a start does
    finally:
        robot.close()


def pytest_collection_modifyitems(items):
    """Every test that starts a robot asks for :func:`robot_kernels` first."""
    for item in items:
        module = getattr(item, "module", None)
        if any(hasattr(module, name) for name in ROBOT_STARTERS) or \
                set(ROBOT_FIXTURES) & set(getattr(item, "fixturenames", ())) or \
                item.get_closest_marker("e2e") is not None:
            item.fixturenames.insert(0, "robot_kernels")
