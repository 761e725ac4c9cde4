"""The docs state the deadman time the robot uses (``SimConfig.drive_valid_s``)."""

from __future__ import annotations

import re
from pathlib import Path

from sim_robot.config import SimConfig

DOCS = Path(__file__).resolve().parents[2] / "docs"
SECONDS = re.compile(r"(?<![\d.])(\d+(?:\.\d+)?) s\b")


def test_every_line_that_times_the_deadman_says_what_the_code_uses():
    valid_s = SimConfig().drive_valid_s
    timed = []
    for doc in sorted(DOCS.glob("*.md")):
        for n, line in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1):
            if "deadman" in line.lower():
                timed += [(f"{doc.name}:{n}", float(s)) for s in SECONDS.findall(line)]
    assert timed, "no doc states the deadman time"
    wrong = [(where, s) for where, s in timed if s != valid_s]
    assert not wrong, f"the deadman is {valid_s:g} s (drive_valid_s); these docs say otherwise"
