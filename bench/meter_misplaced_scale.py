"""A scale found turned towards its maximum, the needle just above the true minimum: is it
taken for a needle resting on its stop pin (issue 11)?

Against the profile's angles (no clicks), a needle found more than 5 deg below the minimum
reads the minimum, out to the stop pin's tolerance (``app/core/meter/stop_pin.py``), only
where the ring of scale marks is bare round it.  Here that test is put to the case it must
refuse: each frame shows a needle on the scale, 2-10 % of the span above the minimum (no
stop pin), and the fit of the profile's arc is replaced by itself turned towards the
maximum so far that the needle lies 5.5 deg to the pin tolerance below the minimum found.
The scale path, which reads such a dial by its own ticks, is left out, so the reading
against the profile's angles decides.  A reading more than 2 % FS off with a ``stop_pin``
score is one the gap test let through; one at the minimum without it was within the 5 deg
read as the minimum before the test (the turn drawn landed the needle less than 5 deg
below the minimum found); others read the needle elsewhere against the turned arc (the
other end of a two-ended needle), the turn's doing.  Refusals are counted by reason.
Tuning families only (or, with ``--families``, a former held-out family); never the
held-out family.

    PYTHONPATH=$PWD python bench/meter_misplaced_scale.py --n 60 --seed 1 [--level field]
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import app.core.meter as meter  # noqa: E402
from app.core.meter import angles, reader  # noqa: E402
from app.core.meter.reading import refuse  # noqa: E402
from app.core.meter.stop_pin import pin_tolerance  # noqa: E402
from bench.meter_rows import WRONG_PCT_FS  # noqa: E402
from sim_robot.gauge_scene import _level_pose_look, compose  # noqa: E402
from sim_robot.gauge_styles import (  # noqa: E402
    HELD_OUT_CHOICES,
    HELD_OUT_FAMILY,
    TUNING_FAMILIES,
    random_style,
)

FAMILIES = (*TUNING_FAMILIES, *(f for f in HELD_OUT_CHOICES if f != HELD_OUT_FAMILY))


def _reason(err: str) -> str:
    """A refusal's first reason, its figures left out (the gap test's own, if it spoke)."""
    first = err.split("; ")[0]
    if "deg below the minimum: " in first:
        first = "gap test: " + first.split("minimum: ", 1)[1]
    first = re.sub(r"\s*\([^()]*\)", "", first).rstrip(")")  # what is in brackets
    return re.sub(r"[-+]?\d+(\.\d+)?", "#", first)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--level", default="field", choices=("clean", "field", "hard"))
    ap.add_argument("--families", default=",".join(TUNING_FAMILIES))
    ap.add_argument("-v", "--verbose", action="store_true", help="list every frame")
    a = ap.parse_args()
    fams = a.families.split(",")
    if any(f not in FAMILIES for f in fams):
        ap.error(f"families are {', '.join(FAMILIES)} (never the held-out {HELD_OUT_FAMILY})")
    turn = {"deg": 0.0}
    fit = angles.fit_profile_arc

    def turned(*args, **kw):
        f = fit(*args, **kw)
        return f if f.rho_deg is None else replace(f, rho_deg=f.rho_deg + turn["deg"])

    angles.fit_profile_arc = turned
    reader._scale_reading = lambda res, prof, *args, **kw: refuse(prof.unit, "left out")
    rng = np.random.default_rng([a.seed, 77])
    tally: dict[str, int] = {}
    for i in range(a.n):
        fam = fams[i % len(fams)]
        s = replace(random_style(fam, rng), stop_pin=False)
        u = float(rng.uniform(0.02, 0.10))
        value = s.min_value + u * (s.max_value - s.min_value)
        size, pose, look, kind = _level_pose_look(a.level, rng, fam)
        img, truth = compose(s, value, rng, frame_size=size, pose=pose, look=look,
                             backdrop=kind)
        prof = meter.load_profile(truth["profile"])
        delta = u * prof.span_deg + float(rng.uniform(5.5, pin_tolerance(prof.span_deg) - 0.3))
        turn["deg"] = delta if prof.clockwise else -delta
        r = meter.read_gauge(img, prof, learned_fallback=False)
        if r.value is None:
            key = "refused: " + _reason(r.error or "")
        else:
            off = abs(r.value - truth["value"]) / truth["full_scale"] * 100.0
            if off <= WRONG_PCT_FS:
                key = "read within 2 % FS"
            elif "stop_pin" in r.scores:
                key = "WRONG: read as resting on the pin (the gap test let it through)"
            elif r.value == s.min_value:
                key = "WRONG: read as the minimum within 5 deg below it (as before)"
            else:
                key = "WRONG: read elsewhere (the turn forced on the fit, not the gap test)"
        tally[key] = tally.get(key, 0) + 1
        if a.verbose or key.startswith("WRONG"):
            print(f"#{i} {truth['style']} {u:.3f} of the span up, turned {delta:.1f} deg: "
                  f"{key} {r.value} conf {r.confidence} {r.error or ''}")
    print(f"misplaced scales, {a.level}, n={a.n}, seed={a.seed}, families {a.families}:")
    for k, v in sorted(tally.items(), key=lambda kv: -kv[1]):
        print(f"  {v:4d}  {k}")


if __name__ == "__main__":
    main()
