"""The learned keypoints (:mod:`.keypoints`) in the uncalibrated reader (:mod:`.reader`):
their confirmation of the profile's angles on a normalised crop, their reading where the
classical paths refuse, and the order of the two on a crop.

On a crop the keypoints look at the whole image, whatever the classical paths found, so
their reading can be made at any point of a crop's reading and gives the same answer.  It
is asked for after the classical paths refuse the crop's first view and before any
classical retry (the dial search's other rims, a second look about the scale ring's
centre): a retry is made only where the keypoints refuse too.  On an oblique crop whose
scale finder found the ticks over another arc than the profile's, where the profile's
angles mostly refuse, they are asked before the profile's angles as well (docs/
meter-bench.md, "the learned keypoints before the classical retries, and before a
foreseen refusal").
"""

from __future__ import annotations

import cv2
import numpy as np

from .dial import NORM_SIZE
from .pointer import CENTRE as _C
from .profile import GaugeProfile
from .reading import Reading, elapsed_ms

__all__ = ["FORESEE_ARC_REFUSAL", "LEARNED_BEFORE_RETRIES", "crop_keypoints",
           "keypoint_fallback", "keypoint_reading", "learned_once"]

# where the classical path refuses a crop's first view, the learned keypoints read it before
# any classical retry (a second look about the scale ring's centre, the dial search's other
# rims); a retry is made only where they refuse too.  False: every classical path first
LEARNED_BEFORE_RETRIES = True
# an oblique crop whose scale finder found its ticks over another arc than the profile's:
# the profile's angles refuse most of these, so the keypoints read it before them too
# (:func:`.reader._finish`).  False: the profile's angles first there as well
FORESEE_ARC_REFUSAL = True


def learned_once(colour: np.ndarray, prof: GaugeProfile, min_confidence: float, t0: float):
    """A callable giving the learned keypoints' reading of a crop (:func:`keypoint_reading`,
    which on a crop looks at the whole image, whatever the classical paths found), made on
    first use and kept: a refusal, asked again, costs nothing."""
    memo: list = []

    def get() -> Reading:
        if not memo:
            memo.append(keypoint_reading(colour, prof, min_confidence, t0))
        return memo[0]

    return get


def crop_keypoints(colour: np.ndarray | None, full: np.ndarray, mirror: bool):
    """A callable giving the learned keypoints on the normalised crop (``full``: input ->
    crop), computed once on first use; None from it when the model is unavailable."""
    cache: list = []

    def get():
        if not cache:
            from .keypoints import load_model, predict_keypoints

            net, _ = load_model()
            if net is None or colour is None:
                cache.append(None)
            else:
                bgr = colour if colour.ndim == 3 else cv2.cvtColor(colour, cv2.COLOR_GRAY2BGR)
                crop = cv2.warpPerspective(bgr[:, :, :3], full, (NORM_SIZE, NORM_SIZE),
                                           flags=cv2.INTER_AREA, borderMode=cv2.BORDER_REPLICATE)
                cache.append(predict_keypoints(crop, (_C, _C), float(NORM_SIZE), mirror, net))
        return cache[0]

    return get


def keypoint_reading(image: np.ndarray, prof: GaugeProfile, min_confidence: float, t0: float,
                     dial_candidates=None) -> Reading:
    """The learned keypoints' reading (:mod:`.keypoints`) of the input image (colour)."""
    from .keypoints import read_keypoints

    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    elif image.ndim == 3 and image.shape[2] != 3:
        image = np.ascontiguousarray(image[:, :, 0])
    return read_keypoints(image, prof, min_confidence=min_confidence, t0=t0,
                          dial_candidates=dial_candidates)


def keypoint_fallback(image: np.ndarray, prof: GaugeProfile, refused: Reading,
                      min_confidence: float, t0: float, dial_candidates=None,
                      learned_first=None) -> Reading:
    """Where the classical reader refuses: the learned keypoints (:mod:`.keypoints`), whose
    own checks decide; if they refuse too, the classical refusal stands, with their reason
    added.  ``dial_candidates``: the classical dial search's rims, which the keypoints
    reuse where they would search the same grey image alike.  ``learned_first``: a crop's
    reading already asked for (:func:`learned_once`), used in place of a new one."""
    kr = learned_first() if learned_first is not None else \
        keypoint_reading(image, prof, min_confidence, t0, dial_candidates)
    if kr.value is not None:
        return kr
    refused.error = f"{refused.error}; {kr.error}"
    refused.elapsed_ms = elapsed_ms(t0)
    return refused
