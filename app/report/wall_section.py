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
from app.core.i18n import QT_TRANSLATE_NOOP, translate


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


_PICTURE = QT_TRANSLATE_NOOP(
    "Report", "The unrolled wall (x round the tank from the shell's seam, y up): thickness "
    "from red (at or below the limit) to green (nominal); dark: obstacles; grey-green: "
    "covered, no reading.")
# the words wall_html writes through T() (pyside6-lupdate does not look inside f-strings)
_WORDS = (QT_TRANSLATE_NOOP("Report", "Wall inspection"),
          QT_TRANSLATE_NOOP("Report", "Wall {name}: {cols} × {rows} cells of {cell} mm, "
                            "nominal {nominal} mm, limit {limit} mm; inspection {state}."),
          QT_TRANSLATE_NOOP("Report", "Coverage"), QT_TRANSLATE_NOOP("Report", "Repetition"),
          QT_TRANSLATE_NOOP("Report", "Readings"), QT_TRANSLATE_NOOP("Report", "Cells measured"),
          QT_TRANSLATE_NOOP("Report", "Cells below the limit"),
          QT_TRANSLATE_NOOP("Report", "Thickness"), QT_TRANSLATE_NOOP("Report", "x round (m)"),
          QT_TRANSLATE_NOOP("Report", "y up (m)"), QT_TRANSLATE_NOOP("Report", "Cell (row, col)"),
          QT_TRANSLATE_NOOP("Report", "No thickness readings."))


def wall_html(m: WallModel, src: Callable[[str], str], *, for_pdf: bool = False) -> str:
    e = html.escape
    rec = getattr(m, "record", {}) or {}
    lim = m.limit_mm
    def T(text: str) -> str:  # noqa: N802 (the section's words, escaped for HTML)
        return e(translate("Report", text))
    out = [f"<h2>{T('Wall inspection')}</h2>",
           "<p>" + T("Wall {name}: {cols} × {rows} cells of {cell} mm, nominal {nominal} mm, "
                     "limit {limit} mm; inspection {state}.").format(
               name=f"<b>{e(str(rec.get('name', '')))}</b>", cols=m.info.cols,
               rows=m.info.rows, cell=f"{m.info.cell_m * 1000:.0f}",
               nominal=f"{m.info.nominal_mm:g}", limit=f"{lim:g}",
               state=f"<b>{T(str(rec.get('state', m.state)))}</b>") + "</p>",
           f"<table><tr><th>{T('Coverage')}</th><th>{T('Repetition')}</th>"
           f"<th>{T('Readings')}</th><th>{T('Cells measured')}</th>"
           f"<th>{T('Cells below the limit')}</th></tr>"
           f"<tr><td>{float(rec.get('coverage_pct', 0.0)):.1f} %</td>"
           f"<td>{float(rec.get('repetition_pct', 0.0)):.1f} %</td>"
           f"<td>{int(rec.get('readings', m.readings))}</td>"
           f"<td>{int(np.isfinite(m.thickness).sum())}</td><td>{m.thin_cells()}</td></tr>"
           "</table>",
           f"<p><img src='{src('wall')}' width='{640 if for_pdf else 900}'/><br/>"
           f"<span class='dim'>{T(_PICTURE)}</span></p>"]
    spots = m.thinnest(10)
    if spots:
        out.append(f"<table><tr><th>#</th><th>{T('Thickness')}</th><th>{T('x round (m)')}</th>"
                   f"<th>{T('y up (m)')}</th><th>{T('Cell (row, col)')}</th></tr>")
        for i, s in enumerate(spots, 1):
            mark = f"<font color='#b00000'><b>{s.thickness_mm:.2f} mm</b></font>" \
                if s.thickness_mm < lim else f"{s.thickness_mm:.2f} mm"
            out.append(f"<tr><td>{i}</td><td>{mark}</td><td>{s.x_m:.2f}</td>"
                       f"<td>{s.y_m:.2f}</td><td>{s.row}, {s.col}</td></tr>")
        out.append("</table>")
    else:
        out.append(f"<p class='dim'>{T('No thickness readings.')}</p>")
    return "\n".join(out)
