"""A set-point pointer of the colour the profile ignores is no second pointer, its fringe
included (``needle._masked_rays``): blurred and compressed, the pointer's edges fall below
the colour's saturation and would otherwise show as a dark line beside it."""

import numpy as np

from app.core.meter import load_profile, read_gauge
from app.core.meter.needle import N_TH, _masked_rays
from tests.meter.stored_frames import stored


def test_masked_rays_take_the_colours_rays_and_a_margin_round_the_circle():
    masked = np.zeros((N_TH, 40), bool)
    masked[10:14, :20] = True  # half of these rays' radii: the pointer
    masked[300, :3] = True  # a speck: no pointer
    hit = _masked_rays(masked)
    m = int(round(4.0 * N_TH / 360.0))
    assert hit[10 - m] and hit[13 + m] and not hit[13 + m + 1]
    assert hit[N_TH - 1] == (10 - m < 0)  # wraps round when the margin crosses ray 0
    assert not hit[300]
    edge = np.zeros((N_TH, 40), bool)
    edge[0, :20] = True
    assert _masked_rays(edge)[N_TH - m] and not _masked_rays(edge)[N_TH - m - 1]


def test_needles_beside_a_flag_of_the_ignored_colour_are_read():
    """Field frames of the former held-out family atlas (``bench/meter_ab.py --families
    atlas --seed 2``, #82 and #150) with a red set-point flag that the profile ignores:
    each was refused for a second pointer, and is read within 2 % FS."""
    for i in (82, 150):
        img, truth = stored(f"atlas-field-2-{i}")
        prof = load_profile(truth["profile"])
        assert prof.ignore_colour == "red"
        r = read_gauge(img, prof)
        assert r.value is not None, (i, r.error)
        assert abs(r.value - truth["value"]) <= 0.02 * truth["full_scale"], (i, r.value)
