"""bench/meter_why.py: refusals pooled by their deciding reason, each with how far its
candidate reading lay from the truth."""

from bench import meter_why


def _rec(reason, err, read=False, bound=None, method="scale"):
    return {"read": read, "reason": reason, "err_fs": err, "bound_fs": bound,
            "method": method}


def test_refusals_pool_by_their_deciding_reason_with_numbers_masked():
    a = meter_why.reason_class("profile angles: the scale's end marks lie +3.2 deg off the "
                               "profile's span; also: scale arc (183 deg) does not match")
    b = meter_why.reason_class("profile angles: the scale's end marks lie -12.0 deg off the "
                               "profile's span")
    assert a == b == "profile angles: the scale's end marks lie # deg off the profile's span"


def test_the_table_says_how_many_candidates_lay_within_two_percent():
    recs = [_rec("x", 0.5), _rec("x", 1.5), _rec("x", 9.0), _rec("x", None),
            _rec("y", 0.1), _rec(None, 0.2, read=True)]
    lines = meter_why.reason_table(recs).splitlines()
    x = next(ln for ln in lines if ln.endswith(" x")).split()
    # n, with a candidate, <=1 %, <=2 %, median, max
    assert x[:4] == ["4", "3", "33%", "67%"] and float(x[4]) == 1.5 and float(x[5]) == 9.0
    assert lines[1].endswith(" x")  # the most frequent reason first
    assert not any(ln.endswith(" None") for ln in lines)  # readings are no refusals


def test_the_bound_table_counts_errors_beyond_the_stated_bound():
    recs = [_rec(None, 0.5, read=True, bound=0.4), _rec(None, 0.1, read=True, bound=0.4),
            _rec("r", 1.0, bound=1.2)]
    lines = meter_why.bound_table(recs).splitlines()
    band = next(ln for ln in lines if ln.strip().startswith("0.35")).split()
    assert band[1:4] == ["2", "2", "1"] and float(band[4]) == 1.25
    band = next(ln for ln in lines if ln.strip().startswith("0.90")).split()
    assert band[1:4] == ["1", "0", "0"] and band[-3:] == ["1", "of", "1"]
