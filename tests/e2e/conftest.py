import pytest

from app.sim_process import SimRobotProcess


@pytest.fixture
def sim_robot():
    """A real sim_robot process on an ephemeral port."""
    sim = SimRobotProcess(seed=1).start()
    yield sim
    sim.stop()
