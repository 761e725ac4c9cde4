"""Contact fixes logged through the link, replayed off line: for each, the belief's
error before, after the fix the run made (logged), after the weighted mean of the
touching poses (the fix before; replayed) and after the fix now (the mode, only the
faces the body was driving into; replayed) — and, where the run's belief was off by
more than it knew, a run of contacts it could not explain, replayed through
``ContactFixes`` (the widened search).

The cases are the contact fixes of 3 cm or more that ``bench/climber_link_bench.py
--contact-log F`` wrote (the belief before and after, its σ in x and y where the
log has them, the true pose, the speed last commanded), on the tank (seed 0, 30x:
the run of the section "The tank with the corrected-track filing and a fix log" in
docs/climber.md, a run of the mode on main, and a run of main with the σ logged) and
on the 6 m × 4.8 m wall with the manhole (seed 1, 10x). Each is replayed on a fresh
``WallEkf`` at the logged belief with the logged σ (the first run's log has none:
σ_x 4, 8 and 12 cm, σ_y 2 cm). The true pose is for judging only.

``--lanes``: the stair band's real geometry, synthetic: the belief on a lane's centre
(as the relay drives it), the truth ``e`` off it on the side from which the body
meets the band (climbing into its lower side: the truth −x of the belief, the lane
clear of the band by the moves' 2 cm as the belief has it), the body stopped where
its footprint first touches; the mean |x error| after each fix, per ``e``.

    PYTHONPATH=$PWD python bench/contact_fix_replay.py [--lanes] [--log FILE --wall W]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.core.localisation.contact_fix import (  # noqa: E402
    ContactFixConfig,
    ContactFixes,
    contact_fix,
)
from app.core.localisation.wall_ekf import WallEkf  # noqa: E402
from app.core.planner.coverage.wall import rasterise  # noqa: E402
from bench.climber_link_bench import setup  # noqa: E402
from sim_robot.climber.contact import WallContact  # noqa: E402
from sim_robot.climber.kinematics import ClimberParams  # noqa: E402

# (wall, run, sim t, belief before, belief after (logged), true, σ (x, y) before or None,
# speed last commanded)
CASES = [
    ("tank", "A", 4451.0, [72.649, 9.258, 1.568], [72.587, 9.26, 1.568], [72.606, 9.256, 1.57], None, 0.112),  # noqa: E501
    ("tank", "A", 5682.05, [71.85, 8.661, 1.569], [71.788, 8.666, 1.569], [71.826, 8.656, 1.571], None, 0.089),  # noqa: E501
    ("tank", "A", 7176.0, [71.144, 8.241, -1.562], [71.069, 8.261, -1.562], [71.131, 8.258, -1.559], None, -0.089),  # noqa: E501
    ("tank", "A", 8848.55, [69.852, 7.561, 1.596], [69.795, 7.56, 1.596], [69.829, 7.559, 1.597], None, 0.092),  # noqa: E501
    ("tank", "A", 10386.8, [69.142, 7.148, -1.557], [69.074, 7.155, -1.557], [69.112, 7.158, -1.554], None, -0.03),  # noqa: E501
    ("tank", "A", 12423.15, [67.237, 6.039, -1.552], [67.145, 6.057, -1.552], [67.227, 6.059, -1.55], None, -0.05),  # noqa: E501
    ("tank", "A", 15573.05, [64.747, 4.649, 1.524], [64.648, 4.651, 1.524], [64.717, 4.65, 1.526], None, 0.121),  # noqa: E501
    ("tank", "A", 21783.25, [59.35, 1.596, 2.477], [59.292, 1.615, 2.477], [59.335, 1.611, 2.479], None, 0.0),  # noqa: E501
    ("tank", "A", 26234.35, [65.57, 0.625, -1.018], [65.61, 0.626, -1.018], [65.614, 0.61, -1.027], None, 0.101),  # noqa: E501
    ("tank", "A", 30300.75, [10.261, 0.765, -1.305], [10.23, 0.765, -1.305], [10.248, 0.773, -1.307], None, 0.15),  # noqa: E501
    ("tank", "A", 90578.67, [51.029, 0.249, -0.655], [51.029, 0.189, -0.655], [51.029, 0.191, -0.655], None, 0.0),  # noqa: E501
    ("tank", "A", 97961.15, [57.45, 2.244, -1.572], [57.532, 2.243, -1.572], [57.473, 2.244, -1.57], None, 0.111),  # noqa: E501
    ("tank", "A", 99866.75, [59.25, 3.245, -1.572], [59.321, 3.242, -1.572], [59.271, 3.244, -1.571], None, 0.068),  # noqa: E501
    ("tank", "A", 112810.05, [62.395, 5.003, -2.245], [62.427, 4.99, -2.245], [62.398, 4.994, -2.244], None, 0.106),  # noqa: E501
    ("tank", "A", 115369.1, [57.893, 2.393, -2.227], [57.861, 2.393, -2.227], [57.899, 2.393, -2.226], None, 0.114),  # noqa: E501
    ("tank", "A", 117793.15, [54.351, 0.359, -1.58], [54.39, 0.319, -1.58], [54.388, 0.345, -1.58], None, 0.131),  # noqa: E501
    ("tank", "A", 126861.25, [24.629, 0.933, 0.009], [24.707, 0.921, 0.009], [24.655, 0.919, 0.01], None, 0.091),  # noqa: E501
    ("tank", "A", 150154.05, [2.558, 0.461, -3.133], [2.564, 0.589, -3.133], [2.557, 0.5, -3.131], None, -0.056),  # noqa: E501
    ("tank", "B", 11124.9, [68.256, 6.647, 1.622], [68.216, 6.657, 1.622], [68.234, 6.663, 1.624], [0.1177, 0.0433], 0.126),  # noqa: E501
    ("tank", "C", 4444.45, [72.65, 9.255, 1.571], [72.588, 9.257, 1.571], [72.604, 9.256, 1.572], [0.1165, 0.0282], 0.119),  # noqa: E501
    ("tank", "C", 4708.29, [72.57, 0.251, -2.628], [72.57, 0.182, -2.628], [72.571, 0.184, -2.627], [0.0197, 0.2089], 0.0),  # noqa: E501
    ("tank", "C", 5685.4, [71.85, 8.649, 1.57], [71.775, 8.666, 1.57], [71.826, 8.656, 1.572], [0.1031, 0.0376], 0.125),  # noqa: E501
    ("tank", "C", 7102.9, [71.153, 8.266, 1.588], [71.09, 8.268, 1.588], [71.132, 8.259, 1.591], [0.097, 0.0329], 0.102),  # noqa: E501
    ("tank", "C", 8830.4, [69.851, 7.567, 1.58], [69.802, 7.561, 1.58], [69.822, 7.557, 1.581], [0.095, 0.012], 0.092),  # noqa: E501
    ("tank", "C", 9835.5, [69.172, 7.183, 1.71], [69.139, 7.179, 1.71], [69.149, 7.183, 1.712], [0.0901, 0.0062], 0.052),  # noqa: E501
    ("6x4.8 manhole", "D", 5961.84, [2.638, 0.377, -1.108], [2.648, 0.407, -1.108], [2.652, 0.413, -1.109], [0.0677, 0.0311], 0.0),  # noqa: E501
]
RUNS = {"A": "tank, main at 17427eb (log without σ)", "B": "tank, main at 981e280 with the mode",
        "C": "tank, main at ab84df0", "D": "6 m × 4.8 m with the manhole, the mode"}
SIGMAS = [(0.04, 0.02), (0.08, 0.02), (0.12, 0.02)]  # run A's log has no σ: these
# run A's end (150 268 s on): the body against the shell's bottom edge, the belief 0.18 m
# higher beside the manhole at (3.0, 0.9); (belief, true, speed last commanded)
STUCK = [
    ([2.894, 0.36, 1.214], [2.892, 0.18, 1.216], -0.061),
    ([2.894, 0.371, 1.03], [2.892, 0.19, 1.029], -0.073),
    ([2.89, 0.358, 1.256], [2.888, 0.177, 1.255], -0.062),
    ([2.89, 0.367, 1.143], [2.888, 0.185, 1.14], -0.101),
    ([2.887, 0.35, 1.365], [2.885, 0.168, 1.36], -0.077),
    ([2.887, 0.361, 1.223], [2.885, 0.18, 1.223], -0.086),
    ([2.89, 0.372, 1.053], [2.889, 0.19, 1.052], 0.0),
    ([2.89, 0.372, 1.053], [2.889, 0.19, 1.052], -0.08),
]
STUCK_SIGMA = (0.02, 0.01)  # not logged: the floor a surprise opens y to is 1 cm
BEFORE = ContactFixConfig(estimate="mean")
NOW = ContactFixConfig()


def wall_contact(name: str) -> WallContact:
    parts = name.split()
    spec = setup(parts[0], "stair" in parts, "manhole" in parts).spec
    p = ClimberParams()
    return WallContact(spec, rasterise(spec), p.length_m, p.width_m)


def _ekf(belief, sigma) -> WallEkf:
    ekf = WallEkf(*belief)
    ekf.open_variance(0, sigma[0])
    ekf.open_variance(1, sigma[1])
    return ekf


def replay(contact: WallContact, belief, sigma, cfg: ContactFixConfig, moving: float):
    """The belief after one contact fix from ``belief`` with σ ``sigma``."""
    ekf = _ekf(belief, sigma)
    fix = contact_fix(ekf, lambda x, y, th, g: contact.depth(x, y, th, g)[0], cfg, moving)
    return ekf.pose, fix


def err(pose, true) -> tuple[float, float]:
    return pose[0] - true[0], pose[1] - true[1]


def fmt(e) -> str:
    return f"({100 * e[0]:+5.1f}, {100 * e[1]:+5.1f})"


def logged_cases(walls: dict) -> None:
    print("the logged contact fixes: error (x, y) in cm, believed − true; 'mean' replays the "
          "fix before, 'mode' the mode, 'now' the mode on the faces driven into")
    print(f"{'run':3} {'t s':>9} {'σ cm':>10} {'before':>14} {'logged':>14} {'mean':>14} "
          f"{'mode':>14} {'now':>14}  verdict (|e| now against before)")
    rows = []
    for wall, run, t, before, after, true, sd, v in CASES:
        contact = walls.setdefault(wall, wall_contact(wall))
        for sigma in [sd] if sd else SIGMAS:
            (pm, _), (po, _), (pn, fn) = (replay(contact, before, sigma, cfg, mv)
                                          for cfg, mv in ((BEFORE, 0.0), (NOW, 0.0), (NOW, v)))
            eb, el, em, en = err(before, true), err(after, true), err(pm, true), err(pn, true)
            eo = err(po, true)
            nb, nm, nn = math.hypot(*eb), math.hypot(*em), math.hypot(*en)
            verdict = "worse" if nn > nb + 0.005 else "better" if nn < nb - 0.005 else "same"
            print(f"{run:3} {t:9.0f} {100 * sigma[0]:4.1f},{100 * sigma[1]:4.1f} {fmt(eb)} "
                  f"{fmt(el)} {fmt(em)} {fmt(eo)} {fmt(en)}  {verdict}"
                  f"{'' if fn.fixed else ' (no fix: ' + fn.why + ')'}")
            rows.append((run, sigma, nb, nm, nn, math.hypot(*eo)))
    for label, keep in (("all", lambda r: True), ("σ logged (runs B–D)", lambda r: r[0] != "A"),
                        *((f"run A, σ_x {100 * s[0]:.0f} cm", lambda r, s=s: r[0] == "A"
                           and r[1] == s) for s in SIGMAS)):
        sel = [r for r in rows if keep(r)]
        if not sel:
            continue
        b, m, n, o = (np.array([r[k] for r in sel]) for k in (2, 3, 4, 5))
        print(f"  {label}: {len(sel)} cases; mean |error| before {100 * b.mean():.1f} cm, mean "
              f"{100 * m.mean():.1f} cm ({int((m > b + 0.005).sum())} worse), mode "
              f"{100 * o.mean():.1f} cm ({int((o > b + 0.005).sum())} worse), now "
              f"{100 * n.mean():.1f} cm ({int((n > b + 0.005).sum())} worse); worst after: "
              f"mean {100 * m.max():.1f}, now {100 * n.max():.1f} cm")


def stuck(walls: dict) -> None:
    """Run A's end, replayed through ContactFixes (before: the mean, no widening)."""
    contact = walls.setdefault("tank", wall_contact("tank"))

    def depth(x, y, th, g):
        return contact.depth(x, y, th, g)[0]
    print("\nrun A's end: contacts against the bottom edge with the belief 0.18 m high "
          f"(σ {100 * STUCK_SIGMA[0]:.0f}, {100 * STUCK_SIGMA[1]:.0f} cm, not logged)")
    for label, fixer, use_v in (("before", ContactFixes(BEFORE, wide_after=10**9), False),
                                ("now", ContactFixes(NOW), True)):
        for k, (belief, true, v) in enumerate(STUCK):
            ekf = _ekf(belief, STUCK_SIGMA)
            fix = fixer.on_contact(ekf, depth, v if use_v else 0.0)
            e0, e1 = err(belief, true), err(ekf.pose, true)
            print(f"  {label:6} contact {k + 1}: v {v:+.3f}; error {fmt(e0)} → {fmt(e1)} cm; "
                  f"{'fixed' if fix.fixed else fix.why}")
            if fix.fixed:
                break


def lanes(walls: dict) -> None:
    """The stair band's real geometry (see the module's doc)."""
    contact = walls.setdefault("tank", wall_contact("tank"))

    def depth(x, y, th, g=0.0):
        return contact.depth(x, y, th, g)[0]
    th = math.pi / 2
    print("\nthe stair band, synthetic: the belief on a lane's centre, the truth e to its -x, "
          "climbing into the band's lower side (σ 8, 1.5 cm); mean |x error| after, cm")
    print(f"{'e cm':>5} {'cases':>5} {'before':>7} {'mean':>6} {'now':>6} {'mean worse':>10} "
          f"{'now worse':>9}")
    for e in (0.01, 0.02, 0.03, 0.04, 0.06, 0.08, 0.13):
        got = []
        for c in range(560, 715):
            lane = (c + 0.5) * 0.1
            xt, yt = lane - e, 0.5
            while depth(xt, yt + 0.002, th) <= 0.0 and yt < 9.5:
                yt += 0.002
            if yt >= 9.5 or depth(lane, yt, th, 0.02) > 0.0:
                continue  # the body would not have met the band: the belief stops first
            out = []
            for cfg, v in ((BEFORE, 0.0), (NOW, 1.0)):
                pose, _ = replay(contact, (lane, yt, th), (0.08, 0.015), cfg, v)
                out.append(abs(pose[0] - xt))
            got.append((e, *out))
        if not got:
            print(f"{100 * e:5.0f} {0:5d}  (the belief and the truth on one tread: no contact)")
            continue
        g = np.array(got)
        print(f"{100 * e:5.0f} {len(g):5d} {100 * e:7.1f} {100 * g[:, 1].mean():6.1f} "
              f"{100 * g[:, 2].mean():6.1f} {int((g[:, 1] > e + 0.005).sum()):10d} "
              f"{int((g[:, 2] > e + 0.005).sum()):9d}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lanes", action="store_true", help="the stair band, synthetic (above)")
    ap.add_argument("--log", help="a --contact-log file: its contact fixes instead of the cases")
    ap.add_argument("--wall", default="tank", help="the log's wall: tank, or e.g. '6x4.8 "
                    "manhole', '8x2.4 stair'")
    a = ap.parse_args(argv)
    walls: dict = {}
    if a.log:
        CASES.clear()
        lines = [json.loads(s) for s in Path(a.log).read_text().splitlines() if s.strip()]
        for k, d in enumerate(lines):
            if d.get("fix") == "contact":
                v = next((e["last_v"] for e in lines[k + 1:k + 3] if "last_v" in e
                          and e["t"] == d["t"]), 0.0)
                CASES.append((a.wall, "L", d["t"], d["before"], d["after"], d["true"],
                              d.get("sd_before"), v))
    logged_cases(walls)
    if not a.log:
        stuck(walls)
    if a.lanes:
        lanes(walls)


if __name__ == "__main__":
    main()
