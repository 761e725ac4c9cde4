"""The desk's colours, in one place (ISA-101: calm greys for the normal state,
colour only for what is abnormal). The widgets draw with these; `app.ui.theme`
builds the window's style sheet and palette from them."""

from __future__ import annotations

BACKGROUND = "#d4d4d4"
PANEL = "#e0e0e0"
PLOT_BACKGROUND = "#e6e6e6"
TEXT = "#1a1a1a"
TEXT_DIM = "#6a6a6a"
BORDER = "#a8a8a8"
CURVE = "#2e2e2e"
LIMIT_LINE = "#8a6d00"
GREY_DARK = "#3a3a3a"  # drawn geometry on the map: walls, scans, the robot's outline
GREY_MID = "#7a7a7a"
ACCENT = "#2f5f8f"  # restrained blue for "current": the pose, the target, the point being visited

ALARM_HIGH = "#c8102e"
ALARM_MEDIUM = "#f08c00"
ALARM_LOW = "#f2d600"
ABNORMAL = ALARM_MEDIUM  # link lost
STALE_TEXT = TEXT_DIM
STALE_OUTLINE = GREY_MID
ESTOP = ALARM_HIGH
