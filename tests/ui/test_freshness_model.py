"""The freshness model announces what a display would show differently: a source's
state, or the age a stale source shows ("N s ago", then whole minutes), and not
every tick while something is stale."""

from __future__ import annotations

from app.core.freshness import Age
from app.ui.freshness_model import FreshnessModel


def _model(qtbot, now: dict) -> tuple[FreshnessModel, list]:
    model = FreshnessModel(tick_ms=60_000, mono=lambda: now["t"])  # ticks driven by hand
    seen = []
    model.changed.connect(lambda snap: seen.append(
        {n: (f.age, f.text()) for n, f in snap.items() if n in ("pose", "control")}))
    model.on_link_state("connected")
    for k in range(5):  # a 10 Hz pose: its interval is learnt
        now["t"] = 100.0 + 0.1 * k
        model.note("pose", (1.0, 2.0, 0.0))
    model.note("control", "me")
    return model, seen


def test_a_stale_age_is_announced_when_its_words_change_not_every_tick(qtbot):
    now = {"t": 100.0}
    model, seen = _model(qtbot, now)
    now["t"] = 100.45
    model.on_link_state("lost")  # the state changes: announced at once
    assert seen[-1]["pose"][0] is Age.NO_LINK and seen[-1]["control"][0] is Age.NO_LINK
    n = len(seen)
    for t in (100.6, 100.9, 101.1):  # still "0 s ago" ... "0 s ago"
        now["t"] = t
        model.refresh()
    assert len(seen) == n
    now["t"] = 101.45  # pose and control now "1 s ago"
    model.refresh()
    assert len(seen) == n + 1 and seen[-1]["pose"][1].endswith("1 s ago")
    now["t"] = 101.9
    model.refresh()
    assert len(seen) == n + 1
    # past a minute the age is shown in whole minutes: once a minute
    now["t"] = 100.4 + 61
    model.refresh()
    assert seen[-1]["pose"][1].endswith("1 min ago")
    n = len(seen)
    for k in range(1, 119):  # half-second ticks up to 2 min
        now["t"] = 100.4 + 61 + 0.5 * k
        model.refresh()
    assert len(seen) == n + 1 and seen[-1]["pose"][1].endswith("2 min ago")


def test_a_value_that_goes_quiet_or_comes_back_is_announced_at_once(qtbot):
    now = {"t": 100.0}
    model, seen = _model(qtbot, now)
    n = len(seen)
    now["t"] = 100.45
    model.refresh()  # live, as before: nothing to redraw
    assert len(seen) == n
    now["t"] = 103.0  # quiet for over 2 s with the link up: old
    model.refresh()
    assert seen[-1]["pose"][0] is Age.OLD and seen[-1]["pose"][1].endswith("2 s ago")
    model.note("pose", (1.5, 2.0, 0.0))  # it comes back: live again at once
    assert seen[-1]["pose"] == (Age.LIVE, "")
