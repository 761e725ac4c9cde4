"""The desk's main window and panels: wiring models to widgets."""

from app.ui.qt_fixes import guard_singleton_refcounts

guard_singleton_refcounts()
