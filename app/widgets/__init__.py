"""Reusable widgets that know nothing of robots."""

from app.widgets.image_view import ImageView, OverlayLine, OverlayRect, OverlayText
from app.widgets.plot_strip import PlotStrip
from app.widgets.stale import is_stale, set_stale
from app.widgets.status_lamp import StatusLamp
from app.widgets.steady_label import SteadyLabel
from app.widgets.value_tile import ValueTile

__all__ = ["ImageView", "OverlayLine", "OverlayRect", "OverlayText", "PlotStrip",
           "StatusLamp", "SteadyLabel", "ValueTile", "is_stale", "set_stale"]
