"""CLI: ``python -m app.core.meter read --profile PROFILE.json IMAGE [IMAGE ...]``.

Prints one JSON object per image, one per line, in order:
``{"image", "value", "unit", "confidence", "error"}``.  An image that cannot be opened (a
missing file, a file that is not an image) gets its own line with the error and the batch
goes on.  Exit 0 when every image could be opened (even if some gauges cannot be read),
1 when some could not, 2 with a one-line message on stderr for bad arguments or a bad
profile (a calibrated profile's reference image is resolved relative to the profile file).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import cv2
import numpy as np

from .calibrated import prepare
from .profile import load_profile
from .reader import read_gauge

log = logging.getLogger(__name__)


def _fail(msg: str) -> int:
    sys.stderr.write(msg.replace("\n", " ") + "\n")
    return 2


def _open(p: str) -> tuple[np.ndarray | None, str | None]:
    """The image at ``p`` (BGR), or None and why it could not be opened."""
    path = Path(p)
    if not path.is_file():
        return None, "no such file"
    try:
        data = np.fromfile(str(path), dtype=np.uint8)
    except OSError as e:
        return None, f"cannot read file ({e.strerror or e})"
    img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if img is None:
        return None, "not an image"
    return img, None


def _line(p: str, unit: str, value=None, confidence: float = 0.0, error=None) -> None:
    out = {"image": p, "value": None if value is None else round(value, 6), "unit": unit,
           "confidence": round(confidence, 4), "error": error}
    sys.stdout.write(json.dumps(out) + "\n")
    sys.stdout.flush()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m app.core.meter",
                                 description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    rd = sub.add_parser("read", help="read gauge images with a profile")
    rd.add_argument("--profile", required=True, help="gauge profile JSON")
    rd.add_argument("--min-confidence", type=float, default=0.5)
    rd.add_argument("--learned-confirm", action="store_true",
                    help="let the learned keypoints confirm a reading against the profile's "
                         "angles where the classical estimates leave it open")
    rd.add_argument("--learned-fallback", action=argparse.BooleanOptionalAction, default=True,
                    help="where the classical reader refuses, try the learned keypoints on "
                         "their own, with the error bound they state (on by default; "
                         "--no-learned-fallback for the classical reader alone)")
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
    # the reference frame's geometry found before the first image, not on it
    why = prepare(prof) if prof.calibration is not None else None
    if why is not None:
        log.warning("reference not prepared (the reads will say why): %s", why)
    status = 0
    for p in args.images:
        img, why = _open(p)
        if img is None:
            status = 1
            _line(p, prof.unit, error=why)
            continue
        try:
            r = read_gauge(img, prof, min_confidence=args.min_confidence,
                           learned_fallback=args.learned_fallback,
                           learned_confirm=args.learned_confirm)
        except Exception as e:  # noqa: BLE001 - one image must not end the batch
            log.exception("reading %s failed", p)
            status = 1
            _line(p, prof.unit, error=f"reader failed: {e}")
            continue
        _line(p, r.unit, r.value, r.confidence, r.error)
    return status


if __name__ == "__main__":
    sys.exit(main())
