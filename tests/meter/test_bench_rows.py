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


def test_a_refusal_is_tallied_by_its_deciding_reason():
    """The reader names the deciding reason first and the earlier paths' after it: the
    tally counts the first only, so a scale refusal the angles path overruled is not
    counted as the reason."""
    tally = meter_rows.Tally()
    for span in (183, 48):
        r = type("R", (), {"value": None, "confidence": 0.0, "error": (
            "profile angles: end marks off the profile's span; also: scale arc "
            f"({span} deg) does not match the profile's span (180 deg); keypoints: unsure")})()
        tally.add(r, 1.0, 10.0, 1.0)
    assert tally.reasons == {"profile angles: end marks off the profile's span": 2}


def _fake_rows(monkeypatch):
    """The uncalibrated rows with the renderer and the reader stubbed: which families they
    draw, and what they print."""
    from types import SimpleNamespace

    drawn = []

    def render(family, level, rng):
        drawn.append(family)
        truth = {"value": 1.0, "full_scale": 10.0, "style": family,
                 "profile": {"name": "g", "unit": "bar", "min_value": 0, "max_value": 10,
                             "min_angle_deg": -135, "max_angle_deg": 135}}
        return np.zeros((8, 8, 3), np.uint8), truth

    monkeypatch.setattr(meter_rows, "render_sample", render)
    monkeypatch.setattr(meter_rows, "read_gauge",
                        lambda img, prof, **kw: SimpleNamespace(value=None, confidence=0.0,
                                                                error="stub"))

    def run(**kw):
        drawn.clear()
        args = SimpleNamespace(family="", rows=["heldout"], n=3, seed=1, dump="",
                               verbose=False, **kw)
        meter_rows.uncalibrated_rows(args, ["clean"])
        return set(drawn)

    return run


def test_the_held_out_rows_draw_foundry_and_atlas_on_request(monkeypatch, capsys):
    run = _fake_rows(monkeypatch)
    assert run() == {"foundry"}
    assert "--heldout" not in capsys.readouterr().out
    assert run(heldout="atlas") == {"atlas"}
    assert "--rows heldout --levels clean --n 3 --seed 1 --heldout atlas" in (
        capsys.readouterr().out)


def test_the_bench_accepts_only_known_held_out_families(capsys):
    import pytest

    from bench import meter_bench

    with pytest.raises(SystemExit) as e:
        meter_bench.main(["--rows", "heldout", "--heldout", "plant"])
    assert e.value.code == 2 and "invalid choice: 'plant'" in capsys.readouterr().err


def test_the_trainer_refuses_held_out_families_now_and_before(capsys):
    import pytest

    from bench import train_keypoints

    for fams in ("plant,foundry", "atlas", "dark,atlas,foundry"):
        with pytest.raises(SystemExit) as e:
            train_keypoints.main(["--families", fams, "--gen-only", "--n-clean", "1"])
        assert e.value.code == 2
        err = capsys.readouterr().err
        assert "never trained on" in err and all(f in err for f in fams.split(",")
                                                 if f in ("foundry", "atlas"))
