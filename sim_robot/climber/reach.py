"""Where the crawler's body fits on the wall, as the navigation sees it: the
wall's map (its top and bottom, the obstacles) and the robot's own estimate,
never the simulator's truth.

The probe sits at the body's front face (L/2 ahead of the axle), so a cell
next to the shell's bottom can be probed only with the body above it, facing
down, and one next to the top only facing up: a lane that starts at an edge
takes its first cells facing that edge (reversing away from it) and turns
round once the body fits behind the probe. A turn in place swings the body's
corners round its centre (half-diagonal 0.194 m): too near an edge or an
obstacle the crawler first backs off along its heading. The map's footprint
check is :class:`~.contact.WallContact`'s, here grown by a margin for the
estimate's error.
"""

from __future__ import annotations

import math

import numpy as np

from .contact import WallContact

MARGIN_M = 0.02  # the footprint is grown by this (the estimate's error, the creep)
SWEEP_STEP_RAD = math.radians(10.0)  # headings tried along a turn's sweep


def wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class Reach:
    """Footprint checks on the map for the body whose probe is ``lead_m`` ahead
    of its centre."""

    def __init__(self, contact: WallContact, lead_m: float, margin_m: float = MARGIN_M) -> None:
        self.contact = contact
        self.lead = lead_m
        self.margin = margin_m

    def probe(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        """The probe's point for a body at ``pose`` (its centre and heading)."""
        return pose[0] + self.lead * math.cos(pose[2]), pose[1] + self.lead * math.sin(pose[2])

    def centre(self, px: float, py: float, heading: float) -> tuple[float, float]:
        return px - self.lead * math.cos(heading), py - self.lead * math.sin(heading)

    def fits(self, px: float, py: float, heading: float) -> bool:
        """The body fits with its probe at (px, py), facing ``heading``."""
        cx, cy = self.centre(px, py, heading)
        return self.contact.depth(cx, cy, heading, self.margin)[0] <= 0.0

    def probe_heading(self, px: float, py: float, way: float) -> float | None:
        """The heading to probe (px, py) with on a lane going ``way``: the lane's
        own, or the opposite (facing the edge or obstacle behind, reversing away
        from it); None when the body fits neither way (out of reach: steering the
        probe there at another heading would turn the body on the way)."""
        for h in (way, wrap(way + math.pi)):
            if self.fits(px, py, h):
                return h
        return None

    def body_blocked(self) -> np.ndarray:
        """The map's blocked cells and the free ones next to an obstacle where the
        body fits neither facing up nor down with the probe over the cell's centre
        (the shell's edges aside: the lanes take the edge rows facing the edge).
        The coverage is planned on it, so that the lanes keep the body off the
        obstacles (the cells it adds are out of the body's reach)."""
        c = self.contact
        out = c.blocked.copy()
        for r, col in zip(*np.nonzero(c.near & ~c.blocked), strict=True):
            px, py = (col + 0.5) * c.cell_m, (r + 0.5) * c.cell_m
            if all(c.obstacle_depth(*self.centre(px, py, h), h, self.margin)[0] > 0
                   for h in (math.pi / 2, -math.pi / 2)):
                out[r, col] = True
        # a column's run of free cells too short for the body to turn in place anywhere
        # in it (between an obstacle and the shell's edge, or two obstacles) cannot be
        # entered or left by a lane
        shortest = math.ceil(2 * (c.reach_m + self.margin) / c.cell_m - 1e-9)
        for col in range(c.cols):
            r = 0
            while r < c.rows:
                if out[r, col]:
                    r += 1
                    continue
                end = r
                while end < c.rows and not out[end, col]:
                    end += 1
                if end - r < shortest and (r > 0 or end < c.rows):
                    out[r:end, col] = True
                r = end
        return out

    def sweep_depth(self, cx: float, cy: float, th_from: float, th_to: float) -> float:
        """How far the footprint reaches past an edge or into an obstacle at its
        worst while the body turns in place about (cx, cy) the short way from
        ``th_from`` to ``th_to`` (≤ 0: clear)."""
        turn = wrap(th_to - th_from)
        n = max(1, math.ceil(abs(turn) / SWEEP_STEP_RAD))
        return max(self.contact.depth(cx, cy, th_from + turn * k / n, self.margin)[0]
                   for k in range(n + 1))

    def arc_depth(self, x: float, y: float, th: float, v: float, w: float, tau: float,
                  circ_m: float) -> float:
        """How far the footprint reaches past an edge or into an obstacle at its worst
        along the arc the body drives at (v, ω) for ``tau`` seconds from (x, y, θ)
        (x wrapping round ``circ_m``), sampled every SWEEP_STEP_RAD of the turn and at
        least four times: a steering turn swings the body's corners through what its
        end pose may have left behind."""
        n = max(4, math.ceil(abs(w) * tau / SWEEP_STEP_RAD))
        worst = -math.inf
        for k in range(1, n + 1):
            t = tau * k / n
            mid = th + w * t / 2
            worst = max(worst, self.contact.depth((x + v * t * math.cos(mid)) % circ_m,
                                                  y + v * t * math.sin(mid), th + w * t,
                                                  self.margin)[0])
        return worst

    def straight_depths(self, x: float, y: float, th: float, dist: float,
                        margin: float | None = None) -> list[float]:
        """The footprint's depth past an edge or into an obstacle (grown by ``margin``,
        the reach's own by default) every centimetre of a drive of ``dist`` (signed)
        along the heading from (x, y, θ), the start excluded, the end included."""
        m = self.margin if margin is None else margin
        n = max(1, math.ceil(abs(dist) / 0.01))
        c, s = math.cos(th), math.sin(th)
        return [self.contact.depth(x + dist * k / n * c, y + dist * k / n * s, th, m)[0]
                for k in range(1, n + 1)]

    def straight_reach(self, x: float, y: float, th: float, dist: float) -> float:
        """How far (signed, at most ``dist``) the body at (x, y, θ) can drive along its
        heading before its footprint, grown by the margin, reaches deeper into an edge
        or an obstacle than it is now (sampled every centimetre)."""
        now = max(0.0, self.contact.depth(x, y, th, self.margin)[0])
        n = max(1, math.ceil(abs(dist) / 0.01))
        for k in range(1, n + 1):
            d = dist * k / n
            if self.contact.depth(x + d * math.cos(th), y + d * math.sin(th), th,
                                  self.margin)[0] > now + 1e-4:
                return dist * (k - 1) / n
        return dist

    def back_off_way(self, cx: float, cy: float, th: float, th_to: float,
                     reach_m: float = 0.25) -> float:
        """+1 (forward) or −1 (back): the way along the heading that takes the
        turn's sweep out of what it touches, looked for out to ``reach_m``; 0 when
        neither does (the heading runs along it). Not only a step of 2 cm: against
        the map's cells a diagonal obstacle (the stair band) is a staircase, and a
        body's side along one of its steps touches as deep until it has passed the
        step's corner, 3–5 cm on."""
        now = self.sweep_depth(cx, cy, th, th_to)
        for d in (0.02, 0.05, 0.1, 0.15, 0.2, 0.25):
            if d > reach_m + 1e-9:
                break
            ahead = self.sweep_depth(cx + d * math.cos(th), cy + d * math.sin(th), th, th_to)
            behind = self.sweep_depth(cx - d * math.cos(th), cy - d * math.sin(th), th, th_to)
            if min(ahead, behind) <= now - 0.1 * d:
                return 1.0 if ahead < behind else -1.0
        return 0.0
