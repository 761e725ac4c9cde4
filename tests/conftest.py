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
# wall seconds the compile may take (over 300 s on a fresh clone at load 13 here)
COMPILE_TIMEOUT_S = float(os.environ.get("STATION_PATROL_COMPILE_TIMEOUT_S", "1800"))
_COMPILE = """
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot
robot = SimRobot(SimConfig(video=False))  # builds the localiser (its kernels)
try:
    robot.relay.nav.warm_up()  # the planner's kernels, as a start does (raising here)
finally:
    robot.close()
"""
_compiled: dict[str, str | None] = {}  # "error": why the compile failed (None: it did not)


def pytest_collection_modifyitems(items):
    """Every test that starts a robot asks for :func:`robot_kernels` first."""
    for item in items:
        module = getattr(item, "module", None)
        if any(hasattr(module, name) for name in ROBOT_STARTERS) or \
                set(ROBOT_FIXTURES) & set(getattr(item, "fixturenames", ())) or \
                item.get_closest_marker("e2e") is not None:
            item.fixturenames.insert(0, "robot_kernels")


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
    if session.config.option.collectonly or not any(
            "robot_kernels" in getattr(i, "fixturenames", ()) for i in session.items):
        return
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory(prefix="robot-kernels-") as tmp:
        # the robot writes no key or map into the user's folders
        env = {**os.environ, "STATION_PATROL_KEY_FILE": os.path.join(tmp, "station.key"),
               "STATION_PATROL_DATA_DIR": tmp, "XDG_CONFIG_HOME": tmp}
        try:
            out = subprocess.run([sys.executable, "-c", _COMPILE], capture_output=True,
                                 text=True, timeout=COMPILE_TIMEOUT_S, env=env,
                                 cwd=os.path.dirname(os.path.dirname(__file__)))
        except subprocess.TimeoutExpired:
            _compiled["error"] = f"not done within {COMPILE_TIMEOUT_S:.0f} s"
            return
    _compiled["error"] = None if out.returncode == 0 else \
        f"exit {out.returncode}:\n{out.stderr[-3000:]}"


@pytest.fixture(scope="session")
def robot_kernels():
    """The robot's kernels are compiled (see :func:`pytest_collection_finish`)."""
    error = _compiled.get("error")
    if error:
        pytest.fail(f"the simulated robot's kernels did not compile: {error}")
