"""The desk's data in other tools' formats and protocols (no Qt): the live Foxglove
WebSocket view (:mod:`app.core.interop.foxglove_live`). The MCAP export is
:mod:`app.core.records.mcap_export`."""
