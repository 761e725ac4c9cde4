"""The OPC UA server's own process: it ends with the desk (stopped, or the desk's
process killed), a port in use is said in words, its log records reach the desk's
loggers, and the pipe between them batches and tells when the other side has gone."""

from __future__ import annotations

import asyncio
import logging
import multiprocessing
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from test_server import client, users  # noqa: F401 - fixtures and helpers of the server tests
from waits import wait_until  # tests/ is on the path

from app.config import OpcuaSettings
from app.core.desk.pipeline import DeskPipeline
from app.interop.opcua.server import OpcUaDeskServer
from app.interop.opcua.wire import Sender, read_batches

pytestmark = pytest.mark.slow(18)

ROOT = Path(__file__).resolve().parents[2]


def alive(pid: int) -> bool:
    """The process runs (a zombie waiting to be reaped has ended)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "\nState:\tZ" not in status


def test_a_port_in_use_is_said_in_words(users, tmp_path):  # noqa: F811
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    port = taken.getsockname()[1]
    try:
        server = OpcUaDeskServer(OpcuaSettings(endpoint=f"opc.tcp://127.0.0.1:{port}"),
                                 users=users, pki_dir=tmp_path / "pki")
        pipe = DeskPipeline()
        before = {k: len(v) for k, v in pipe._listeners.items()}
        server.attach(pipe)
        with pytest.raises(RuntimeError, match="the port is in use by another program"):
            server.start()
        assert server._proc is None  # the process that could not serve has ended
        # and the desk no longer feeds it
        assert {k: len(v) for k, v in pipe._listeners.items() if v or k in before} == before
    finally:
        taken.close()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_the_server_process_ends_with_the_desk(users, tmp_path, caplog):  # noqa: F811
    # stopped by the desk: its process ends, and its log records were the desk's
    pipe = DeskPipeline()
    server = OpcUaDeskServer(OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0"),
                             users=users, pki_dir=tmp_path / "pki")
    server.attach(pipe)
    with caplog.at_level(logging.INFO, logger="app.interop.opcua"):
        server.start()
    pid = server.pid
    assert pid != os.getpid() and alive(pid)
    assert any(r.name == "app.interop.opcua.core" and r.process == pid
               and "conditions made" in r.getMessage() for r in caplog.records)
    # the server's process has what it serves, not the desk's pipeline and its modules
    assert server.query("imported", module="asyncua")
    assert not server.query("imported", module="app.core.desk")
    assert not server.query("imported", module="cv2")
    server.stop()
    wait_until(lambda: not alive(pid), timeout=60.0, interval=0.05, what="the server process ended")

    # the desk's process killed: the server notices and ends too
    script = (
        "import sys\n"
        "from app.config import OpcuaSettings\n"
        "from app.core.desk.pipeline import DeskPipeline\n"
        "from app.interop.opcua.server import OpcUaDeskServer\n"
        "from app.interop.opcua.users import UserStore\n"
        "if __name__ == '__main__':\n"
        "    s = OpcUaDeskServer(OpcuaSettings(endpoint='opc.tcp://127.0.0.1:0'),\n"
        "                        users=UserStore(sys.argv[1]), pki_dir=sys.argv[2])\n"
        "    s.attach(DeskPipeline())\n"
        "    s.start()\n"
        "    print(s.pid, flush=True)\n"
        "    sys.stdin.read()\n")
    (tmp_path / "desk.py").write_text(script)
    desk = subprocess.Popen([sys.executable, str(tmp_path / "desk.py"), str(users.path),
                             str(tmp_path / "pki")], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True,
                            env=os.environ | {"PYTHONPATH": str(ROOT)})
    try:
        child = int(desk.stdout.readline())
        assert alive(child)
        desk.kill()
        desk.wait(30)
        wait_until(lambda: not alive(child), timeout=60.0, interval=0.05,
                   what="the server process ended")
    finally:
        if desk.poll() is None:
            desk.kill()


def test_the_pipe_batches_and_tells_the_end():
    r, w = multiprocessing.Pipe(duplex=False)
    got, ended = [], threading.Event()
    reader = threading.Thread(target=read_batches, args=(r, got.append, ended.set),
                              daemon=True)
    reader.start()
    sender = Sender(w, "test-out")
    for i in range(100):  # posted before the thread runs: one batch
        sender.post(("values", ({"gas_lel_pct": float(i)},), 0.0, 0.0))
    sender.start()
    sender.post(("stop",))
    sender.close()
    w.close()  # the writing side has gone: the reader says so
    assert ended.wait(10)
    flat = [m for batch in got for m in batch]
    assert [m[1][0]["gas_lel_pct"] for m in flat[:100]] == [float(i) for i in range(100)]
    assert flat[100:] == [("stop",)]
    assert len(got) == sender.batches <= 2 and sender.messages == 101
    sender2 = Sender(r, "test-broken")  # a pipe whose other end has gone: counted, no raise
    r.close()
    sender2.start().post(("stop",))
    sender2.close()
    assert sender2.broken


def test_a_stop_does_not_wait_for_asyncuas_clock():
    """asyncua's Server.stop waits for its clock task (ServerStatus' CurrentTime, written
    once a second) to wake: up to 1 s of every stop of the desk's server. The core ends
    that task at once (end_clock, before the server stops); the clock ran until then."""
    from asyncua import Server

    from app.interop.opcua import aspace_cache
    from app.interop.opcua.core import end_clock

    async def run():
        server, _ = await aspace_cache.initialised(Server)  # the run's cache
        server.set_endpoint("opc.tcp://127.0.0.1:0")
        async with server:
            task = server.iserver.time_task
            await asyncio.sleep(0)
            assert task is not None and not task.done()
            await end_clock(server)
            assert task.cancelled() and server.iserver.time_task is None
            assert server.iserver._time_task_stop
    asyncio.run(run())
