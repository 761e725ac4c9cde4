"""Interoperation with the station's systems (OPC UA)."""
