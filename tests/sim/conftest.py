"""Helpers for the simulated-robot tests: an in-process robot and a plain-socket desk."""

from __future__ import annotations

import pytest

from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot

from .desk import SocketDesk as Desk
from .desk import wait_until

__all__ = ["Desk", "wait_until"]


@pytest.fixture
def robot():
    cfg = SimConfig(video=False, seed=3)
    r = SimRobot(cfg)
    r.start()
    yield r
    r.close()


@pytest.fixture
def desk_factory(robot):
    desks: list[Desk] = []

    def make(**kw) -> Desk:
        d = Desk(*robot.address, **kw)
        desks.append(d)
        return d

    yield make
    for d in desks:
        d.close()


@pytest.fixture
def climber():
    """The wall climber on the small test wall (test_climber_link.small_setup), in process."""
    from sim_robot.climber.sim import ClimberSim

    from .test_climber_link import TIME_SCALE, small_setup

    sim = ClimberSim(SimConfig(video=False, seed=2, time_scale=TIME_SCALE), small_setup())
    sim.start()
    yield sim
    sim.close()
