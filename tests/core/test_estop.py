"""The e-stop's delivery book (app/core/estop): sent, acknowledged, not delivered."""

from app.core.estop import NOT_DELIVERED, EstopDelivery


def test_link_down_is_not_delivered_at_once():
    d = EstopDelivery()
    r = d.press(False, None, 1000.0, 5.0)
    assert r.status == "not_delivered" and r.alarm is True
    assert r.text == f"{NOT_DELIVERED} — link down: use the robot's own stop"
    assert d.pending is None and d.tick(100.0) is None


def test_only_the_ack_of_the_estop_counts():
    d = EstopDelivery(ack_timeout_s=2.0)
    assert d.press(True, 7, 1000.0, 5.0).status == "sent"
    assert d.on_ack(8, True, "", 1000.5) is None  # another command
    assert d.tick(6.0) is None  # not yet late
    r = d.on_ack(7, True, "", 1000.5)
    assert r.delivered and r.alarm is False and "acknowledged by the robot at" in r.text
    assert d.tick(100.0) is None


def test_late_refused_or_cut_off():
    d = EstopDelivery(ack_timeout_s=2.0)
    d.press(True, 1, 1000.0, 5.0)
    r = d.tick(7.5)
    assert r.status == "not_delivered" and "within 2 s" in r.text
    assert d.on_ack(1, True, "", 1003.0).delivered  # the late ack still clears it
    d.press(True, 2, 1010.0, 20.0)
    assert d.on_link_down().status == "not_delivered"
    assert d.on_link_down() is None  # nothing pending any more
    d.press(True, 3, 1020.0, 30.0)
    r = d.on_ack(3, False, "no_lease", 1020.1)
    assert r.alarm is True and "refused by the robot (no_lease)" in r.text
    assert (d.sent, d.acknowledged, d.not_delivered) == (3, 1, 3)


def test_the_robot_reporting_estop_clears_the_alarm():
    d = EstopDelivery()
    assert d.on_robot_estop() is None  # nothing to clear
    d.press(False, None, 1000.0, 5.0)
    r = d.on_robot_estop()
    assert r.alarm is False and "reports its e-stop engaged" in r.text
