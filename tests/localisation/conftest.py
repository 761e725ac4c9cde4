"""The real lidar logs live in shared/carmen beside the repository (../shared)."""

from pathlib import Path

import pytest

CARMEN = Path(__file__).resolve().parents[2].parent / "shared" / "carmen"
FREIBURG = CARMEN / "freiburg-101-corrected.log.gz"


@pytest.fixture(scope="session")
def freiburg_path() -> Path:
    if not FREIBURG.exists():
        pytest.skip(f"the shared lidar logs are not beside the repository ({CARMEN})")
    return FREIBURG


@pytest.fixture(scope="session")
def freiburg(freiburg_path):
    from app.core.localisation.carmen import read_log

    return read_log(freiburg_path)


EDMONTON = CARMEN / "edmonton-corrected.log.gz"


@pytest.fixture(scope="session")
def edmonton():
    from app.core.localisation.carmen import read_log

    if not EDMONTON.exists():
        pytest.skip(f"the shared lidar logs are not beside the repository ({CARMEN})")
    return read_log(EDMONTON)
