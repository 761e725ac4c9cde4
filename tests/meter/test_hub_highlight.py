"""A domed hub's highlight is a light disc inside its rim and off its centre: the pivot is
the centre of the rim that most rays also find around it, not the highlight's."""

import json
import math

import cv2
from stored_frames import HERE

from app.core.meter import load_profile
from app.core.meter.clicks import refine_pivot

# the reference frame of `process` CG-301 (cal-ref tuning seed 27): a black hub with a
# grey highlight up and to the left of its centre; its pivot clicked 3.7 px off
FRAME = "cal-ref-tuning-27-4-CG-301"
TRUE_PIVOT = (330.2952281989456, 279.2514048449147)  # the generator's, in the reference


def test_the_pivot_is_the_hubs_rim_about_its_highlight():
    cal = load_profile(json.loads((HERE / f"{FRAME}.profile.json").read_text()),
                       base_dir=HERE).calibration
    ref = cv2.imread(str(cal.image_path), cv2.IMREAD_GRAYSCALE)
    p = refine_pivot(ref, cal.center, cal.radius_px)
    assert p.ok, p.why  # (it was kept as clicked: the highlight is no hub)
    assert math.hypot(p.xy[0] - TRUE_PIVOT[0], p.xy[1] - TRUE_PIVOT[1]) < 0.5
