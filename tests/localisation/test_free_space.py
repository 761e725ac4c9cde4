"""Free rays of the beams that returned nothing (free_space.no_return_rays)."""

import math

import numpy as np

from app.core.localisation.free_space import no_return_rays

N = 360
TURN = -math.pi + 2 * math.pi / N * np.arange(N)  # a full turn, 1° a beam


def _lengths_by_beam(rays, angles):
    """{beam index: ray length} of the rays (matched to the beams by bearing)."""
    out = {}
    for x, y in rays:
        i = int(np.argmin(np.abs(np.angle(np.exp(1j * (angles - math.atan2(y, x)))))))
        out[i] = math.hypot(x, y)
    return out


def test_a_dropout_amid_a_wall_clears_no_more_than_its_neighbours_saw():
    r = np.full(N, 3.0)
    r[50] = np.inf  # one beam swallowed by the wall 3 m away
    rays = _lengths_by_beam(no_return_rays(r, TURN, max_range_m=11.9, margin_m=0.3), TURN)
    assert rays.keys() == {50}
    assert math.isclose(rays[50], 2.7)  # stops short of the wall: never through it


def test_open_ground_clears_to_the_usable_range_and_the_edges_stop_short_of_the_walls():
    r = np.full(N, 4.0)
    r[100:120] = np.inf  # a gap onto open ground between walls 4 m away
    r[119] = 12.5  # beyond the usable range: no return either
    rays = _lengths_by_beam(no_return_rays(r, TURN, max_range_m=11.9, margin_m=0.3), TURN)
    assert sorted(rays) == list(range(100, 120))
    assert math.isclose(rays[100], 3.7) and math.isclose(rays[119], 3.7)  # beside the walls
    assert all(math.isclose(rays[i], 11.6) for i in range(101, 119))
    wider = _lengths_by_beam(no_return_rays(r, TURN, 11.9, margin_m=0.3, neighbours=2), TURN)
    assert math.isclose(wider[101], 3.7) and math.isclose(wider[102], 11.6)
    short = _lengths_by_beam(no_return_rays(r, TURN, 11.9, clear_m=6.0, margin_m=0.3), TURN)
    assert math.isclose(short[110], 5.7)  # as far as the sensor is taken to see


def test_the_first_and_last_beams_of_a_full_turn_are_neighbours_but_not_of_a_half_turn():
    r = np.full(N, np.inf)
    r[-1] = 2.0
    rays = _lengths_by_beam(no_return_rays(r, TURN, 11.9, margin_m=0.3), TURN)
    assert math.isclose(rays[0], 1.7)  # beside the last beam, round the turn
    half = np.linspace(-math.pi / 2, math.pi / 2, 181)
    rh = np.full(181, np.inf)
    rh[-1] = 2.0
    rays = _lengths_by_beam(no_return_rays(rh, half, 11.9, margin_m=0.3), half)
    assert math.isclose(rays[0], 11.6) and math.isclose(rays[179], 1.7)


def test_readings_that_are_not_open_ground_give_no_ray_and_hold_their_neighbours_back():
    r = np.full(N, np.inf)
    r[10] = np.nan  # not a number: nothing known along it
    r[20] = 0.02  # dust on the window
    rays = _lengths_by_beam(no_return_rays(r, TURN, 11.9, margin_m=0.3), TURN)
    assert not {9, 10, 11, 19, 20, 21} & rays.keys()
    assert math.isclose(rays[30], 11.6)
    assert len(no_return_rays(np.full(N, 3.0), TURN, 11.9)) == 0  # every beam came back
