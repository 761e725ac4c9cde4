"""Patrol reports: data gathered from the archive (``data``), laid out as
HTML or PDF (``render``), and the ``station-patrol report`` command (``cli``)."""
