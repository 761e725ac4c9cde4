"""How long the desk waits for its OPC UA server's process: ``start()`` (the process
spawned, the address space built, listening) and ``stop()`` (its sessions closed, the
process ended), wall seconds on the desk's thread, over ``--rounds`` servers one after
the other (the standard address space's cache made first, as a desk's first start
makes it).

    PYTHONPATH=. python bench/opcua_start_bench.py [--rounds 8]

Caches, certificate and users in a temporary folder; None security on (as the tests).
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=8)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="opcua-start-"))
    os.environ["STATION_PATROL_CACHE_DIR"] = str(tmp / "cache")
    os.environ["STATION_PATROL_DATA_DIR"] = str(tmp / "data")

    from app.config import OpcuaSettings
    from app.core.desk.pipeline import DeskPipeline
    from app.interop.opcua.server import OpcUaDeskServer
    from app.interop.opcua.users import UserStore

    users = UserStore(tmp / "users.json")
    users.add("viewer", "viewer", "viewer-pass")
    starts, stops = [], []
    for i in range(args.rounds + 1):
        pipe = DeskPipeline()
        server = OpcUaDeskServer(OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0",
                                               allow_none_security=True),
                                 users=users, pki_dir=tmp / "pki")
        server.attach(pipe)
        t0 = time.perf_counter()
        server.start()
        t1 = time.perf_counter()
        server.stop()
        t2 = time.perf_counter()
        pipe.close()
        if i == 0:  # made the address space's cache and the desk's certificate
            print(f"first start {t1 - t0:.2f} s, stop {t2 - t1:.3f} s")
            continue
        starts.append(t1 - t0)
        stops.append(t2 - t1)
    print(f"{args.rounds} rounds: start median {statistics.median(starts):.2f} s "
          f"({min(starts):.2f}-{max(starts):.2f}), stop median "
          f"{statistics.median(stops):.3f} s ({min(stops):.3f}-{max(stops):.3f})")


if __name__ == "__main__":
    main()
