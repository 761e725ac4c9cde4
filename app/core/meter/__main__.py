"""CLI: ``python -m app.core.meter read --profile PROFILE.json IMAGE [IMAGE ...]``.

Prints one JSON object per image, one per line, in order.  Exit 0 when every input could be
opened (even if some gauges cannot be read); exit 2 with a one-line message on stderr for a
missing file, a file that is not an image or a bad profile.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import cv2
import numpy as np

from .profile import load_profile
from .reader import read_gauge


def _fail(msg: str) -> int:
    sys.stderr.write(msg.replace("\n", " ") + "\n")
    return 2


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m app.core.meter",
                                 description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    rd = sub.add_parser("read", help="read gauge images with a profile")
    rd.add_argument("--profile", required=True, help="gauge profile JSON")
    rd.add_argument("--min-confidence", type=float, default=0.5)
    rd.add_argument("images", nargs="+")
    rd.add_argument("-v", "--verbose", action="store_true")
    try:
        args = ap.parse_args(argv)
    except SystemExit as e:
        return int(e.code or 0) if e.code in (0, None) else 2
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.WARNING)
    cv2.setNumThreads(1)  # small images: threads cost more than they give
    try:
        prof = load_profile(args.profile)
    except ValueError as e:
        return _fail(f"error: bad profile: {e}")
    images = []
    for p in args.images:
        path = Path(p)
        if not path.is_file():
            return _fail(f"error: no such file: {p}")
        data = np.fromfile(str(path), dtype=np.uint8)
        img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
        if img is None:
            return _fail(f"error: not an image: {p}")
        images.append((p, img))
    for p, img in images:
        r = read_gauge(img, prof, min_confidence=args.min_confidence)
        out = {"image": p, "value": None if r.value is None else round(r.value, 6),
               "unit": r.unit, "confidence": round(r.confidence, 4), "error": r.error}
        sys.stdout.write(json.dumps(out) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
