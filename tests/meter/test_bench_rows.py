"""The meter bench's row tally: a reader exception is a counted, named refusal."""

import numpy as np

from bench import meter_rows


def test_an_exception_from_the_reader_is_a_named_refusal_and_the_row_goes_on(monkeypatch):
    calls = []

    def reader(img, profile, **kw):
        calls.append(img.shape)
        if len(calls) == 2:
            raise ValueError("zero-size array")
        return type("R", (), {"value": 1.0, "confidence": 1.0, "error": None})()

    monkeypatch.setattr(meter_rows, "read_gauge", reader)
    tally = meter_rows.Tally()
    for _ in range(3):
        r, ms = meter_rows.timed_read(np.zeros((8, 8, 3), np.uint8), {})
        tally.add(r, 1.0, 10.0, ms)
    assert len(calls) == 3 and tally.n == 3 and len(tally.errs) == 2
    assert tally.reasons == {"read_gauge raised ValueError: zero-size array": 1}
