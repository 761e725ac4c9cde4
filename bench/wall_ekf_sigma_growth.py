"""How the wall EKF's σ_y grows with no height fix, and which state makes it grow.

The filter (app/core/localisation/wall_ekf.py) is driven through synthetic moves like the
relay's mop-up (turns in place at 0.5 rad/s, straight moves at 5 cm/s, 20 Hz reports, a
gravity heading each report) with no seam, edge or rim fix, for T simulated seconds, and
σ_y is printed with the slip states' covariance kept, or zeroed at every report (their
share of σ_y removed), and with their random walk off. Then the cell-step pattern again,
a height fix of σ 1 cm taken each time σ_y passes D/2 = 5 cm: how often one is needed, with
the slip states' random walk per √s as the filter has it and smaller, and per √m of wheel
arc instead (0.009 /√m is about the filter's 0.002 /√s at these speeds: 0.05 m/s straight,
the wheels' 0.055 m/s in a turn in place) (the simulator's body draws
each turn's slip factors afresh, 15 % about fixed values: no walk at all).

    PYTHONPATH=$PWD python bench/wall_ekf_sigma_growth.py [T_s]
"""

from __future__ import annotations

import math
import sys

import numpy as np

from app.core.localisation.wall_ekf import K_CREEP, K_DOWN, K_UP, WallEkf, WallNoise

B = 0.22  # the track (m)
DT, V, W = 0.05, 0.05, 0.5
Q = math.pi / 2
PATTERNS = {
    "turns in place only (±90°)": [("turn", Q), ("turn", -Q)],
    "up/down 0.3 m, 180° in place between": [("drive", 0.3), ("turn", Q), ("turn", Q),
                                              ("drive", 0.3), ("turn", -Q), ("turn", -Q)],
    "cell steps (0.1 m) up, along, down, along, a 90° turn each":
        [("drive", 0.1), ("turn", -Q), ("drive", 0.1), ("turn", -Q),
         ("drive", 0.1), ("turn", Q), ("drive", 0.1), ("turn", Q)],
}


def drive(ekf: WallEkf, seq, T: float, zero=(), fix_above: float | None = None):
    """Drive ``seq`` over and over for ``T`` s; returns the turns made and the fixes taken."""
    t, th, i, turns, fixes = 0.0, math.pi / 2, 0, 0, 0
    h = np.zeros((1, ekf.n))
    h[0, 1] = 1.0
    while t < T:
        kind, amt = seq[i % len(seq)]
        i += 1
        turns += kind == "turn"
        for _ in range(max(1, round(abs(amt) / ((W if kind == "turn" else V) * DT)))):
            if kind == "turn":
                om = math.copysign(W, amt)
                ekf.advance(DT, -om * B / 2 * DT, om * B / 2 * DT, om)
                th += om * DT
            else:
                ekf.advance(DT, V * DT, V * DT, 0.0)
            ekf.update_gravity_heading(th)
            for k in zero:
                ekf._p[k, :] = 0.0
                ekf._p[:, k] = 0.0
            t += DT
        if fix_above is not None and math.sqrt(ekf.covariance[1, 1]) > fix_above:
            ekf.update(np.array([ekf.state[1]]), h, np.array([[0.01**2]]))
            fixes += 1
    return turns, fixes


def main() -> None:
    T = float(sys.argv[1]) if len(sys.argv) > 1 else 1000.0
    for name, seq in PATTERNS.items():
        print(f"{name}, {T:.0f} s, no height fix:")
        for label, kw in (("as is", {}), ("k_creep's share only", {"zero": (K_UP, K_DOWN)}),
                          ("k_up, k_down's share only", {"zero": (K_CREEP,)}),
                          ("no slip states", {"zero": (K_UP, K_DOWN, K_CREEP)}),
                          ("slip walk 0", {"wall": WallNoise(slip_walk=0.0,
                                                             slip_walk_per_m=0.0)})):
            ekf = WallEkf(5.0, 2.0, math.pi / 2, track_m=B, wall=kw.pop("wall", None))
            drive(ekf, seq, T, **kw)
            p = ekf.covariance
            print(f"  {label:26s} σ_y {math.sqrt(p[1, 1]):7.3f} m  σ_x {math.sqrt(p[0, 0]):.3f} m"
                  f"  σ(k_creep) {math.sqrt(p[K_CREEP, K_CREEP]):.3f}")
    print("cell steps with a height fix whenever σ_y > 5 cm:")
    d = WallNoise()
    walks = [(d.slip_walk, d.slip_walk_per_m, "the filter's")]
    walks += [(w, 0.0, "") for w in (0.001, 0.0005, 0.0002)]
    walks += [(0.0, m, "") for m in (0.009, 0.006, 0.003, 0.0015)]
    for per_s, per_m, label in walks:
        ekf = WallEkf(5.0, 2.0, math.pi / 2, track_m=B,
                      wall=WallNoise(slip_walk=per_s, slip_walk_per_m=per_m))
        turns, fixes = drive(ekf, PATTERNS[next(reversed(PATTERNS))], T, fix_above=0.05)
        print(f"  slip walk {per_s:.4f} /√s + {per_m:.4f} /√m {label:>12s}: {fixes} fixes in "
              f"{T:.0f} s ({turns} turns: one every {turns / max(fixes, 1):.0f} turns); "
              f"σ(k_creep) at the end {math.sqrt(ekf.covariance[K_CREEP, K_CREEP]):.4f}")


if __name__ == "__main__":
    main()
