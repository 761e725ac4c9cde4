"""The desk's meter service keeps a bounded history in memory (the archive keeps
every reading), so a desk running for days does not grow with its readings."""

from app.core import meter_service as ms


def test_the_in_memory_history_is_bounded_and_keeps_the_latest(monkeypatch):
    monkeypatch.setattr(ms, "MAX_RECORDS", 5)
    svc = ms.MeterService(settle_s=0.0)
    points = [f"P-{k}" for k in range(12)]
    for p in points:
        svc.start("CG-301", p)
        assert svc.finish() is not None
    assert [r.point for r in svc.records] == points[-5:]
    assert svc.latest["CG-301"].point == points[-1]
