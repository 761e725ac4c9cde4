"""The ISA-18.2 state machine: every transition, by the pure function and
through the monitor with its listeners."""

import pytest

from app.core.alarms import (
    AlarmEvent,
    AlarmMonitor,
    AlarmState,
    LimitRule,
    Priority,
    next_state,
    parse_priority,
)

S, E = AlarmState, AlarmEvent


@pytest.mark.parametrize("state,event,active,expected", [
    (S.NORMAL, E.ACTIVATE, True, S.UNACK),
    (S.NORMAL, E.ACK, False, S.NORMAL),
    (S.NORMAL, E.CLEAR, False, S.NORMAL),
    (S.UNACK, E.ACK, True, S.ACKED),
    (S.UNACK, E.CLEAR, False, S.RTN_UNACK),
    (S.ACKED, E.CLEAR, False, S.NORMAL),
    (S.ACKED, E.ACK, True, S.ACKED),
    (S.RTN_UNACK, E.ACK, False, S.NORMAL),
    (S.RTN_UNACK, E.ACTIVATE, True, S.UNACK),
    (S.UNACK, E.SHELVE, True, S.SHELVED),
    (S.ACKED, E.SHELVE, True, S.SHELVED),
    (S.RTN_UNACK, E.SHELVE, False, S.SHELVED),
    (S.NORMAL, E.SHELVE, False, S.SHELVED),
    (S.SHELVED, E.ACTIVATE, True, S.SHELVED),
    (S.SHELVED, E.CLEAR, False, S.SHELVED),
    (S.SHELVED, E.ACK, True, S.SHELVED),
    (S.SHELVED, E.UNSHELVE, True, S.UNACK),
    (S.SHELVED, E.UNSHELVE, False, S.NORMAL),
    (S.OUT_OF_SERVICE, E.SHELVE, True, S.OUT_OF_SERVICE),
    (S.UNACK, E.REMOVE, True, S.OUT_OF_SERVICE),
    (S.NORMAL, E.REMOVE, False, S.OUT_OF_SERVICE),
    (S.SHELVED, E.REMOVE, True, S.OUT_OF_SERVICE),
    (S.OUT_OF_SERVICE, E.ACTIVATE, True, S.OUT_OF_SERVICE),
    (S.OUT_OF_SERVICE, E.RETURN, True, S.UNACK),
    (S.OUT_OF_SERVICE, E.RETURN, False, S.NORMAL),
    (S.NORMAL, E.RETURN, False, S.NORMAL),
    (S.UNACK, E.UNSHELVE, True, S.UNACK),
])
def test_state_diagram(state, event, active, expected):
    assert next_state(state, event, active) is expected


def test_priorities_parse_by_name():
    assert parse_priority("emergency") is Priority.EMERGENCY
    assert parse_priority(" High ") is Priority.HIGH
    assert Priority.EMERGENCY > Priority.HIGH > Priority.MEDIUM > Priority.LOW
    with pytest.raises(ValueError, match="unknown priority 'urgent'"):
        parse_priority("urgent")


@pytest.fixture
def mon():
    m = AlarmMonitor([LimitRule("temp_c", high=45.0, deadband=1.0, unit="°C",
                                label="Temperature")])
    seen = []
    m.add_listener(seen.append)
    m.seen = seen
    return m


def states(trs):
    return [(t.from_state.value, t.to_state.value) for t in trs]


def test_full_cycle_ack_while_active(mon):
    trs = mon.update("temp_c", 46.0, 1.0)
    assert states(trs) == [("NORMAL", "UNACK")] and trs[0].raised
    assert mon.state("temp_c.high") is S.UNACK
    trs = mon.acknowledge("temp_c.high", 2.0, user="ana")
    assert states(trs) == [("UNACK", "ACKED")]
    assert trs[0].alarm.acked_by == "ana" and trs[0].alarm.acked_t == 2.0
    assert mon.acknowledge("temp_c.high", 2.5) == []  # nothing left to acknowledge
    trs = mon.update("temp_c", 43.0, 3.0)
    assert states(trs) == [("ACKED", "NORMAL")] and trs[0].cleared
    assert mon.listed() == []
    # every transition reached the listener, in order
    assert states(mon.seen) == [("NORMAL", "UNACK"), ("UNACK", "ACKED"), ("ACKED", "NORMAL")]


def test_return_to_normal_unacknowledged_stays_listed(mon):
    mon.update("temp_c", 46.0, 1.0)
    trs = mon.update("temp_c", 43.0, 2.0)
    assert states(trs) == [("UNACK", "RTN_UNACK")]
    [a] = mon.listed()
    assert a.state is S.RTN_UNACK and not a.active and a.cleared_t == 2.0
    assert mon.active() == []  # no longer standing ...
    assert mon.most_severe_unacknowledged().key == "temp_c.high"  # ... but still unacked
    # comes back before being acknowledged: unacknowledged again
    assert states(mon.update("temp_c", 47.0, 3.0)) == [("RTN_UNACK", "UNACK")]
    mon.update("temp_c", 40.0, 4.0)
    assert states(mon.acknowledge("temp_c.high", 5.0)) == [("RTN_UNACK", "NORMAL")]
    assert mon.listed() == []


def test_acknowledge_all(mon):
    mon.set_rule(LimitRule("humidity_pct", high=90.0, deadband=2.0))
    mon.update_many({"temp_c": 50.0, "humidity_pct": 95.0}, 1.0)
    trs = mon.acknowledge_all([a.key for a in mon.listed()], 2.0, user="bo")
    assert sorted(t.alarm.key for t in trs) == ["humidity_pct.high", "temp_c.high"]
    assert all(t.to_state is S.ACKED and t.user == "bo" for t in trs)


def test_shelve_hides_and_expires_by_itself(mon):
    mon.update("temp_c", 46.0, 1.0)
    trs = mon.shelve("temp_c.high", 2.0, 60.0, "sensor being recalibrated", user="ana")
    assert states(trs) == [("UNACK", "SHELVED")]
    assert trs[0].reason == "sensor being recalibrated" and trs[0].user == "ana"
    assert trs[0].alarm.shelved_until == 62.0
    assert mon.active() == [] and mon.most_severe_unacknowledged() is None
    # condition changes while shelved: no transition, nothing annunciated
    assert mon.update("temp_c", 40.0, 10.0) == []
    assert mon.update("temp_c", 48.0, 20.0) == []
    assert mon.tick(61.9) == []
    trs = mon.tick(62.0)
    assert states(trs) == [("SHELVED", "UNACK")]  # condition stands: annunciated again
    assert trs[0].reason == "shelving expired" and trs[0].raised


def test_shelve_expiry_with_condition_gone_returns_to_normal(mon):
    mon.update("temp_c", 46.0, 1.0)
    mon.shelve("temp_c.high", 2.0, 10.0, "known fault")
    mon.update("temp_c", 40.0, 5.0)
    assert states(mon.tick(12.0)) == [("SHELVED", "NORMAL")]


def test_unshelve_by_the_operator(mon):
    mon.update("temp_c", 46.0, 1.0)
    mon.shelve("temp_c.high", 2.0, 600.0, "noisy")
    assert states(mon.unshelve("temp_c.high", 3.0, user="ana")) == [("SHELVED", "UNACK")]


def test_shelve_needs_reason_and_sane_duration(mon):
    mon.update("temp_c", 46.0, 1.0)
    with pytest.raises(ValueError, match="needs a reason"):
        mon.shelve("temp_c.high", 2.0, 60.0, "  ")
    with pytest.raises(ValueError, match="duration"):
        mon.shelve("temp_c.high", 2.0, 0.0, "x")
    with pytest.raises(ValueError, match="duration"):
        mon.shelve("temp_c.high", 2.0, 9 * 3600, "x")
    with pytest.raises(ValueError, match="not a number"):
        mon.shelve("temp_c.high", 2.0, "ten", "x")
    assert mon.state("temp_c.high") is S.UNACK and mon.seen[-1].to_state is S.UNACK


def test_out_of_service_and_back(mon):
    mon.update("temp_c", 46.0, 1.0)
    with pytest.raises(ValueError, match="needs a reason"):
        mon.set_out_of_service("temp_c.high", True, 2.0, None)
    trs = mon.set_out_of_service("temp_c.high", True, 2.0, "sensor replaced", user="tech")
    assert states(trs) == [("UNACK", "OUT_OF_SERVICE")] and trs[0].reason == "sensor replaced"
    assert mon.shelve("temp_c.high", 3.0, 60, "x") == []  # not shelvable while out of service
    assert mon.update("temp_c", 40.0, 4.0) == []
    assert states(mon.set_out_of_service("temp_c.high", False, 5.0, user="tech")) == [
        ("OUT_OF_SERVICE", "NORMAL")]
    mon.set_out_of_service("temp_c.high", True, 6.0, "again")
    mon.update("temp_c", 50.0, 7.0)
    assert states(mon.set_out_of_service("temp_c.high", False, 8.0)) == [
        ("OUT_OF_SERVICE", "UNACK")]


def test_an_alarm_never_raised_can_be_taken_out_of_service(mon):
    trs = mon.set_out_of_service("temp_c.high", True, 1.0, "maintenance")
    assert states(trs) == [("NORMAL", "OUT_OF_SERVICE")]
    assert trs[0].alarm.limit == 45.0 and trs[0].alarm.unit == "°C"
    assert mon.update("temp_c", 50.0, 2.0) == []


def test_set_condition_and_record(mon):
    trs = mon.set_condition("link.lost", True, 10.0, source="link", priority=Priority.HIGH,
                            text="Link to the robot lost")
    assert states(trs) == [("NORMAL", "UNACK")]
    assert mon.set_condition("link.lost", True, 11.0, source="link", priority=Priority.HIGH,
                             text="Link to the robot lost") == []
    rec = trs[0].as_record()
    assert rec == {"t": 10.0, "alarm": "link.lost", "source": "link", "priority": "HIGH",
                   "from_state": "NORMAL", "to_state": "UNACK", "value": None, "limit": None,
                   "unit": "", "text": "Link to the robot lost", "user": None, "reason": None,
                   "origin": None}
    trs = mon.set_condition("link.lost", False, 12.0, source="link", priority=Priority.HIGH,
                            text="Link to the robot lost")
    assert trs[0].as_record()["to_state"] == "RTN_UNACK"


def test_limit_record_carries_value_and_limit(mon):
    [tr] = mon.update("temp_c", 46.5, 1.0)
    rec = tr.as_record()
    assert (rec["alarm"], rec["source"], rec["priority"], rec["value"], rec["limit"],
            rec["unit"]) == ("temp_c.high", "temp_c", "MEDIUM", 46.5, 45.0, "°C")
    assert rec["text"] == "Temperature 46.5 °C above limit 45 °C"


def test_failing_listener_does_not_stop_the_others(mon):
    def bad(_tr):
        raise RuntimeError("boom")

    mon.add_listener(bad)
    got = []
    mon.add_listener(got.append)
    mon.update("temp_c", 46.0, 1.0)
    assert len(got) == 1 and mon.listener_errors == 1 and mon.is_active("temp_c.high")
    mon.remove_listener(bad)
    mon.update("temp_c", 40.0, 2.0)
    assert mon.listener_errors == 1


def test_header_alarm_is_most_severe_unacknowledged():
    m = AlarmMonitor([LimitRule("temp_c", high=45.0), LimitRule("gas_lel_pct", high=10.0,
                                                                  priority=Priority.HIGH)])
    m.update("temp_c", 50.0, 1.0)
    m.update("gas_lel_pct", 20.0, 2.0)
    assert m.most_severe_unacknowledged().key == "gas_lel_pct.high"
    m.acknowledge("gas_lel_pct.high", 3.0)
    assert m.most_severe_unacknowledged().key == "temp_c.high"
    assert m.most_severe().key == "gas_lel_pct.high"  # still standing
    m.acknowledge("temp_c.high", 4.0)
    assert m.most_severe_unacknowledged() is None
