"""The patrol report's wall-inspection section: a wall climber's coverage, the
thickness map from its probe, and the thinnest spots with their positions on
the unrolled wall (from the last record the desk archived, see
:func:`app.core.desk.wall.archive_record`)."""

from __future__ import annotations

import html
from collections.abc import Callable

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtGui import QImage

from app.core.desk.wall import WallModel, wall_picture


def wall_image(m: WallModel, width: int = 900) -> QImage:
    """The thickness map (obstacles dark, covered but unread cells grey-green,
    readings red at and below the limit through green at nominal), row 0 at the
    bottom, scaled to ``width`` pixels without smoothing (one block per cell)."""
    rgb = np.ascontiguousarray(wall_picture(m, regions=False)[::-1])
    h, w = rgb.shape[:2]
    img = QImage(rgb.data, w, h, 3 * w, QImage.Format.Format_RGB888).copy()
    scale = max(1, width // max(w, 1))
    return img.scaled(w * scale, h * scale, Qt.AspectRatioMode.KeepAspectRatio,
                      Qt.TransformationMode.FastTransformation)


def wall_html(m: WallModel, src: Callable[[str], str], *, for_pdf: bool = False) -> str:
    e = html.escape
    rec = getattr(m, "record", {}) or {}
    lim = m.limit_mm
    out = ["<h2>Wall inspection</h2>",
           f"<p>Wall <b>{e(str(rec.get('name', '')))}</b>: {m.info.cols} × {m.info.rows} cells "
           f"of {m.info.cell_m * 1000:.0f} mm, nominal {m.info.nominal_mm:g} mm, limit "
           f"{lim:g} mm; inspection <b>{e(str(rec.get('state', m.state)))}</b>.</p>",
           "<table><tr><th>Coverage</th><th>Repetition</th><th>Readings</th>"
           "<th>Cells measured</th><th>Cells below the limit</th></tr>"
           f"<tr><td>{float(rec.get('coverage_pct', 0.0)):.1f} %</td>"
           f"<td>{float(rec.get('repetition_pct', 0.0)):.1f} %</td>"
           f"<td>{int(rec.get('readings', m.readings))}</td>"
           f"<td>{int(np.isfinite(m.thickness).sum())}</td><td>{m.thin_cells()}</td></tr>"
           "</table>",
           f"<p><img src='{src('wall')}' width='{640 if for_pdf else 900}'/><br/>"
           "<span class='dim'>The unrolled wall (x round the tank from the shell's seam, y "
           "up): thickness from red (at or below the limit) to green (nominal); dark: "
           "obstacles; grey-green: covered, no reading.</span></p>"]
    spots = m.thinnest(10)
    if spots:
        out.append("<table><tr><th>#</th><th>Thickness</th><th>x round (m)</th>"
                   "<th>y up (m)</th><th>Cell (row, col)</th></tr>")
        for i, s in enumerate(spots, 1):
            mark = f"<font color='#b00000'><b>{s.thickness_mm:.2f} mm</b></font>" \
                if s.thickness_mm < lim else f"{s.thickness_mm:.2f} mm"
            out.append(f"<tr><td>{i}</td><td>{mark}</td><td>{s.x_m:.2f}</td>"
                       f"<td>{s.y_m:.2f}</td><td>{s.row}, {s.col}</td></tr>")
        out.append("</table>")
    else:
        out.append("<p class='dim'>No thickness readings.</p>")
    return "\n".join(out)
