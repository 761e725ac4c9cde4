"""The relay: the Raspberry Pi's role between the MCU's serial link and the desks.

:class:`Relay` (in :mod:`.core`) assembles the parts, one module each; the
names other code uses are importable from here.
"""

from .commands import LEASE_COMMANDS, MISSION_COMMANDS, REJECT_TEXT, SAFETY_COMMANDS
from .core import Relay

__all__ = ["LEASE_COMMANDS", "MISSION_COMMANDS", "REJECT_TEXT", "SAFETY_COMMANDS", "Relay"]
