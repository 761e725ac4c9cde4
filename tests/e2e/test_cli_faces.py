"""The desk's command-line faces say what happened (issue 12, C)."""

import socket
import subprocess
import sys

from app.cli import main, probe_robot


def _closed_port() -> int:
    s = socket.create_server(("127.0.0.1", 0))  # a free port ...
    port = s.getsockname()[1]
    s.close()  # ... that nothing listens on any more
    return port


def test_connect_to_a_closed_port_says_connection_refused(capsys, tmp_path):
    port = _closed_port()
    code = main(["--connect", f"127.0.0.1:{port}", "--headless", "--duration", "2",
                 "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code != 0
    assert f"cannot connect to 127.0.0.1:{port}: connection refused" in err
    assert "finished" not in err


def test_probe_says_none_when_something_listens():
    srv = socket.create_server(("127.0.0.1", 0))
    try:
        assert probe_robot("127.0.0.1", srv.getsockname()[1]) is None
    finally:
        srv.close()


def test_connect_to_a_closed_port_exits_non_zero_as_a_process(tmp_path):
    port = _closed_port()
    r = subprocess.run([sys.executable, "-m", "app.cli", "--connect", f"127.0.0.1:{port}",
                        "--headless", "--duration", "2", "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1
    assert "connection refused" in r.stderr and "finished" not in r.stdout + r.stderr
