"""Scores and diagnosis of the poses mapped on a drawn log (bench/synth_carmen.py,
bench/synth_diagnosis.py): ATE and RPE against the drawn reference, the kind of
place each scan is taken in, the worst stretches, and the online steps' errors."""

from __future__ import annotations

import math

import numpy as np

from app.core.localisation.evaluate import align_rigid, ate_m, rpe
from app.core.localisation.se2 import relative

USABLE_M = 30.0  # the reader's usable range (preprocess.py max_range_m)


def score(est: np.ndarray, ref: np.ndarray) -> tuple[float, float, float, float, float]:
    r1, r10 = rpe(est, ref, 1.0), rpe(est, ref, 10.0)
    return ate_m(est, ref), 100 * r1.trans_m, r1.rot_deg, 100 * r10.trans_m, r10.rot_deg


def place_kinds(true_ranges: np.ndarray, angles: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Per scan of true ranges: "open" (over 40 % of the beams return nothing
    within the usable range), "corridor" (its wall normals hold one
    direction under a tenth of the other: matching is degenerate along it),
    else "room"; and that ratio of the weakest to the strongest direction."""
    kinds, ratios = [], []
    for r in true_ranges:
        ok = np.isfinite(r) & (r < USABLE_M)
        if ok.mean() < 0.6:
            kinds.append("open")
            ratios.append(math.nan)
            continue
        rr = np.where(ok, r, 0.0)
        xy = np.c_[rr * np.cos(angles), rr * np.sin(angles)]
        d = np.diff(xy, axis=0)
        good = ok[1:] & ok[:-1] & (np.abs(np.diff(rr)) < 0.2)
        t = d[good] / np.maximum(np.hypot(*d[good].T), 1e-9)[:, None]
        n = np.c_[-t[:, 1], t[:, 0]]
        ev = np.linalg.eigvalsh(n.T @ n) if len(n) else np.zeros(2)
        ratio = float(ev[0] / max(ev[1], 1e-9))
        ratios.append(ratio)
        kinds.append("corridor" if ratio < 0.1 else "room")
    return kinds, np.array(ratios)


def aligned_errors(est: np.ndarray, ref: np.ndarray) -> np.ndarray:
    r, t = align_rigid(est[:, :2], ref[:, :2])
    return np.hypot(*(est[:, :2] @ r.T + t - ref[:, :2]).T)


def rpe_per_start(est: np.ndarray, ref: np.ndarray, delta_m: float) -> np.ndarray:
    """(start, end, translation m, rotation deg) of each RPE pair."""
    path = np.r_[0.0, np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))]
    out = []
    for i in range(len(ref)):
        j = int(np.searchsorted(path, path[i] + delta_m))
        if j >= len(ref):
            break
        d = relative(relative(ref[i], ref[j]), relative(est[i], est[j]))
        out.append((i, j, math.hypot(d[0], d[1]), abs(math.degrees(float(d[2])))))
    return np.array(out).reshape(-1, 4)


def diagnose(est: np.ndarray, ref: np.ndarray, kinds: list[str], ratios: np.ndarray) -> None:
    path = np.r_[0.0, np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))]
    err = aligned_errors(est, ref)
    over = np.where(err > 0.25)[0]
    print(f"      aligned error: median {np.median(err):.3f} m, max {err.max():.3f} m at scan "
          f"{int(np.argmax(err))} ({path[int(np.argmax(err))]:.0f} m); "
          f"{len(over)} of {len(err)} scans over 0.25 m")
    pairs = rpe_per_start(est, ref, 10.0)
    taken: list[tuple[int, int]] = []
    for row in pairs[np.argsort(-pairs[:, 2])]:
        i, j = int(row[0]), int(row[1])
        if any(i < b and a < j for a, b in taken):
            continue
        taken.append((i, j))
        ks = kinds[i:j + 1]
        counts = ", ".join(f"{k} {ks.count(k)}" for k in ("corridor", "room", "open")
                           if ks.count(k))
        rr = ratios[i:j + 1]
        rr = rr[np.isfinite(rr)]
        print(f"      worst RPE10 stretch: scans {i}-{j} ({path[i]:.0f}-{path[j]:.0f} m): "
              f"{100 * row[2]:.1f} cm / {row[3]:.2f} deg; places: {counts}; "
              f"weakest normal ratio {rr.min() if len(rr) else math.nan:.3f}")
        if len(taken) == 3:
            break


def step_errors(est: np.ndarray, odo: np.ndarray, ref: np.ndarray,
                kinds: list[str]) -> None:
    """The online steps (each scan's estimate as the mapper made it, before
    any loop closure) against the drawn ones, by the kind of place the step
    ends in: along the step (+: too long) and across it, mean and RMS in cm,
    beside odometry's."""
    def errs(p):
        out = []
        for k in range(1, len(ref)):
            t, e = relative(ref[k - 1], ref[k]), relative(p[k - 1], p[k])
            n = math.hypot(t[0], t[1])
            u = t[:2] / n if n > 0.2 else np.array([1.0, 0.0])
            d = e[:2] - t[:2]
            out.append((float(d @ u), float(u[0] * d[1] - u[1] * d[0])))
        return np.array(out)
    eo, ee = errs(odo), errs(est)
    ks = np.array(kinds[1:])
    for kind in ("corridor", "room", "open"):
        m = ks == kind
        if m.sum() < 5:
            continue
        print(f"      online steps in {kind} ({m.sum()}): along {100 * ee[m, 0].mean():+.1f} "
              f"(RMS {100 * np.sqrt(np.mean(ee[m, 0] ** 2)):.1f}), across RMS "
              f"{100 * np.sqrt(np.mean(ee[m, 1] ** 2)):.1f} cm; odometry along "
              f"{100 * eo[m, 0].mean():+.1f} (RMS {100 * np.sqrt(np.mean(eo[m, 0] ** 2)):.1f}) cm")
    big = np.hypot(ee[:, 0], ee[:, 1])
    worst = np.argsort(-big)[:4]
    print(f"      online steps off by over 10 cm: {int(np.sum(big > 0.1))} of {len(big)}; worst: "
          + ", ".join(f"scan {k + 1} {100 * big[k]:.0f} cm ({ks[k]})" for k in worst))
