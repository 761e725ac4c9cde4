"""The standard address space from the cache (app/interop/opcua/aspace_cache.py)."""

import asyncio
import shutil

import pytest
from asyncua import Server, ua

from app.interop.opcua import aspace_cache


async def _read(server):
    name = await server.get_node(ua.ObjectIds.Server).read_browse_name()
    state = await server.get_node(ua.ObjectIds.Server_ServerStatus_State).read_value()
    ns = await server.get_namespace_array()
    return name.Name, state, ns[0]


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A cache made by a first start (≈ 4 s: built, then written), and what it read."""
    root = tmp_path_factory.mktemp("cache")

    async def run():
        server, how = await aspace_cache.initialised(Server, root=root)
        return how, await _read(server)

    how, read = asyncio.run(run())
    return root, how, read


def _copy(made, tmp_path):
    root = made[0]
    shutil.copytree(aspace_cache.shelf_folder(root), aspace_cache.shelf_folder(tmp_path))
    return aspace_cache.shelf_folder(tmp_path)


def test_made_once_then_loaded_with_the_same_nodes(made, tmp_path):
    root, how, read = made
    assert how == "made"
    assert read == ("Server", read[1], "http://opcfoundation.org/UA/")
    folder = aspace_cache.shelf_folder(root)
    assert (folder / "complete").is_file()
    assert [p.name for p in root.iterdir()] == [folder.name]  # no temporary left

    async def run():
        server, how = await aspace_cache.initialised(Server, root=root)
        return how, await _read(server), len(server.iserver.aspace._nodes)

    how2, read2, copied = asyncio.run(run())
    assert how2 == "shelf" and read2 == read
    assert copied < 2000  # loaded lazily: not every standard node copied out of the shelf


def test_a_damaged_cache_is_rebuilt_and_made_again(made, tmp_path, caplog):
    folder = _copy(made, tmp_path)
    for p in folder.iterdir():
        if p.name != "complete":
            p.write_bytes(b"not a shelf")

    async def run():
        server, how = await aspace_cache.initialised(Server, root=tmp_path)
        return how, await _read(server)

    how, read = asyncio.run(run())
    assert how == "made" and read == made[2]
    assert "could not be loaded" in caplog.text
    assert (folder / "complete").is_file() and (folder / "aspace").read_bytes() != b"not a shelf"


def test_off_or_unwritable_builds_as_before(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache folder would go")

    async def run():
        server, how = await aspace_cache.initialised(Server, root=blocked)
        return how, await _read(server)

    how, read = asyncio.run(run())
    assert how == "built" and read[0] == "Server"
    assert aspace_cache.shelf_folder(blocked).parent == blocked


def test_a_shelf_loaded_twice_at_once_by_two_starts(made):
    async def run():  # two servers in one loop: both read the one shelf
        a, b = await asyncio.gather(aspace_cache.initialised(Server, root=made[0]),
                                    aspace_cache.initialised(Server, root=made[0]))
        return a[1], b[1], await _read(a[0]), await _read(b[0])

    how_a, how_b, read_a, read_b = asyncio.run(run())
    assert how_a == how_b == "shelf" and read_a == read_b == made[2]
