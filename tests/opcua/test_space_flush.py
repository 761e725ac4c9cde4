"""How the address space writes the desk's values: staged, then written together by
``flush`` (the latest of several values once), a repeated value and quality not
written again before ``refresh_s``, a changed quality written at once; and the
DataValues written are the ones the server keeps (asyncua's per-item copy is the
value itself). An asyncua Server in this process, initialised but not listening."""

from __future__ import annotations

import asyncio
import copy
import math

from asyncua import Server, ua

from app.interop.opcua import aspace_cache
from app.interop.opcua.space import GOOD, NO_COMM, DeskSpace

T0 = 1_800_000_000.0
KEY = "Environment.temp_c"


async def _space(refresh_s: float) -> tuple[Server, DeskSpace]:
    server, _ = await aspace_cache.initialised(Server)  # the run's cached standard nodes
    space = DeskSpace(server, refresh_s=refresh_s)
    await space.build()
    return server, space


async def _value(server: Server, space: DeskSpace, key: str) -> ua.DataValue:
    return server.read_attribute_value(space.items[key].node.nodeid)


def test_staged_values_written_once_each_flush():
    async def main():
        server, sp = await _space(refresh_s=60.0)
        before = await _value(server, sp, KEY)
        sp.set(KEY, 20.0, T0)
        sp.set(KEY, 21.0, T0 + 0.1)
        assert (await _value(server, sp, KEY)).StatusCode == before.StatusCode  # staged
        writes = sp.writes
        assert await sp.flush() == 1
        dv = await _value(server, sp, KEY)
        assert dv.Value.Value == 21.0 and dv.StatusCode.is_good()
        assert dv.SourceTimestamp.timestamp() == T0 + 0.1
        assert copy.deepcopy(dv) is dv  # never changed once written: its copy is itself
        # the same value and quality again: not written before refresh_s
        sp.set(KEY, 21.0, T0 + 0.2)
        assert await sp.flush() == 0 and sp.writes == writes + 1
        assert (await _value(server, sp, KEY)).SourceTimestamp.timestamp() == T0 + 0.1
        # a new quality is written at once, with the kept value's timestamp
        sp.set_quality("telemetry", NO_COMM)
        assert await sp.flush() == 1
        dv = await _value(server, sp, KEY)
        assert dv.StatusCode.value == NO_COMM and dv.Value.Value is None
        sp.set_quality("telemetry", GOOD)
        await sp.flush()
        dv = await _value(server, sp, KEY)
        assert dv.Value.Value == 21.0 and dv.SourceTimestamp.timestamp() == T0 + 0.2
    asyncio.run(main())


def test_repeated_value_refreshed_after_refresh_s():
    async def main():
        server, sp = await _space(refresh_s=0.0)
        sp.set(KEY, 5.0, T0)
        await sp.flush()
        sp.set(KEY, 5.0, T0 + 1.0)
        assert await sp.flush() == 1
        assert (await _value(server, sp, KEY)).SourceTimestamp.timestamp() == T0 + 1.0
        # NaN (no reading) repeated is the same value, not a change
        sp.refresh_s = 60.0
        sp.set(KEY, math.nan, T0 + 2.0)
        assert await sp.flush() == 1
        sp.set(KEY, math.nan, T0 + 3.0)
        assert await sp.flush() == 0
    asyncio.run(main())
