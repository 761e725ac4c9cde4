"""`python -m app.core.records`: the archive queried without a window."""

import csv
import io
import json
import time
from contextlib import redirect_stdout

import pytest

from app.core.records import Archive
from app.core.records.__main__ import main, parse_time

T0 = 1_700_000_000.0


@pytest.fixture
def path(tmp_path):
    p = tmp_path / "a.sqlite3"
    a = Archive(p)
    for i in range(600):
        a.add_telemetry(T0 + i, {"temp_c": 20.0 + (i % 10), "gas_lel_pct": 1.5}, seq=i)
    a.add_event(T0 + 5, "patrol_status", {"state": "driving"})
    a.add_event(T0 + 6, "link_state", {"state": "lost"})
    a.add_command(T0 + 7, "ana", "estop", {}, seq=3)
    a.ack_command(3, True, "", T0 + 7.1)
    a.close()
    return p


def run(*args):
    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(list(args))
    return code, buf.getvalue()


def test_info_check_series_events_commands(path):
    code, out = run("--archive", str(path), "info")
    assert code == 0 and "telemetry         600" in out and "gas_lel_pct, temp_c" in out
    assert run("--archive", str(path), "check") == (0, "integrity_check: ok\n")
    code, out = run("--archive", str(path), "series", "temp_c", "--points", "10")
    rows = list(csv.reader(io.StringIO(out)))
    assert rows[0] == ["time_utc", "t", "mean", "min", "max"] and len(rows) == 11
    assert {r[3] for r in rows[1:]} == {"20.0"} and {r[4] for r in rows[1:]} == {"29.0"}
    code, out = run("--archive", str(path), "events", "--kind", "link_state")
    (line,) = out.splitlines()
    assert json.loads(line)["data"] == {"state": "lost"}
    code, out = run("--archive", str(path), "commands")
    rows = list(csv.DictReader(io.StringIO(out)))
    assert rows[0]["command"] == "estop" and rows[0]["acked"] == "True"


def test_export_with_a_time_range(path, tmp_path):
    out = tmp_path / "t.csv"
    code, _ = run("--archive", str(path), "export", "--channels", "temp_c",
                  "--from", "2023-11-14T22:13:30Z", "--to", str(T0 + 19), "--out", str(out))
    rows = list(csv.reader(out.open()))
    assert code == 0 and [r[3] for r in rows[1:]] == [str(20.0 + i % 10) for i in range(10, 20)]


def test_prune_and_missing_or_foreign_files(path, tmp_path, capsys):
    code, out = run("--archive", str(path), "prune", "--days", "1", "--export",
                    str(tmp_path / "old"))
    assert code == 0 and "'telemetry': 600" in out
    assert (tmp_path / "old").is_dir()
    assert main(["--archive", str(tmp_path / "none.sqlite3"), "info"]) == 1
    bad = tmp_path / "bad.sqlite3"
    bad.write_text("hello")
    assert main(["--archive", str(bad), "info"]) == 1
    assert "not a Station Patrol archive" in capsys.readouterr().err


def test_parse_time():
    assert parse_time("1700000000") == T0
    assert parse_time("2023-11-14T22:13:20") == T0
    assert parse_time("2023-11-14T23:13:20+01:00") == T0
    assert abs(parse_time("-2h") - (time.time() - 7200)) < 5
    with pytest.raises(Exception, match="not a time"):
        parse_time("yesterday-ish")


def test_series_from_relative_time_works_as_the_help_shows(tmp_path):
    """``series temp_c --from -2h`` (issue 12, C): the relative time is not taken
    for an option."""
    p = tmp_path / "recent.sqlite3"
    a = Archive(p)
    now = time.time()
    for i in range(30):
        a.add_telemetry(now - 3 * 3600 + i * 600, {"temp_c": float(i)}, seq=i)
    a.close()
    code, out = run("--archive", str(p), "series", "temp_c", "--from", "-2h", "--points", "100")
    assert code == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    # samples 0..5 lie more than 2 h back (sample i at 3 h - i·10 min): left out
    values = sorted({float(r["mean"]) for r in rows})
    assert values and values[0] >= 6.0 and values[-1] == 29.0


def test_unknown_channel_is_an_error_naming_the_known_ones(path, capsys):
    code, out = run("--archive", str(path), "series", "temp_C")
    err = capsys.readouterr().err
    assert code == 2 and out == ""
    assert "unknown channel 'temp_C'" in err and "gas_lel_pct, temp_c" in err
    assert "0 points" not in err
    code, _ = run("--archive", str(path), "export", "--channels", "temp_c,nope",
                  "--out", str(path.parent / "x.csv"))
    assert code == 2 and "unknown channel 'nope'" in capsys.readouterr().err
    assert not (path.parent / "x.csv").exists()


@pytest.fixture
def two_sessions(tmp_path):
    """Two desk runs in one archive: desk-a (gas 1.0, x < 10) then desk-b (gas 7.0,
    x >= 100), an hour apart."""
    p = tmp_path / "s.sqlite3"
    ids = []
    for k, (desk, gas) in enumerate((("desk-a", 1.0), ("desk-b", 7.0))):
        a = Archive(p)
        ids.append(a.begin_session(desk, f"10.0.0.{k + 5}:7000"))
        t0 = T0 + 3600 * k
        for i in range(20):
            a.add_telemetry(t0 + i, {"gas_lel_pct": gas, "temp_c": 20.0}, seq=i)
        a.add_event(t0 + 1, "patrol_status", {"state": desk})
        a.add_command(t0 + 2, desk, "estop", {}, seq=k + 1)
        a.close()
    return p, ids


def test_row_reading_commands_read_one_session_and_say_which(two_sessions, tmp_path, capsys):
    path, (sa, sb) = two_sessions
    capsys.readouterr()
    # default: the latest session, named on stderr
    code, out = run("--archive", str(path), "series", "gas_lel_pct", "--points", "50")
    err = capsys.readouterr().err
    rows = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and len(rows) == 20 and {r["mean"] for r in rows} == {"7.0"}
    assert f"session {sb}" in err and "desk desk-b" in err and "desk-a" not in err
    # a given session
    csv_a = tmp_path / "a.csv"
    code, _ = run("--archive", str(path), "export", "--session", str(sa), "--out", str(csv_a))
    err = capsys.readouterr().err
    rows = list(csv.DictReader(csv_a.open()))
    assert code == 0 and len(rows) == 20 and {r["gas_lel_pct"] for r in rows} == {"1.0"}
    assert f"session {sa}" in err and "desk desk-a" in err
    code, out = run("--archive", str(path), "events", "--session", str(sa))
    assert [json.loads(line)["data"] for line in out.splitlines()] == [{"state": "desk-a"}]
    code, out = run("--archive", str(path), "commands")
    assert [r["user"] for r in csv.DictReader(io.StringIO(out))] == ["desk-b"]
    # all: both, and it says they are mixed
    capsys.readouterr()
    code, out = run("--archive", str(path), "commands", "--session", "all")
    assert [r["user"] for r in csv.DictReader(io.StringIO(out))] == ["desk-a", "desk-b"]
    assert "all sessions mixed" in capsys.readouterr().err
    # latest within a range is the newest session with telemetry there
    code, out = run("--archive", str(path), "series", "gas_lel_pct", "--to", str(T0 + 100))
    assert {r["mean"] for r in csv.DictReader(io.StringIO(out))} == {"1.0"}
    assert f"session {sa}" in capsys.readouterr().err
    # a session the archive does not hold: an error naming the ones it holds
    code, out = run("--archive", str(path), "alarms", "--session", "99")
    err = capsys.readouterr().err
    assert code == 2 and out == "" and "no session 99" in err and f"{sa}, {sb}" in err
