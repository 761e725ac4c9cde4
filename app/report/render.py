"""Lay a :class:`~app.report.data.ReportData` out as HTML or PDF.

The figures (the route over the map, one plot per environment channel) are
drawn with QPainter onto QImages, so this runs without a window (Qt's offscreen
platform). The HTML is one self-contained file: images are embedded as base64
PNG. The PDF is the same document printed by Qt's own PDF writer
(QTextDocument onto QPdfWriter), with the images handed to the document as
resources.
"""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from PySide6.QtCore import QBuffer, QByteArray, QIODevice, QMarginsF, QPointF, QRectF, Qt, QUrl
from PySide6.QtGui import (
    QColor,
    QFont,
    QImage,
    QPageLayout,
    QPageSize,
    QPainter,
    QPainterPath,
    QPdfWriter,
    QPen,
    QTextDocument,
)

from app.report.data import ReportData

__all__ = ["plot_image", "render_html", "route_image", "write_html", "write_pdf",
           "write_report"]

LABELS = {"gas_lel_pct": "Combustible gas", "temp_c": "Temperature",
          "humidity_pct": "Humidity", "battery_v": "Battery",
          "obstacle_front_m": "Obstacle ahead"}
STATE_COLOURS = {"normal": "#2e7d32", "ok": "#2e7d32", "high": "#c8102e", "low": "#c8102e",
                 "alarm": "#c8102e", "warning": "#f08c00", "unreadable": "#6a6a6a"}


def iso(t: float | None) -> str:
    if t is None:
        return "—"
    return datetime.fromtimestamp(float(t), UTC).strftime("%Y-%m-%d %H:%M:%S")


def _num(v: float | None, fmt: str = ".2f") -> str:
    return "—" if v is None or not math.isfinite(v) else format(v, fmt)


# ---------------------------------------------------------------- figures
def png_bytes(img: QImage) -> bytes:
    ba = QByteArray()
    buf = QBuffer(ba)
    buf.open(QIODevice.OpenModeFlag.WriteOnly)
    img.save(buf, "PNG")
    buf.close()
    return bytes(ba.data())


def plot_image(t: np.ndarray, mean: np.ndarray, vmin: np.ndarray, vmax: np.ndarray, *,
               title: str, unit: str, width: int = 900, height: int = 220) -> QImage:
    """A time plot: the min–max band shaded, the mean drawn over it."""
    img = QImage(width, height, QImage.Format.Format_RGB32)
    img.fill(QColor("#ffffff"))
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    font = QFont()
    font.setPixelSize(12)
    p.setFont(font)
    left, right, top, bottom = 64, 12, 22, 26
    pw, ph = width - left - right, height - top - bottom
    p.setPen(QColor("#1a1a1a"))
    p.drawText(QRectF(left, 2, pw, 18), Qt.AlignmentFlag.AlignLeft,
               f"{title} [{unit}]" if unit else title)
    p.setPen(QPen(QColor("#a8a8a8"), 1))
    p.drawRect(QRectF(left, top, pw, ph))
    t, mean, vmin, vmax = (np.asarray(a, float) for a in (t, mean, vmin, vmax))
    ok = np.isfinite(t) & np.isfinite(mean)
    if ok.sum() == 0:
        p.setPen(QColor("#6a6a6a"))
        p.drawText(QRectF(left, top, pw, ph), Qt.AlignmentFlag.AlignCenter, "no data")
        p.end()
        return img
    t, mean = t[ok], mean[ok]
    vmin = np.where(np.isfinite(vmin[ok]), vmin[ok], mean)
    vmax = np.where(np.isfinite(vmax[ok]), vmax[ok], mean)
    t0, t1 = float(t.min()), float(t.max())
    if t1 <= t0:
        t1 = t0 + 1.0
    y0, y1 = float(vmin.min()), float(vmax.max())
    if y1 - y0 < 1e-9:
        y0, y1 = y0 - 0.5, y1 + 0.5
    pad = 0.05 * (y1 - y0)
    y0, y1 = y0 - pad, y1 + pad

    def px(tt: float) -> float:
        return left + (tt - t0) / (t1 - t0) * pw

    def py(v: float) -> float:
        return top + (y1 - v) / (y1 - y0) * ph

    # grid and axis labels
    p.setPen(QColor("#6a6a6a"))
    for k in range(5):
        v = y0 + (y1 - y0) * k / 4
        yy = py(v)
        p.setPen(QPen(QColor("#e0e0e0"), 1))
        p.drawLine(QPointF(left, yy), QPointF(left + pw, yy))
        p.setPen(QColor("#6a6a6a"))
        p.drawText(QRectF(0, yy - 8, left - 6, 16),
                   Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter, f"{v:.4g}")
    for k in range(5):
        tt = t0 + (t1 - t0) * k / 4
        xx = px(tt)
        label = datetime.fromtimestamp(tt, UTC).strftime("%H:%M:%S")
        p.drawText(QRectF(xx - 40, top + ph + 4, 80, 16), Qt.AlignmentFlag.AlignHCenter, label)
    # min-max band
    if np.any(vmax > vmin):
        band = QPainterPath()
        band.moveTo(px(t[0]), py(vmax[0]))
        for a, b in zip(t[1:], vmax[1:], strict=True):
            band.lineTo(px(a), py(b))
        for a, b in zip(t[::-1], vmin[::-1], strict=True):
            band.lineTo(px(a), py(b))
        band.closeSubpath()
        p.fillPath(band, QColor(46, 46, 46, 50))
    path = QPainterPath()
    path.moveTo(px(t[0]), py(mean[0]))
    for a, b in zip(t[1:], mean[1:], strict=True):
        path.lineTo(px(a), py(b))
    p.setPen(QPen(QColor("#2e2e2e"), 1.5))
    p.drawPath(path)
    p.end()
    return img


def route_image(data: ReportData, *, size: int = 700) -> QImage:
    """The station map with the driven path and the inspection points.

    With a map whose geometry is known the path is drawn in the map's frame;
    otherwise the path alone is drawn, scaled to fit."""
    poses = np.asarray(data.poses, float).reshape(-1, 4)
    pts = [(p["x"], p["y"], p.get("name", "")) for p in data.points]
    m = data.map
    base: QImage | None = None
    if m is not None and m.png:
        base = QImage.fromData(m.png, "PNG")
        if base.isNull():
            base = None
    if base is not None and m is not None and m.resolution_m > 0:
        res, ox, oy, h = m.resolution_m, m.origin_x_m, m.origin_y_m, base.height()
        scale = min(size / base.width(), size / base.height())
        w_px, h_px = max(1, round(base.width() * scale)), max(1, round(base.height() * scale))

        def to_px(x: float, y: float) -> QPointF:
            col = (x - ox) / res
            row = h - (y - oy) / res
            return QPointF(col * scale, row * scale)
        img = base.convertToFormat(QImage.Format.Format_RGB32).scaled(
            w_px, h_px, Qt.AspectRatioMode.IgnoreAspectRatio,
            Qt.TransformationMode.SmoothTransformation)
    else:
        xs = list(poses[:, 1]) + [p[0] for p in pts]
        ys = list(poses[:, 2]) + [p[1] for p in pts]
        img = QImage(size, size, QImage.Format.Format_RGB32)
        img.fill(QColor("#f4f4f4"))
        if not xs:
            p = QPainter(img)
            p.drawText(QRectF(0, 0, size, size), Qt.AlignmentFlag.AlignCenter,
                       "no route recorded")
            p.end()
            return img
        x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
        span = max(x1 - x0, y1 - y0, 1.0)
        margin = 30
        k = (size - 2 * margin) / span

        def to_px(x: float, y: float) -> QPointF:
            return QPointF(margin + (x - x0) * k, size - margin - (y - y0) * k)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    if len(poses) >= 2:
        path = QPainterPath()
        path.moveTo(to_px(poses[0, 1], poses[0, 2]))
        for x, y in poses[1:, 1:3]:
            path.lineTo(to_px(x, y))
        p.setPen(QPen(QColor("#1565c0"), 2.5))
        p.drawPath(path)
    if len(poses):
        p.setBrush(QColor("#2e7d32"))
        p.setPen(Qt.PenStyle.NoPen)
        p.drawEllipse(to_px(poses[0, 1], poses[0, 2]), 5, 5)
        p.setBrush(QColor("#1565c0"))
        p.drawEllipse(to_px(poses[-1, 1], poses[-1, 2]), 5, 5)
    font = QFont()
    font.setPixelSize(12)
    p.setFont(font)
    for x, y, name in pts:
        c = to_px(x, y)
        p.setPen(QPen(QColor("#000000"), 1))
        p.setBrush(QColor("#f08c00"))
        p.drawRect(QRectF(c.x() - 4, c.y() - 4, 8, 8))
        p.drawText(QPointF(c.x() + 6, c.y() - 6), str(name))
    p.end()
    return img


# ---------------------------------------------------------------- document
def _images(data: ReportData) -> dict[str, QImage]:
    imgs = {"route": route_image(data)}
    if data.wall is not None:
        from app.report.wall_section import wall_image
        imgs["wall"] = wall_image(data.wall)
    units = {s.channel: s.unit for s in data.stats}
    for ch, (t, mean, vmin, vmax) in data.plots.items():
        imgs[f"plot_{ch}"] = plot_image(t, mean, vmin, vmax, title=LABELS.get(ch, ch),
                                        unit=units.get(ch, ""))
    for i, r in enumerate(data.readings):
        for key, jpeg in ((f"snap_{i}", r.snapshot_jpeg), (f"ref_{i}", r.reference_jpeg)):
            if jpeg:
                q = QImage.fromData(jpeg, "JPEG")
                if not q.isNull():
                    if q.width() > 240:
                        q = q.scaledToWidth(240, Qt.TransformationMode.SmoothTransformation)
                    imgs[key] = q
    return imgs


def render_html(data: ReportData, src: Callable[[str], str] | None = None,
                images: dict[str, QImage] | None = None, *, for_pdf: bool = False) -> str:
    """The report as HTML. ``src(name)`` gives each image's address: by
    default a base64 ``data:`` URL, so the file stands alone."""
    imgs = _images(data) if images is None else images
    if src is None:
        def src(name: str) -> str:
            return "data:image/png;base64," + base64.b64encode(
                png_bytes(imgs[name])).decode("ascii")
    e = html.escape
    page_w = "100%"
    out: list[str] = []
    out.append("<!DOCTYPE html><html><head><meta charset='utf-8'>"
               f"<title>Patrol report {e(iso(data.t0))} – {e(iso(data.t1))}</title>"
               "<style>body{font-family:sans-serif;font-size:10pt;color:#1a1a1a}"
               "table{border-collapse:collapse;margin-bottom:12px}"
               "th,td{border:1px solid #a8a8a8;padding:3px 6px;text-align:left;"
               "vertical-align:top}th{background:#e0e0e0}"
               "h1{font-size:16pt}h2{font-size:13pt;margin-top:18px}"
               ".dim{color:#6a6a6a}</style></head><body>")
    out.append("<h1>Station patrol report</h1>")
    out.append(f"<p>From <b>{e(iso(data.t0))}</b> to <b>{e(iso(data.t1))}</b> UTC"
               f"<br/><span class='dim'>made {e(iso(data.generated_t))} UTC"
               + (f" from {e(data.source)}" if data.source else "") + "</span></p>")
    n_alarm = len(data.alarms)
    n_unacked = sum(1 for a in data.alarms if a.acked_t is None)
    out.append("<table><tr><th>Distance driven</th><th>Meter readings</th><th>Alarms</th>"
               "<th>Not acknowledged</th><th>Operator commands</th><th>Events</th></tr>"
               f"<tr><td>{data.distance_m:.1f} m</td><td>{len(data.readings)}</td>"
               f"<td>{n_alarm}</td><td>{n_unacked}</td><td>{data.n_commands}</td>"
               f"<td>{data.n_events}</td></tr></table>")
    for note in data.notes:
        out.append(f"<p class='dim'>{e(note)}</p>")
    # route
    out.append("<h2>Route</h2>")
    if "route" in imgs:
        out.append(f"<p><img src='{src('route')}' width='{480 if for_pdf else 600}'/></p>")
    if data.points:
        out.append("<p class='dim'>Inspection points: "
                   + ", ".join(e(str(p.get("name", ""))) for p in data.points) + "</p>")
    if data.wall is not None and "wall" in imgs:
        from app.report.wall_section import wall_html
        out.append(wall_html(data.wall, src, for_pdf=for_pdf))
    # meter readings
    out.append("<h2>Meter readings</h2>")
    if not data.readings:
        out.append("<p class='dim'>No meter readings in this range.</p>")
    else:
        out.append(f"<table width='{page_w}'><tr><th>Time (UTC)</th><th>Point</th>"
                   "<th>Value</th><th>Confidence</th><th>State</th><th>Snapshot</th></tr>")
        for i, r in enumerate(data.readings):
            colour = STATE_COLOURS.get(r.state.lower(), "#1a1a1a")
            value = (f"{r.value:.3f} {e(r.unit)}" if r.value is not None
                     else f"<span class='dim'>{e(r.error or 'not read')}</span>")
            width = 160 if for_pdf else 200
            if f"ref_{i}" in imgs and f"snap_{i}" in imgs:
                # out of band on a calibrated point: its reference frame beside this one
                w2 = width * 3 // 4
                snap = ("<table><tr><td class='dim'>reference</td><td class='dim'>now</td>"
                        f"</tr><tr><td><img src='{src(f'ref_{i}')}' width='{w2}'/></td>"
                        f"<td><img src='{src(f'snap_{i}')}' width='{w2}'/></td></tr></table>")
            elif f"snap_{i}" in imgs:
                snap = f"<img src='{src(f'snap_{i}')}' width='{width}'/>"
            else:
                snap = "<span class='dim'>—</span>"
            out.append(f"<tr><td>{e(iso(r.t))}</td><td>{e(r.point)}</td><td>{value}</td>"
                       f"<td>{_num(r.confidence)}</td>"
                       f"<td><font color='{colour}'><b>{e(r.state)}</b></font></td>"
                       f"<td>{snap}</td></tr>")
        out.append("</table>")
    # alarms
    out.append("<h2>Alarms and their handling</h2>")
    if not data.alarms:
        out.append("<p class='dim'>No alarms in this range.</p>")
    else:
        out.append(f"<table width='{page_w}'><tr><th>Alarm</th><th>Priority</th>"
                   "<th>Raised</th><th>Value / limit</th><th>Acknowledged</th>"
                   "<th>Cleared</th><th>Handling</th></tr>")
        for a in data.alarms:
            vl = "—"
            if a.value is not None:
                vl = f"{a.value:.3g}" + (f" / {a.limit:.3g}" if a.limit is not None else "") \
                    + (f" {e(a.unit)}" if a.unit else "")
            acked = iso(a.acked_t) + (f" by {e(a.acked_by)}" if a.acked_by else "") \
                if a.acked_t is not None else "—"
            out.append(f"<tr><td>{e(a.text)}<br/><span class='dim'>{e(a.alarm)}</span></td>"
                       f"<td>{e(a.priority)}</td><td>{e(iso(a.raised_t))}</td><td>{vl}</td>"
                       f"<td>{acked}</td><td>{e(iso(a.cleared_t))}</td>"
                       f"<td>{e(a.handling)}</td></tr>")
        out.append("</table>")
    # environment
    out.append("<h2>Environment</h2>")
    if not data.stats:
        out.append("<p class='dim'>No telemetry in this range.</p>")
    else:
        out.append("<table><tr><th>Channel</th><th>Min</th><th>Max</th><th>Mean</th>"
                   "<th>Samples</th></tr>")
        for s in data.stats:
            unit = f" {e(s.unit)}" if s.unit else ""
            out.append(f"<tr><td>{e(LABELS.get(s.channel, s.channel))}"
                       f" <span class='dim'>({e(s.channel)})</span></td>"
                       f"<td>{s.vmin:.3f}{unit}</td><td>{s.vmax:.3f}{unit}</td>"
                       f"<td>{s.mean:.3f}{unit}</td><td>{s.n}</td></tr>")
        out.append("</table>")
    for ch in data.plots:
        name = f"plot_{ch}"
        if name in imgs:
            out.append(f"<p><img src='{src(name)}' width='{640 if for_pdf else 900}'/></p>")
    out.append("</body></html>")
    return "\n".join(out)


def write_html(data: ReportData, path: str | Path) -> Path:
    path = Path(path)
    path.write_text(render_html(data), encoding="utf-8")
    return path


def write_pdf(data: ReportData, path: str | Path) -> Path:
    """Print the report with Qt's PDF writer (A4, 15 mm margins)."""
    path = Path(path)
    imgs = _images(data)
    doc = QTextDocument()
    for name, img in imgs.items():
        doc.addResource(QTextDocument.ResourceType.ImageResource, QUrl(f"img://{name}"), img)
    doc.setHtml(render_html(data, src=lambda n: f"img://{n}", images=imgs, for_pdf=True))
    writer = QPdfWriter(str(path))
    writer.setTitle(f"Patrol report {iso(data.t0)} – {iso(data.t1)}")
    writer.setCreator("Station Patrol")
    writer.setResolution(96)
    writer.setPageLayout(QPageLayout(QPageSize(QPageSize.PageSizeId.A4),
                                     QPageLayout.Orientation.Portrait,
                                     QMarginsF(15, 15, 15, 15), QPageLayout.Unit.Millimeter))
    doc.setPageSize(writer.pageLayout().paintRectPixels(writer.resolution()).size().toSizeF())
    doc.print_(writer)
    del writer  # finishes the file
    return path


def write_report(data: ReportData, path: str | Path) -> Path:
    """HTML or PDF by the file's extension (.html/.htm or .pdf)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".pdf":
        return write_pdf(data, path)
    if suffix in (".html", ".htm"):
        return write_html(data, path)
    raise ValueError(f"cannot tell the report format from {str(path)!r}: "
                     "use .pdf or .html")
