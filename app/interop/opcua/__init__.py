"""The desk as an OPC UA server (asyncua): see docs/opcua.md."""
