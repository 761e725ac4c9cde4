"""The reset of a latched gas alarm goes into the archive with who and when."""

from __future__ import annotations

import sqlite3

from app.comm import protocol as P
from app.core.desk.pipeline import DeskPipeline
from app.core.records import Archive

T0 = 1_800_000_000.0
A2 = "gas_lel_pct.a2"


def tel(t: float, gas: float) -> P.Telemetry:
    m = P.Telemetry(gas_lel_pct=gas, temp_c=20.0, humidity_pct=40.0, battery_v=24.0)
    m.received_s = t
    return m


def test_latched_gas_reset_archived_with_who_and_when(tmp_path):
    archive = Archive(tmp_path / "a.sqlite3")
    pipe = DeskPipeline(archive=archive, user="desk-1", clock=lambda: T0 + 30)
    pipe.ingest("telemetry", tel(T0, 25.0))  # A2, latching
    pipe.ingest("telemetry", tel(T0 + 5, 1.0))
    pipe.monitor.tick(T0 + 20)
    assert pipe.monitor.latched(A2)
    trs, why = pipe.monitor.reset(A2, T0 + 21, user="ana")
    assert why == "" and trs
    pipe.close()
    con = sqlite3.connect(tmp_path / "a.sqlite3")
    try:
        rows = con.execute("SELECT t, from_state, to_state, user, reason FROM "
                           "alarm_transition WHERE alarm = ? ORDER BY t, id", (A2,)).fetchall()
    finally:
        con.close()
    assert rows[0][1:3] == ("NORMAL", "UNACK")
    assert rows[-1] == (T0 + 21, "UNACK", "RTN_UNACK", "ana", "reset")
