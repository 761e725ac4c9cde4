"""Work the answer does not depend on is not done: the same answers as doing it."""

import math

import cv2
import numpy as np
import pytest

from app.core.meter import ring_centre as rc
from app.core.meter.geometry import Line
from app.core.meter.pointer import CENTRE


def _pass(seed: int, hub) -> dict:
    """A pointer pass's result on a dial of ticks whose ring is centred off the crop's
    centre (as under perspective, or about another point), the needle from ``hub``."""
    rng = np.random.default_rng(seed)
    dark = (rng.random((300, 300)) < 0.01).astype(np.uint8) * 200
    cx, cy = CENTRE + rng.uniform(-8.0, 8.0, 2)
    start, span = rng.uniform(0, 360), rng.uniform(200, 300)
    r_out = rng.uniform(105, 118)
    for k in range(41):
        a = math.radians(start + span * k / 40.0)
        r_in = r_out - (14 if k % 5 == 0 else 7)
        cv2.line(dark, (int(cx + r_in * math.sin(a)), int(cy - r_in * math.cos(a))),
                 (int(cx + r_out * math.sin(a)), int(cy - r_out * math.cos(a))), 220, 2)
    a = rng.uniform(0, 2 * math.pi)
    u = (math.sin(a), -math.cos(a))
    pmask = np.zeros((300, 300), np.uint8)
    cv2.line(pmask, (int(hub[0]), int(hub[1])),
             (int(hub[0] + 100 * u[0]), int(hub[1] + 100 * u[1])), 1, 5)
    return {"centre": (float(hub[0]), float(hub[1])), "dark": dark, "pmask": pmask,
            "line": Line((float(hub[0]), float(hub[1])), u), "otsu_t": 60.0}


@pytest.mark.parametrize("seed", range(8))
def test_a_hub_near_the_rim_centre_is_allowed_without_fitting_rings(seed, monkeypatch):
    rng = np.random.default_rng(100 + seed)
    for k in range(6):
        # hubs within CENTRES_AGREE_PX of the rim's centre, some on its edge
        d = rc.CENTRES_AGREE_PX * (1.0 - 1e-6 if k == 0 else rng.uniform(0.0, 1.0))
        phi = rng.uniform(0, 2 * math.pi)
        hub = (CENTRE + d * math.cos(phi), CENTRE + d * math.sin(phi))
        res = _pass(seed * 10 + k, hub)
        for every_ring in (False, True):
            for rim_radius in (135.0, 147.0):
                # the full test, every ring fitted ...
                monkeypatch.setattr(rc, "NEAR_RIM_PX", -1.0)
                full = rc.hub_is_perspective_centre(res, rim_radius, every_ring=every_ring)
                # ... and without fitting any
                monkeypatch.setattr(rc, "NEAR_RIM_PX", rc.CENTRES_AGREE_PX - 1e-9)

                def no_fit(*a, **kw):
                    raise AssertionError("a ring was fitted")

                monkeypatch.setattr(rc, "ring_centre", no_fit)
                assert rc.hub_is_perspective_centre(res, rim_radius, every_ring=every_ring) \
                    is full is True
                monkeypatch.undo()


@pytest.mark.parametrize("seed", range(4))
def test_a_hub_off_the_rim_centre_is_still_tested_against_the_rings(seed, monkeypatch):
    rng = np.random.default_rng(200 + seed)
    fitted = []
    fit = rc.ring_centre

    def counted(*a, **kw):
        fitted.append(a[2])
        return fit(*a, **kw)

    monkeypatch.setattr(rc, "ring_centre", counted)
    for k in range(4):
        d = rng.uniform(3.1, 12.0)
        phi = rng.uniform(0, 2 * math.pi)
        hub = (CENTRE + d * math.cos(phi), CENTRE + d * math.sin(phi))
        fitted.clear()
        rc.hub_is_perspective_centre(_pass(seed * 10 + k, hub), 135.0)
        assert len(fitted) == 2  # from the hub and from the rim's centre
