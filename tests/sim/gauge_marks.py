"""A check the gauge family tests share: the truth's end marks lie on printed ink."""

import numpy as np


def assert_end_marks_on_ink(img, truth, ink_bgr, label) -> int:
    """Assert that the minimum and maximum end marks of ``truth`` fall where ``img``
    shows the dial's ink (some pixel of the 5 × 5 patch round each within 70 of
    ``ink_bgr``); ``label`` names the dial in a failure. Returns the marks checked."""
    checked = 0
    for key in ("min_mark_xy", "max_mark_xy"):
        x, y = (int(round(q)) for q in truth[key])
        patch = img[y - 2:y + 3, x - 2:x + 3].reshape(-1, 3).astype(float)
        assert np.linalg.norm(patch - np.array(ink_bgr, float), axis=1).min() < 70, (
            label, key)
        checked += 1
    return checked
